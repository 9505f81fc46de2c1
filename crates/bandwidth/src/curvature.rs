//! Per-vertex principal curvatures of a triangle mesh (Rusinkiewicz 2004), for the curvature
//! k of Eq. 3–4.
//!
//! Milaenen et al. 2019 (§5) precompute object-space curvature with the robust statistical
//! estimator of Kalogerakis et al. (SGP 2007), for which no public implementation exists. This
//! module stands in for it with S. Rusinkiewicz, *Estimating Curvatures and Their Derivatives
//! on Triangle Meshes*, 3DPVT 2004, the de-facto standard (trimesh2 and others): Kalogerakis's
//! estimator matters for noisy scans, Rusinkiewicz's is accurate on render meshes.
//!
//! **Method** (Rusinkiewicz 2004, §3–4):
//! 1. vertex normals: face normals weighted by sin α / (|e₁| |e₂|) at each corner (N. Max,
//!    *Weights for Computing Vertex Normals from Facet Normals*, JGT 1999; exact on spheres);
//! 2. per face, the second fundamental form II = [[e, f], [f, g]] in an orthonormal frame of
//!    the face is the least-squares solution of II · (edge) = (difference of the vertex normals
//!    along it) over the three edges (6 equations, 3 unknowns);
//! 3. each face's II is rotated into the frame of each of its vertices (the face frame is first
//!    rotated about n_f × n_v so that the normals coincide) and accumulated with the vertex's
//!    Voronoi area in that face (the "mixed area" of Meyer et al. 2003: circumcentric Voronoi
//!    area for non-obtuse triangles, half/quarter of the triangle for obtuse ones);
//! 4. the eigenvalues of the averaged 2 × 2 tensor are κ₁ ≥ κ₂, with their directions.
//!
//! The scalar this crate uses for Eq. 4 is k = max(|κ₁|, |κ₂|) (the conservative choice, see
//! `../shared/docs/wave2.md` F1.0 item 5). Sign: with outward normals a sphere has κ = +1/R.
//!
//! **Robustness.** Faces with zero or non-finite area, or whose 3 × 3 normal equations are
//! singular, are skipped; a vertex without a usable face (isolated, or only degenerate faces)
//! gets curvature 0 and normal 0 and [`VertexCurvature::valid`] false. Boundary vertices use
//! the faces they have (no special treatment: their estimate is one-sided). Every output is
//! finite.

use crate::BandwidthError;
use glam::DVec3;

/// The curvature estimate at one vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexCurvature {
    /// Larger principal curvature κ₁ (1/length unit of the positions).
    pub k1: f64,
    /// Smaller principal curvature κ₂ ≤ κ₁.
    pub k2: f64,
    /// Unit principal direction of κ₁ (0 when invalid).
    pub dir1: DVec3,
    /// Unit principal direction of κ₂ (0 when invalid).
    pub dir2: DVec3,
    /// The unit vertex normal used (0 when invalid).
    pub normal: DVec3,
    /// False for a vertex no usable face touches (its curvatures are then 0).
    pub valid: bool,
}

impl VertexCurvature {
    /// k = max(|κ₁|, |κ₂|), the scalar of Eq. 4.
    pub fn max_abs(&self) -> f64 {
        self.k1.abs().max(self.k2.abs())
    }

    /// Mean curvature (κ₁ + κ₂)/2.
    pub fn mean(&self) -> f64 {
        0.5 * (self.k1 + self.k2)
    }

    /// Gaussian curvature κ₁ κ₂.
    pub fn gaussian(&self) -> f64 {
        self.k1 * self.k2
    }

    const INVALID: VertexCurvature = VertexCurvature {
        k1: 0.0,
        k2: 0.0,
        dir1: DVec3::ZERO,
        dir2: DVec3::ZERO,
        normal: DVec3::ZERO,
        valid: false,
    };
}

