//! The triangles the sampler works on: the finite, non-degenerate ones of the input, with
//! their areas and the cumulative areas used to draw a triangle by area.

use glam::DVec3;

/// The finite, non-degenerate triangles with their areas.
pub(super) struct Mesh {
    /// (original index, vertices)
    pub(super) tris: Vec<(u32, [DVec3; 3])>,
    pub(super) area: Vec<f64>,
    /// Inclusive prefix sums of `area`.
    pub(super) cdf: Vec<f64>,
    pub(super) total: f64,
    pub(super) origin: DVec3,
}

impl Mesh {
    pub(super) fn new(triangles: &[[DVec3; 3]]) -> Self {
        let mut tris = Vec::new();
        let mut area = Vec::new();
        for (i, t) in triangles.iter().enumerate().take(u32::MAX as usize) {
            if !t.iter().all(|p| p.is_finite()) {
                continue;
            }
            let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
            if a > 0.0 && a.is_finite() {
                tris.push((i as u32, *t));
                area.push(a);
            }
        }
        let mut cdf = Vec::with_capacity(area.len());
        let mut acc = 0.0;
        for &a in &area {
            acc += a;
            cdf.push(acc);
        }
        let origin = tris
            .iter()
            .flat_map(|(_, t)| t.iter().copied())
            .fold(DVec3::splat(f64::INFINITY), DVec3::min);
        Mesh {
            tris,
            area,
            cdf,
            total: acc,
            origin,
        }
    }

    pub(super) fn point(&self, k: usize, u: f64, v: f64) -> DVec3 {
        let t = &self.mesh_tri(k);
        (1.0 - u - v) * t[0] + u * t[1] + v * t[2]
    }

    fn mesh_tri(&self, k: usize) -> [DVec3; 3] {
        self.tris[k].1
    }
}
