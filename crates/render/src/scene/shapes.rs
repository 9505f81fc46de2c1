//! Procedural shapes, transforms and textures. Being written.

use super::Texture;
use glam::DVec3;
use sss_bssrdf::Rgb;

pub(crate) fn eval_texture(_t: &Texture, _p: DVec3) -> Rgb {
    [1.0; 3]
}