/// Principal curvatures at every vertex of the mesh (`positions`, `triangles` indexing them),
/// see the module docs. Errors on a non-finite position or an index out of range; never
/// panics, and every value returned is finite.
pub fn vertex_curvatures(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<VertexCurvature>, BandwidthError> {
    let n = positions.len();
    if let Some(i) = positions
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        return Err(BandwidthError::InvalidMesh(format!(
            "position {i} is not finite: {:?}",
            positions[i]
        )));
    }
    if let Some((t, tri)) = triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&i| i as usize >= n))
    {
        return Err(BandwidthError::InvalidMesh(format!(
            "triangle {t} {tri:?} indexes past the {n} vertices"
        )));
    }
    let p: Vec<DVec3> = positions.iter().map(|&a| DVec3::from_array(a)).collect();
    let faces: Vec<Face> = triangles.iter().filter_map(|t| Face::new(&p, *t)).collect();

    // 1. Vertex normals (Max 1999).
    let mut normals = vec![DVec3::ZERO; n];
    for f in &faces {
        for c in 0..3 {
            let e1 = f.p[(c + 1) % 3] - f.p[c];
            let e2 = f.p[(c + 2) % 3] - f.p[c];
            let w = e1.length_squared() * e2.length_squared();
            if w > 0.0 && w.is_finite() {
                normals[f.v[c]] += e1.cross(e2) / w;
            }
        }
    }
    for (i, nv) in normals.iter_mut().enumerate() {
        let len = nv.length();
        *nv = if len > 0.0 && len.is_finite() {
            *nv / len
        } else {
            // Fall back to the first usable face's normal, if any.
            faces
                .iter()
                .find(|f| f.v.contains(&i))
                .map_or(DVec3::ZERO, |f| f.normal)
        };
    }

    // Vertex frames: u ⊥ n along the first usable edge, v = n × u.
    let mut frames: Vec<Option<(DVec3, DVec3)>> = vec![None; n];
    for f in &faces {
        for c in 0..3 {
            let i = f.v[c];
            if frames[i].is_some() || normals[i] == DVec3::ZERO {
                continue;
            }
            frames[i] = Some(tangent_frame(normals[i], f.p[(c + 1) % 3] - f.p[c]));
        }
    }

    // 2–3. Per-face fits, rotated into the vertex frames, weighted by the mixed area.
    let mut acc = vec![[0.0f64; 3]; n];
    let mut weight = vec![0.0f64; n];
    for f in &faces {
        let Some((e, ff, g)) = f.second_fundamental_form(&normals) else {
            continue;
        };
        let areas = f.corner_areas();
        for (&i, &w) in f.v.iter().zip(&areas) {
            let Some((u, v)) = frames[i] else { continue };
            if !(w > 0.0) || !w.is_finite() {
                continue;
            }
            let (tu, tv) = rotate_frame(f.t, f.b, f.normal, normals[i]);
            let (u1, v1) = (u.dot(tu), u.dot(tv));
            let (u2, v2) = (v.dot(tu), v.dot(tv));
            let ku = e * u1 * u1 + 2.0 * ff * u1 * v1 + g * v1 * v1;
            let kuv = e * u1 * u2 + ff * (u1 * v2 + u2 * v1) + g * v1 * v2;
            let kv = e * u2 * u2 + 2.0 * ff * u2 * v2 + g * v2 * v2;
            if ku.is_finite() && kuv.is_finite() && kv.is_finite() {
                acc[i][0] += w * ku;
                acc[i][1] += w * kuv;
                acc[i][2] += w * kv;
                weight[i] += w;
            }
        }
    }

    // 4. Eigen-decomposition per vertex.
    Ok((0..n)
        .map(|i| {
            let (Some((u, v)), true) = (frames[i], weight[i] > 0.0) else {
                return VertexCurvature::INVALID;
            };
            let [ku, kuv, kv] = acc[i].map(|a| a / weight[i]);
            let mid = 0.5 * (ku + kv);
            let rad = (0.5 * (ku - kv)).hypot(kuv);
            let (k1, k2) = (mid + rad, mid - rad);
            // Direction of κ₁ at angle φ in (u, v): tan 2φ = 2 kuv / (ku − kv).
            let phi = 0.5 * (2.0 * kuv).atan2(ku - kv);
            let dir1 = u * phi.cos() + v * phi.sin();
            let dir2 = normals[i].cross(dir1);
            if !(k1.is_finite() && k2.is_finite()) {
                return VertexCurvature::INVALID;
            }
            VertexCurvature {
                k1,
                k2,
                dir1,
                dir2,
                normal: normals[i],
                valid: true,
            }
        })
        .collect())
}

