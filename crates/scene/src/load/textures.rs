//! A material's `texture`: checker, stripes or noise.

use super::context::{Ctx, list};
use crate::format::{Keys, TextureDef};
use crate::{SceneError, Texture};
use sss_bssrdf::Rgb;

impl Ctx<'_> {
    pub(super) fn texture(&self, t: &TextureDef, path: &str) -> Result<Texture, SceneError> {
        let present = t.present();
        let key = |k: &str| format!("{path}.{k}");
        let what = format!("a {} texture", t.kind);
        let colours = |s: &Self| -> Result<(Rgb, Rgb), SceneError> {
            let a = s.required(t.a, path, "a", &what)?;
            let b = s.required(t.b, path, "b", &what)?;
            Ok((s.unit_colour(a, &key("a"))?, s.unit_colour(b, &key("b"))?))
        };
        match t.kind.as_str() {
            "checker" => {
                self.check_keys(path, &present, &["scale", "a", "b"], &what)?;
                let scale = self.required(t.scale, path, "scale", &what)?;
                let scale = self.positive(scale, &key("scale"))?;
                let (a, b) = colours(self)?;
                Ok(Texture::Checker { scale, a, b })
            }
            "stripes" => {
                self.check_keys(path, &present, &["axis", "period", "a", "b"], &what)?;
                let axis = self.required(t.axis, path, "axis", &what)?;
                let axis = self.nonzero_vec(axis, &key("axis"))?.normalize();
                let period = self.required(t.period, path, "period", &what)?;
                let period = self.positive(period, &key("period"))?;
                let (a, b) = colours(self)?;
                Ok(Texture::Stripes { axis, period, a, b })
            }
            "noise" => {
                self.check_keys(path, &present, &["scale", "seed", "a", "b"], &what)?;
                let scale = self.required(t.scale, path, "scale", &what)?;
                let scale = self.positive(scale, &key("scale"))?;
                let (a, b) = colours(self)?;
                Ok(Texture::Noise {
                    scale,
                    seed: t.seed.unwrap_or(0),
                    a,
                    b,
                })
            }
            other => Err(self.err(
                &key("type"),
                format!(
                    "unknown texture type `{other}`; expected one of {}",
                    list(&["checker", "stripes", "noise"])
                ),
            )),
        }
    }
}
