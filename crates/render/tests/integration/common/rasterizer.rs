//! A z-buffer rasteriser over a scene's meshes (pixel centres, like the renderer's one sample
//! per pixel): an independent check of what the camera sees, and flat-shaded previews.

use glam::DVec3;
use sss_render::scene::{Camera, Light, Scene};
use std::path::Path;

/// What the camera sees at each pixel centre.
pub struct Frame {
    /// Object index seen at each pixel (row-major), if any.
    pub ids: Vec<Option<usize>>,
    /// Face normal seen at each pixel.
    pub normals: Vec<DVec3>,
}

/// Projects `p` to continuous pixel coordinates (x right, y down) and its depth along the
/// view direction.
pub fn project(cam: &Camera, p: DVec3) -> (f64, f64, f64) {
    let f = (cam.target - cam.position).normalize();
    let r = f.cross(cam.up).normalize();
    let u = r.cross(f);
    let d = p - cam.position;
    let z = d.dot(f);
    let th = (cam.vfov_deg.to_radians() / 2.0).tan();
    let aspect = cam.width as f64 / cam.height as f64;
    let nx = d.dot(r) / (z * th * aspect);
    let ny = d.dot(u) / (z * th);
    (
        (nx + 1.0) / 2.0 * cam.width as f64,
        (1.0 - ny) / 2.0 * cam.height as f64,
        z,
    )
}

pub fn rasterize(s: &Scene) -> Frame {
    let cam = &s.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut inv_depth = vec![0.0f64; w * h];
    let mut ids = vec![None; w * h];
    let mut normals = vec![DVec3::ZERO; w * h];
    for (oi, o) in s.objects.iter().enumerate() {
        let proj: Vec<(f64, f64, f64)> =
            o.mesh.positions.iter().map(|&p| project(cam, p)).collect();
        for t in &o.mesh.triangles {
            let [a, b, c] = t.map(|i| proj[i as usize]);
            if a.2 <= 1e-6 || b.2 <= 1e-6 || c.2 <= 1e-6 {
                continue;
            }
            let [pa, pb, pc] = t.map(|i| o.mesh.positions[i as usize]);
            let n = (pb - pa).cross(pc - pa).normalize();
            let area = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
            if area.abs() < 1e-12 {
                continue;
            }
            let x0 = a.0.min(b.0).min(c.0).floor().max(0.0) as usize;
            let x1 = (a.0.max(b.0).max(c.0).ceil().max(0.0) as usize).min(w);
            let y0 = a.1.min(b.1).min(c.1).floor().max(0.0) as usize;
            let y1 = (a.1.max(b.1).max(c.1).ceil().max(0.0) as usize).min(h);
            for y in y0..y1 {
                for x in x0..x1 {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let e = |p: (f64, f64, f64), q: (f64, f64, f64)| {
                        ((q.0 - p.0) * (py - p.1) - (px - p.0) * (q.1 - p.1)) / area
                    };
                    let (wa, wb, wc) = (e(b, c), e(c, a), e(a, b));
                    if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                        continue;
                    }
                    let iz = wa / a.2 + wb / b.2 + wc / c.2;
                    let k = y * w + x;
                    if iz > inv_depth[k] {
                        inv_depth[k] = iz;
                        ids[k] = Some(oi);
                        normals[k] = n;
                    }
                }
            }
        }
    }
    Frame { ids, normals }
}

/// Writes a flat-shaded preview PNG of the frame (for looking at the framing by eye).
pub fn write_preview(s: &Scene, frame: &Frame, dir: &Path) {
    let (w, h) = (s.camera.width, s.camera.height);
    let towards_light = match s.lights.first() {
        Some(Light::Directional { direction, .. }) => -*direction,
        Some(Light::Point { position, .. }) => (*position - s.camera.target).normalize(),
        Some(Light::Quad {
            corner,
            edge_u,
            edge_v,
            ..
        }) => (*corner + 0.5 * (*edge_u + *edge_v) - s.camera.target).normalize(),
        _ => DVec3::Y,
    };
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for (id, n) in frame.ids.iter().zip(&frame.normals) {
        let c = match id {
            None => [0u8; 3],
            Some(i) => {
                let base = if s.translucent(*i).is_some() {
                    [230.0, 170.0, 140.0]
                } else {
                    [150.0, 150.0, 170.0]
                };
                let k = 0.25 + 0.75 * n.dot(towards_light).max(0.0);
                base.map(|v: f64| (v * k) as u8)
            }
        };
        rgb.extend_from_slice(&c);
    }
    let file = std::fs::File::create(dir.join(format!("{}.png", s.name))).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header().unwrap().write_image_data(&rgb).unwrap();
}
