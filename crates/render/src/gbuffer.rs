//! The G-buffer: per pixel sample, the first surface the camera sees (position, normals,
//! object, view direction, distance, pixel footprint). Every integrator shades these same
//! points, so their images can be subtracted.

use crate::camera::{CameraFrame, pixel_samples};
use crate::geometry::SceneGeometry;
use glam::DVec3;
use rayon::prelude::*;
use sss_scene::Scene;

/// One pixel sample that hit a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GSample {
    /// Pixel index (row-major, top-left first).
    pub pixel: u32,
    /// Index of this sample within its pixel (0..samples per pixel).
    pub index: u32,
    /// Object hit.
    pub object: u32,
    /// Triangle hit.
    pub triangle: u32,
    /// Hit position.
    pub p: DVec3,
    /// Unit shading normal (out of the object).
    pub n: DVec3,
    /// Unit geometric normal (out of the object).
    pub ng: DVec3,
    /// Unit direction from the surface to the camera.
    pub wo: DVec3,
    /// Distance from the camera.
    pub distance: f64,
    /// World-space size of one pixel at this distance (scene units): the distance along the
    /// ray times the angle one pixel subtends at the image centre, 2 tan(fov/2)/height. That is
    /// exact perpendicular to the ray at the image centre; off-centre the true perpendicular
    /// size is smaller by cos γ across and cos² γ radially (γ the angle off the optical axis;
    /// at the corners of a 30° 4:3 image this value is 1.09× and 1.19× the true size). Divide
    /// by |n·wo| for the size along the surface.
    pub footprint: f64,
}

/// Pixel samples of a whole image, grouped by pixel.
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Camera samples per pixel.
    pub samples_per_pixel: u32,
    /// The samples that hit something, pixel by pixel in order.
    pub samples: Vec<GSample>,
    /// `samples[offsets[i]..offsets[i + 1]]` are pixel i's hits (length width·height + 1).
    pub offsets: Vec<u32>,
}

impl GBuffer {
    /// Casts the camera rays of `scene` (pixel samples seeded by `seed`).
    pub fn new(scene: &Scene, geom: &SceneGeometry, seed: u64) -> Self {
        let cam = &scene.camera;
        let frame = CameraFrame::new(cam);
        let (w, h, spp) = (cam.width, cam.height, cam.pixel_samples.max(1));
        let pixel_angle = frame.pixel_angle();
        let per_pixel: Vec<Vec<GSample>> = (0..w as u64 * h as u64)
            .into_par_iter()
            .map(|i| {
                let (px, py) = ((i % w as u64) as u32, (i / w as u64) as u32);
                pixel_samples(seed, i, px, py, spp)
                    .into_iter()
                    .enumerate()
                    .filter_map(|(k, (x, y))| {
                        let dir = frame.direction(x, y);
                        let hit = geom.closest_hit(frame.origin(), dir, 0.0, f64::INFINITY)?;
                        Some(GSample {
                            pixel: i as u32,
                            index: k as u32,
                            object: hit.object,
                            triangle: hit.triangle,
                            p: hit.p,
                            n: hit.n,
                            ng: hit.ng,
                            wo: -dir,
                            distance: hit.t,
                            footprint: hit.t * pixel_angle,
                        })
                    })
                    .collect()
            })
            .collect();
        let mut offsets = Vec::with_capacity(per_pixel.len() + 1);
        let mut samples = Vec::new();
        offsets.push(0);
        for v in per_pixel {
            samples.extend(v);
            offsets.push(samples.len() as u32);
        }
        GBuffer {
            width: w,
            height: h,
            samples_per_pixel: spp,
            samples,
            offsets,
        }
    }

    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The hits of pixel `i`.
    pub fn pixel(&self, i: usize) -> &[GSample] {
        &self.samples[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}