/// k = max(|κ₁|, |κ₂|) per vertex (0 where invalid); see [`vertex_curvatures`].
pub fn vertex_max_abs_curvature(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<f64>, BandwidthError> {
    Ok(vertex_curvatures(positions, triangles)?
        .iter()
        .map(VertexCurvature::max_abs)
        .collect())
}

/// A usable (non-degenerate) triangle with its orthonormal frame (t, b, normal).
struct Face {
    v: [usize; 3],
    p: [DVec3; 3],
    normal: DVec3,
    t: DVec3,
    b: DVec3,
    area: f64,
}

impl Face {
    fn new(p: &[DVec3], tri: [u32; 3]) -> Option<Face> {
        let v = tri.map(|i| i as usize);
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            return None;
        }
        let q = v.map(|i| p[i]);
        let e = q[1] - q[0];
        let cross = e.cross(q[2] - q[0]);
        let twice_area = cross.length();
        let scale = e
            .length_squared()
            .max((q[2] - q[0]).length_squared())
            .max((q[2] - q[1]).length_squared());
        // Zero area, or so thin that its normal is noise.
        if !(twice_area > 1e-12 * scale) || !twice_area.is_finite() {
            return None;
        }
        let normal = cross / twice_area;
        let t = e.normalize_or_zero();
        if t == DVec3::ZERO {
            return None;
        }
        let b = normal.cross(t);
        Some(Face {
            v,
            p: q,
            normal,
            t,
            b,
            area: 0.5 * twice_area,
        })
    }

    /// Least-squares II = (e, f, g) in the face frame from the three edges and the vertex
    /// normals' differences along them (Rusinkiewicz 2004, Eq. 4–5). `None` when singular.
    fn second_fundamental_form(&self, normals: &[DVec3]) -> Option<(f64, f64, f64)> {
        // Normal equations AᵀA x = Aᵀ r, rows [u, v, 0] → dn·t and [0, u, v] → dn·b.
        let mut m = [[0.0f64; 3]; 3];
        let mut r = [0.0f64; 3];
        for c in 0..3 {
            let (a, b) = ((c + 1) % 3, (c + 2) % 3);
            let edge = self.p[b] - self.p[a];
            let dn = normals[self.v[b]] - normals[self.v[a]];
            let (u, v) = (edge.dot(self.t), edge.dot(self.b));
            let (dt, db) = (dn.dot(self.t), dn.dot(self.b));
            m[0][0] += u * u;
            m[0][1] += u * v;
            m[1][1] += u * u + v * v;
            m[1][2] += u * v;
            m[2][2] += v * v;
            r[0] += u * dt;
            r[1] += v * dt + u * db;
            r[2] += v * db;
        }
        m[1][0] = m[0][1];
        m[2][1] = m[1][2];
        solve3(m, r).map(|x| (x[0], x[1], x[2]))
    }

    /// The vertex's share of the face area (Meyer et al. 2003, mixed Voronoi area).
    fn corner_areas(&self) -> [f64; 3] {
        let mut dots = [0.0; 3];
        for (c, d) in dots.iter_mut().enumerate() {
            *d = (self.p[(c + 1) % 3] - self.p[c]).dot(self.p[(c + 2) % 3] - self.p[c]);
        }
        if let Some(obtuse) = dots.iter().position(|&d| d < 0.0) {
            let mut a = [0.25 * self.area; 3];
            a[obtuse] = 0.5 * self.area;
            return a;
        }
        // cot of the angle at corner c = dot / |cross| = dot / (2 area).
        let cot = dots.map(|d| d / (2.0 * self.area));
        let mut a = [0.0; 3];
        for (c, ac) in a.iter_mut().enumerate() {
            let (q, r) = ((c + 1) % 3, (c + 2) % 3);
            // Edge c–r is opposite q, edge c–q opposite r.
            let l_cr = (self.p[r] - self.p[c]).length_squared();
            let l_cq = (self.p[q] - self.p[c]).length_squared();
            *ac = 0.125 * (l_cr * cot[q] + l_cq * cot[r]);
        }
        a
    }
}

/// An orthonormal tangent frame (u, v) at normal `n`, u along `hint` projected onto the plane
/// (any perpendicular when the hint is parallel to n).
fn tangent_frame(n: DVec3, hint: DVec3) -> (DVec3, DVec3) {
    let mut u = (hint - n * hint.dot(n)).normalize_or_zero();
    if u == DVec3::ZERO {
        u = n.any_orthonormal_vector();
    }
    (u, n.cross(u))
}

/// Rotates the tangent vectors (t, b) of normal `from` by the rotation taking `from` to `to`
/// about `from × to` (Rodrigues); for opposite normals, the half turn about t.
fn rotate_frame(t: DVec3, b: DVec3, from: DVec3, to: DVec3) -> (DVec3, DVec3) {
    let c = from.dot(to);
    if c <= -1.0 + 1e-12 {
        return (t, -b);
    }
    let axis = from.cross(to);
    let rot = |x: DVec3| x * c + axis.cross(x) + axis * (axis.dot(x) / (1.0 + c));
    (rot(t), rot(b))
}

/// Solves a symmetric 3 × 3 system by Cramer's rule; `None` when (relatively) singular.
fn solve3(m: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    let det = |a: [[f64; 3]; 3]| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let d = det(m);
    let scale = m.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
    if !(d.abs() > 1e-12 * scale * scale * scale) || !d.is_finite() {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut a = m;
        for row in 0..3 {
            a[row][k] = r[row];
        }
        *xk = det(a) / d;
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}
