//! The G-buffer: per pixel sample, the first surface the camera sees (position, normals,
//! object, view direction, distance, pixel footprint). Every integrator shades these same
//! points, so their images can be subtracted.

use crate::camera::{CameraFrame, pixel_samples_into};
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

/// Pixels per parallel task when casting the camera rays: large enough that task overhead
/// and the per-task buffers are negligible, small enough to balance the load on many cores
/// (a 1080p frame is about a thousand tasks).
const CHUNK_PIXELS: usize = 2048;

impl GBuffer {
    /// Casts the camera rays of `scene` (pixel samples seeded by `seed`).
    ///
    /// The pixels are cast in parallel in runs of consecutive pixels; each run gathers its
    /// hits and per-pixel counts into one buffer (no allocation per pixel), and the runs are
    /// then copied, in parallel, into the one flat `samples` array. The result does not depend
    /// on the thread count.
    pub fn new(scene: &Scene, geom: &SceneGeometry, seed: u64) -> Self {
        let cam = &scene.camera;
        let frame = CameraFrame::new(cam);
        let (w, h, spp) = (cam.width, cam.height, cam.pixel_samples.max(1));
        let pixel_angle = frame.pixel_angle();
        let pixels = w as usize * h as usize;
        let runs: Vec<(Vec<GSample>, Vec<u32>)> = (0..pixels.div_ceil(CHUNK_PIXELS))
            .into_par_iter()
            .map(|c| {
                let range = c * CHUNK_PIXELS..pixels.min((c + 1) * CHUNK_PIXELS);
                let mut hits = Vec::with_capacity(range.len() * spp as usize);
                let mut counts = Vec::with_capacity(range.len());
                let mut positions = Vec::with_capacity(spp as usize);
                for i in range {
                    let (px, py) = ((i % w as usize) as u32, (i / w as usize) as u32);
                    pixel_samples_into(seed, i as u64, px, py, spp, &mut positions);
                    let before = hits.len();
                    for (k, &(x, y)) in positions.iter().enumerate() {
                        let dir = frame.direction(x, y);
                        let Some(hit) = geom.closest_hit(frame.origin(), dir, 0.0, f64::INFINITY)
                        else {
                            continue;
                        };
                        hits.push(GSample {
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
                        });
                    }
                    counts.push((hits.len() - before) as u32);
                }
                (hits, counts)
            })
            .collect();

        // Offsets by prefix sums; `run_start[c]` is the index of run c's first sample.
        let mut offsets = Vec::with_capacity(pixels + 1);
        let mut run_start = Vec::with_capacity(runs.len() + 1);
        let mut total = 0u32;
        offsets.push(0);
        for (hits, counts) in &runs {
            run_start.push(total as usize);
            for &k in counts {
                total += k;
                offsets.push(total);
            }
            debug_assert_eq!(total as usize, run_start.last().unwrap_or(&0) + hits.len());
        }
        run_start.push(total as usize);
        // Sample j lies in the last run starting at or before j (empty runs are skipped, as
        // their start equals the next run's).
        let samples: Vec<GSample> = (0..total as usize)
            .into_par_iter()
            .with_min_len(CHUNK_PIXELS)
            .map(|j| {
                let c = run_start.partition_point(|&s| s <= j) - 1;
                runs[c].0[j - run_start[c]]
            })
            .collect();
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
