//! The `[camera]` table: a pinhole camera, checked for a usable view.

use super::context::{Ctx, fmt_num};
use crate::format::CameraDef;
use crate::{Camera, SceneError};

impl Ctx<'_> {
    pub(super) fn camera(&self, c: &CameraDef) -> Result<Camera, SceneError> {
        let position = self.finite_vec(c.position, "camera.position")?;
        let target = self.finite_vec(c.target, "camera.target")?;
        let up = self.nonzero_vec(c.up.unwrap_or([0.0, 1.0, 0.0]), "camera.up")?;
        if !(c.fov.is_finite() && c.fov > 0.0 && c.fov < 180.0) {
            return Err(self.err(
                "camera.fov",
                format!(
                    "the vertical field of view must be in (0, 180) degrees, got {}",
                    fmt_num(c.fov)
                ),
            ));
        }
        if c.resolution.contains(&0) {
            return Err(self.err(
                "camera.resolution",
                format!(
                    "width and height must be at least 1, got [{}, {}]",
                    c.resolution[0], c.resolution[1]
                ),
            ));
        }
        let pixel_samples = c.pixel_samples.unwrap_or(1);
        if pixel_samples == 0 {
            return Err(self.err("camera.pixel_samples", "must be at least 1"));
        }
        let view = target - position;
        if view.length_squared() == 0.0 {
            return Err(self.err(
                "camera.target",
                "equals camera.position, so the view direction is undefined",
            ));
        }
        if view.normalize().cross(up.normalize()).length() < 1e-6 {
            return Err(self.err(
                "camera.up",
                "is parallel to the view direction (target - position)",
            ));
        }
        Ok(Camera {
            position,
            target,
            up,
            vfov_deg: c.fov,
            width: c.resolution[0],
            height: c.resolution[1],
            pixel_samples,
        })
    }
}
