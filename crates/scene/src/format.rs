//! The TOML scene format as serde structures, and the span index that turns byte offsets of
//! the parsed document into line numbers and key paths for error messages.
//!
//! Every table is a flat struct with `deny_unknown_fields`, so serde rejects misspelt keys and
//! reports type errors at the offending value (toml's error span). Sections whose keys depend
//! on a `type` or `shape` (lights, materials, textures, objects) keep every key optional here;
//! `load` checks which keys each type requires and accepts, using [`Keys::present`]. The
//! format itself is documented, key by key, in `scenes/README.md`.

use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use toml::de::{DeTable, DeValue};

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub camera: CameraDef,
    #[serde(default)]
    pub lights: Vec<LightDef>,
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDef>,
    #[serde(default)]
    pub objects: Vec<ObjectDef>,
}

/// `[camera]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraDef {
    pub position: [f64; 3],
    pub target: [f64; 3],
    pub up: Option<[f64; 3]>,
    pub fov: f64,
    pub resolution: [u32; 2],
    pub pixel_samples: Option<u32>,
}

/// One `[[lights]]` entry (keys depend on `type`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightDef {
    #[serde(rename = "type")]
    pub kind: String,
    pub position: Option<[f64; 3]>,
    pub intensity: Option<Triple>,
    pub direction: Option<[f64; 3]>,
    pub irradiance: Option<Triple>,
    pub corner: Option<[f64; 3]>,
    pub edge_u: Option<[f64; 3]>,
    pub edge_v: Option<[f64; 3]>,
    pub radiance: Option<Triple>,
    pub angular_diameter: Option<f64>,
}

/// One `[materials.NAME]` table (keys depend on `type`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialDef {
    #[serde(rename = "type")]
    pub kind: String,
    pub model: Option<String>,
    pub preset: Option<String>,
    pub sigma_a: Option<Triple>,
    pub sigma_s: Option<Triple>,
    pub g: Option<f64>,
    pub eta: Option<f64>,
    pub units_per_mm: Option<f64>,
    pub albedo: Option<Triple>,
    pub texture: Option<TextureDef>,
    pub angular: Option<String>,
    pub sphere_radius: Option<RadiusDef>,
    pub drift: Option<bool>,
    pub unscattered: Option<bool>,
}

/// `sphere_radius = 12.5` (scene units), `sphere_radius = "auto"` or `sphere_radius = "local"`.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub(super) enum RadiusDef {
    /// A length in scene units.
    Value(f64),
    /// A keyword (`auto` or `local`).
    Keyword(String),
}

/// A `texture = { type = .., .. }` table (keys depend on `type`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TextureDef {
    #[serde(rename = "type")]
    pub kind: String,
    pub scale: Option<f64>,
    pub axis: Option<[f64; 3]>,
    pub period: Option<f64>,
    pub seed: Option<u64>,
    pub a: Option<Triple>,
    pub b: Option<Triple>,
}

/// One `[[objects]]` entry (keys depend on `shape`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ObjectDef {
    pub name: Option<String>,
    pub material: String,
    pub shape: String,
    pub transform: Option<TransformDef>,
    pub file: Option<String>,
    pub radius: Option<f64>,
    pub subdivisions: Option<u32>,
    pub size: Option<Vec<f64>>,
    pub major: Option<f64>,
    pub minor: Option<f64>,
    pub segments: Option<Segments>,
    pub amplitude: Option<f64>,
    pub frequency: Option<f64>,
    pub seed: Option<u64>,
}

/// `transform = { scale, rotate, translate }`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TransformDef {
    pub scale: Option<Triple>,
    pub rotate: Option<[f64; 3]>,
    pub translate: Option<[f64; 3]>,
}

/// Which optional keys a section sets, so `load` can check them against its type.
pub(super) trait Keys {
    /// The names of the optional keys that are present.
    fn present(&self) -> Vec<&'static str>;
}

fn collect(pairs: &[(&'static str, bool)]) -> Vec<&'static str> {
    pairs.iter().filter(|(_, p)| *p).map(|(k, _)| *k).collect()
}

impl Keys for LightDef {
    fn present(&self) -> Vec<&'static str> {
        collect(&[
            ("position", self.position.is_some()),
            ("intensity", self.intensity.is_some()),
            ("direction", self.direction.is_some()),
            ("irradiance", self.irradiance.is_some()),
            ("corner", self.corner.is_some()),
            ("edge_u", self.edge_u.is_some()),
            ("edge_v", self.edge_v.is_some()),
            ("radiance", self.radiance.is_some()),
            ("angular_diameter", self.angular_diameter.is_some()),
        ])
    }
}

impl Keys for MaterialDef {
    fn present(&self) -> Vec<&'static str> {
        collect(&[
            ("model", self.model.is_some()),
            ("preset", self.preset.is_some()),
            ("sigma_a", self.sigma_a.is_some()),
            ("sigma_s", self.sigma_s.is_some()),
            ("g", self.g.is_some()),
            ("eta", self.eta.is_some()),
            ("units_per_mm", self.units_per_mm.is_some()),
            ("albedo", self.albedo.is_some()),
            ("texture", self.texture.is_some()),
            ("angular", self.angular.is_some()),
            ("sphere_radius", self.sphere_radius.is_some()),
            ("drift", self.drift.is_some()),
            ("unscattered", self.unscattered.is_some()),
        ])
    }
}

impl Keys for TextureDef {
    fn present(&self) -> Vec<&'static str> {
        collect(&[
            ("scale", self.scale.is_some()),
            ("axis", self.axis.is_some()),
            ("period", self.period.is_some()),
            ("seed", self.seed.is_some()),
            ("a", self.a.is_some()),
            ("b", self.b.is_some()),
        ])
    }
}

