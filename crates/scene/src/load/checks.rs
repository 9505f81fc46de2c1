//! Checks shared by every table of a scene file: keys that do not apply to a `type` or
//! `shape`, required keys, finite and non-zero vectors, colours and positive numbers.

use super::context::{Ctx, fmt_num, list};
use crate::SceneError;
use crate::format::Triple;
use glam::DVec3;
use sss_bssrdf::Rgb;

impl Ctx<'_> {
    /// Rejects keys that are present but do not belong to this `type`/`shape`.
    pub(super) fn check_keys(
        &self,
        path: &str,
        present: &[&'static str],
        allowed: &[&str],
        what: &str,
    ) -> Result<(), SceneError> {
        if let Some(k) = present.iter().find(|k| !allowed.contains(k)) {
            return Err(self.err(
                &format!("{path}.{k}"),
                format!(
                    "`{k}` does not apply to {what} (its keys: {})",
                    list(allowed)
                ),
            ));
        }
        Ok(())
    }

    pub(super) fn required<T: Copy>(
        &self,
        v: Option<T>,
        path: &str,
        key: &str,
        what: &str,
    ) -> Result<T, SceneError> {
        v.ok_or_else(|| self.err(&format!("{path}.{key}"), format!("{what} needs `{key}`")))
    }

    pub(super) fn finite_vec(&self, v: [f64; 3], key: &str) -> Result<DVec3, SceneError> {
        if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
            return Err(self.err(key, format!("must be finite, got {}", fmt_num(*bad))));
        }
        Ok(DVec3::from_array(v))
    }

    pub(super) fn nonzero_vec(&self, v: [f64; 3], key: &str) -> Result<DVec3, SceneError> {
        let d = self.finite_vec(v, key)?;
        if d.length_squared() == 0.0 || !d.length_squared().is_finite() {
            return Err(self.err(key, "must be a non-zero vector"));
        }
        Ok(d)
    }

    /// A radiometric colour: finite and ≥ 0 per channel.
    pub(super) fn emission(&self, c: Triple, key: &str) -> Result<Rgb, SceneError> {
        for (ch, v) in c.0.iter().enumerate() {
            if !v.is_finite() || *v < 0.0 {
                return Err(self.err(
                    key,
                    format!(
                        "must be finite and non-negative, got {} in channel {ch}",
                        fmt_num(*v)
                    ),
                ));
            }
        }
        Ok(c.0)
    }

    /// A reflectance-like colour in [0, 1] per channel.
    pub(super) fn unit_colour(&self, c: Triple, key: &str) -> Result<Rgb, SceneError> {
        for (ch, v) in c.0.iter().enumerate() {
            if !(0.0..=1.0).contains(v) {
                return Err(self.err(
                    key,
                    format!("must be in [0, 1], got {} in channel {ch}", fmt_num(*v)),
                ));
            }
        }
        Ok(c.0)
    }

    pub(super) fn positive(&self, v: f64, key: &str) -> Result<f64, SceneError> {
        if !(v.is_finite() && v > 0.0) {
            return Err(self.err(
                key,
                format!("must be a finite number > 0, got {}", fmt_num(v)),
            ));
        }
        Ok(v)
    }
}