impl Keys for ObjectDef {
    fn present(&self) -> Vec<&'static str> {
        collect(&[
            ("file", self.file.is_some()),
            ("radius", self.radius.is_some()),
            ("subdivisions", self.subdivisions.is_some()),
            ("size", self.size.is_some()),
            ("major", self.major.is_some()),
            ("minor", self.minor.is_some()),
            ("segments", self.segments.is_some()),
            ("amplitude", self.amplitude.is_some()),
            ("frequency", self.frequency.is_some()),
            ("seed", self.seed.is_some()),
        ])
    }
}

/// A number or an array of three numbers (`1.5` means `[1.5, 1.5, 1.5]`): colours and scales.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Triple(pub [f64; 3]);

impl<'de> Deserialize<'de> for Triple {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Triple;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of 3 numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Triple, E> {
                Ok(Triple([v; 3]))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Triple, E> {
                Ok(Triple([v as f64; 3]))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Triple, E> {
                Ok(Triple([v as f64; 3]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Triple, A::Error> {
                let mut out = [0.0; 3];
                for (i, slot) in out.iter_mut().enumerate() {
                    *slot = seq
                        .next_element::<f64>()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Triple(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// Torus tessellation: one integer for both directions, or `[around_axis, around_tube]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Segments(pub [i64; 2]);

impl<'de> Deserialize<'de> for Segments {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Segments;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an integer or an array of 2 integers")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Segments, E> {
                Ok(Segments([v; 2]))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Segments, E> {
                let v = i64::try_from(v).unwrap_or(i64::MAX);
                Ok(Segments([v; 2]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Segments, A::Error> {
                let mut out = [0; 2];
                for (i, slot) in out.iter_mut().enumerate() {
                    *slot = seq
                        .next_element::<i64>()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(3, &self));
                }
                Ok(Segments(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// Byte spans of every key and value of a parsed document, by key path (`camera.fov`,
/// `objects[2].transform.scale`, `materials.skin.sigma_a`), with the line starts of the text.
pub(super) struct SpanIndex {
    /// (path, span of the key or array element, span of the value).
    entries: Vec<(String, Range<usize>, Range<usize>)>,
    /// Byte offset at which each line starts.
    line_starts: Vec<usize>,
}

impl SpanIndex {
    /// Indexes `doc`, parsed from `text`.
    pub fn new(text: &str, doc: &DeTable<'_>) -> Self {
        let mut entries = Vec::new();
        index_table(doc, "", &mut entries);
        SpanIndex {
            entries,
            line_starts: line_starts(text),
        }
    }

    /// An index of no document (for errors found before parsing succeeded).
    pub fn empty(text: &str) -> Self {
        SpanIndex {
            entries: Vec::new(),
            line_starts: line_starts(text),
        }
    }

    /// The 1-based line holding byte `offset`.
    pub fn line_of_offset(&self, offset: usize) -> usize {
        self.line_starts.partition_point(|&s| s <= offset).max(1)
    }

    /// The line of the key `path`, or of its nearest enclosing key or table that exists (so
    /// a missing key points at its table's header).
    pub fn line(&self, path: &str) -> Option<usize> {
        let mut p = path;
        loop {
            if let Some((_, key, _)) = self.entries.iter().find(|(q, _, _)| q == p) {
                return Some(self.line_of_offset(key.start));
            }
            p = parent_path(p)?;
        }
    }

    /// The key path an error span points at: the key whose name is exactly `span`, else the
    /// innermost key whose value contains it, if any.
    pub fn path_at(&self, span: &Range<usize>) -> Option<&str> {
        if let Some((p, _, _)) = self.entries.iter().find(|(_, k, _)| k == span) {
            return Some(p);
        }
        // Ties (an array of tables and its first element share the header's span) go to the
        // later, deeper entry.
        self.entries
            .iter()
            .rev()
            .filter(|(_, _, v)| v.start <= span.start && span.end <= v.end.max(v.start + 1))
            .min_by_key(|(_, _, v)| v.end - v.start)
            .map(|(p, _, _)| p.as_str())
    }
}

/// `a.b[2].c` -> `a.b[2]` -> `a.b` -> `a` -> None.
fn parent_path(p: &str) -> Option<&str> {
    let cut = p.rfind(['.', '['])?;
    Some(&p[..cut])
}

fn line_starts(text: &str) -> Vec<usize> {
    std::iter::once(0)
        .chain(text.match_indices('\n').map(|(i, _)| i + 1))
        .collect()
}

fn index_table(
    table: &DeTable<'_>,
    prefix: &str,
    out: &mut Vec<(String, Range<usize>, Range<usize>)>,
) {
    for (key, value) in table.iter() {
        let path = if prefix.is_empty() {
            key.get_ref().to_string()
        } else {
            format!("{prefix}.{}", key.get_ref())
        };
        out.push((path.clone(), key.span(), value.span()));
        index_value(value.get_ref(), &path, out);
    }
}

fn index_value(
    value: &DeValue<'_>,
    path: &str,
    out: &mut Vec<(String, Range<usize>, Range<usize>)>,
) {
    match value {
        DeValue::Table(t) => index_table(t, path, out),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let p = format!("{path}[{i}]");
                out.push((p.clone(), item.span(), item.span()));
                index_value(item.get_ref(), &p, out);
            }
        }
        _ => {}
    }
}
