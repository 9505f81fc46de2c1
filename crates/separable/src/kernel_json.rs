//! A separable kernel as a JSON file: the text `sss kernel --format json` prints
//! ([`KernelFile::to_json`]) and its reader ([`KernelFile::from_json`]), so that an exported
//! kernel can be loaded back.
//!
//! The format, one object on one line (numbers in Rust's shortest round-trip exponent form,
//! `1.25e-1`, which the reader parses back to the same `f64`):
//!
//! ```text
//! {"method": "preintegrated", "model": "better-dipole", "normalized": false,
//!  "total_diffuse_reflectance": [r, g, b], "passes": 2,
//!  "taps": [{"offset_mm": x, "weights": [r, g, b]}, ...]}
//! ```
//!
//! for a rank-1 kernel, or, for a multi-term one (SVD rank ≥ 2, several Gaussians),
//! `"terms": [{"horizontal": [taps...], "vertical": [taps...]}, ...]` in place of `"taps"`.
//! The taps are [`ShaderTaps`] (see [`crate::shader`] for what the weights mean): a rank-1
//! kernel's `taps` are the 1D profile a(x) whose weights sum to R per channel (the total
//! diffuse reflectance, or 1 when `normalized`), and its 2D kernel is a(x) a(y) / Σa; a
//! multi-term kernel's terms are stored as applied, with their vertical weights divided by R
//! when `normalized`. `passes` is the number of 1D passes (2 per term) and `method` and `model`
//! name the kernel and the BSSRDF model it was fitted to.
//!
//! The reader never panics: every problem is a [`SeparableError::KernelFile`] naming the field
//! (`terms[1].vertical[4].weights`) and what is wrong with it. It refuses text over
//! [`MAX_BYTES`], more than [`MAX_TAPS`] taps in a 1D kernel or [`MAX_TERMS`] terms, an empty
//! tap list, a number that is not finite or whose magnitude exceeds [`MAX_ABS`], a negative
//! total diffuse reflectance, offsets that decrease, a `passes` that is not twice the number
//! of terms, a rank-1 kernel whose weights of a channel sum to a negative value, and keys it
//! does not know.
//!
//! ```
//! use sss_separable::kernel_json::KernelFile;
//!
//! let text = r#"{"method": "preintegrated", "model": "better-dipole", "normalized": true,
//!   "total_diffuse_reflectance": [0.5, 0.25, 0.125], "passes": 2,
//!   "taps": [{"offset_mm": -1, "weights": [0.25, 0.25, 0.25]},
//!            {"offset_mm": 0, "weights": [0.5, 0.5, 0.5]},
//!            {"offset_mm": 1, "weights": [0.25, 0.25, 0.25]}]}"#;
//! let file = KernelFile::from_json(text)?;
//! assert_eq!(file.passes(), 2);
//! let kernel = file.kernel()?; // a(x) a(y) / Σa: energy 1 per channel
//! assert!(kernel.total_weight().iter().all(|e| (e - 1.0).abs() < 1e-15));
//! assert!(KernelFile::from_json(&text.replace("0.125]", "-0.125]")).is_err());
//! # Ok::<(), sss_separable::SeparableError>(())
//! ```

use crate::Rgb;
use crate::error::SeparableError;
use crate::kernel::{Kernel1d, SeparableKernel, SeparableTerm, Tap};
use crate::shader::ShaderTaps;
use serde_json::{Map, Value};
use std::fmt::Write as _;

/// Most bytes of a kernel file the reader accepts (8 MiB: the largest kernel within
/// [`MAX_TAPS`] and [`MAX_TERMS`] is about 4 MB).
pub const MAX_BYTES: usize = 8 << 20;
/// Most taps in one 1D kernel (the largest `--taps` of `sss kernel`).
pub const MAX_TAPS: usize = 1025;
/// Most terms of a multi-term kernel (this crate's fits have at most 6).
pub const MAX_TERMS: usize = 16;
/// Largest magnitude of an offset (mm), a weight or a total diffuse reflectance. The fits give
/// offsets of a few tens of mm and weights of at most R ≤ 1; the cap keeps the kernel's sums
/// and products (its energy, a rank-1 kernel split into two passes) finite.
pub const MAX_ABS: f64 = 1e6;

/// A kernel file: the exported taps and what the file says about them.
#[derive(Clone, Debug, PartialEq)]
pub struct KernelFile {
    /// The kernel's method (`preintegrated`, `svd3`, `artist:production`, `guided:k=2`, ...).
    pub method: String,
    /// The BSSRDF model the kernel approximates (`better-dipole`, ...).
    pub model: String,
    /// Whether the weights are normalised (rank-1 taps summing to 1, multi-term vertical
    /// weights divided by R) instead of summing to the total diffuse reflectance.
    pub normalized: bool,
    /// The model's total diffuse reflectance R per channel.
    pub total_diffuse_reflectance: Rgb,
    /// The taps as a shader applies them.
    pub taps: ShaderTaps,
}

/// One number in the file's notation: Rust's shortest round-trip exponent form (`1.5e0`).
fn number(v: f64, what: &dyn Fn() -> String) -> Result<String, SeparableError> {
    if v.is_finite() {
        Ok(format!("{v:e}"))
    } else {
        Err(SeparableError::KernelFile(format!(
            "{}: {v} is not finite and has no JSON number",
            what()
        )))
    }
}

/// A 1D kernel as the JSON array `[{"offset_mm": x, "weights": [r, g, b]}, ...]`.
fn taps_json(k: &Kernel1d, name: &str) -> Result<String, SeparableError> {
    let mut items = Vec::with_capacity(k.taps.len());
    for (i, t) in k.taps.iter().enumerate() {
        let offset = number(t.offset_mm, &|| format!("{name}[{i}].offset_mm"))?;
        let mut w = [const { String::new() }; 3];
        for c in 0..3 {
            w[c] = number(t.weight[c], &|| format!("{name}[{i}].weights[{c}]"))?;
        }
        items.push(format!(
            "{{\"offset_mm\": {offset}, \"weights\": [{}, {}, {}]}}",
            w[0], w[1], w[2]
        ));
    }
    Ok(format!("[{}]", items.join(", ")))
}

/// A string as a JSON string literal (quotes and escapes as serde_json writes them).
fn string_json(s: &str) -> String {
    Value::String(s.to_string()).to_string()
}

impl KernelFile {
    /// The number of 1D passes a filter makes with these taps: 2, or 2 per term.
    pub fn passes(&self) -> usize {
        match &self.taps {
            ShaderTaps::Rank1(_) => 2,
            ShaderTaps::Terms(t) => 2 * t.len(),
        }
    }

    /// The file's text (see the module documentation), one line ending in a newline: what
    /// `sss kernel --format json` prints. Errors if a number is not finite (the file would
    /// need `NaN` or `inf`, which JSON does not have). Numbers beyond [`MAX_ABS`] are written,
    /// but [`KernelFile::from_json`] refuses them.
    pub fn to_json(&self) -> Result<String, SeparableError> {
        let r = self.total_diffuse_reflectance;
        let mut rs = [const { String::new() }; 3];
        for c in 0..3 {
            rs[c] = number(r[c], &|| format!("total_diffuse_reflectance[{c}]"))?;
        }
        let mut out = String::new();
        let _ = write!(
            out,
            "{{\"method\": {}, \"model\": {}, \"normalized\": {}, \"total_diffuse_reflectance\": [{}, {}, {}], \"passes\": {}",
            string_json(&self.method),
            string_json(&self.model),
            self.normalized,
            rs[0],
            rs[1],
            rs[2],
            self.passes()
        );
        match &self.taps {
            ShaderTaps::Rank1(t) => {
                let _ = write!(out, ", \"taps\": {}", taps_json(t, "taps")?);
            }
            ShaderTaps::Terms(terms) => {
                let mut items = Vec::with_capacity(terms.len());
                for (i, t) in terms.iter().enumerate() {
                    items.push(format!(
                        "{{\"horizontal\": {}, \"vertical\": {}}}",
                        taps_json(&t.horizontal, &format!("terms[{i}].horizontal"))?,
                        taps_json(&t.vertical, &format!("terms[{i}].vertical"))?
                    ));
                }
                let _ = write!(out, ", \"terms\": [{}]", items.join(", "));
            }
        }
        out.push_str("}\n");
        Ok(out)
    }

    /// Reads a kernel file's text (see the module documentation for the format and what is
    /// refused). Never panics: bad input is a [`SeparableError::KernelFile`] naming the field.
    pub fn from_json(text: &str) -> Result<KernelFile, SeparableError> {
        if text.len() > MAX_BYTES {
            return Err(bad(format!(
                "the text has {} bytes, more than the {MAX_BYTES} a kernel file may have",
                text.len()
            )));
        }
        let value: Value =
            serde_json::from_str(text).map_err(|e| bad(format!("not a JSON kernel file: {e}")))?;
        let Value::Object(root) = value else {
            return Err(bad(format!(
                "expected a JSON object at the top, got {}",
                kind(&value)
            )));
        };
        const KEYS: [&str; 7] = [
            "method",
            "model",
            "normalized",
            "total_diffuse_reflectance",
            "passes",
            "taps",
            "terms",
        ];
        if let Some(k) = root.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(bad(format!(
                "unknown key `{}` (the keys are {})",
                k.escape_debug(),
                KEYS.join(", ")
            )));
        }
        let method = string(&root, "method")?;
        let model = string(&root, "model")?;
        let normalized = match field(&root, "normalized")? {
            Value::Bool(b) => *b,
            v => {
                return Err(bad(format!(
                    "normalized: expected true or false, got {}",
                    kind(v)
                )));
            }
        };
        let total_diffuse_reflectance = rgb(
            field(&root, "total_diffuse_reflectance")?,
            "total_diffuse_reflectance",
        )?;
        if let Some(c) = (0..3).find(|&c| total_diffuse_reflectance[c] < 0.0) {
            return Err(bad(format!(
                "total_diffuse_reflectance[{c}] = {} is negative",
                show(total_diffuse_reflectance[c])
            )));
        }
        let passes = match field(&root, "passes")? {
            Value::Number(n) => n.as_u64().ok_or_else(|| {
                bad(format!(
                    "passes: expected a whole number of passes, got {n}"
                ))
            })?,
            v => return Err(bad(format!("passes: expected a number, got {}", kind(v)))),
        };
        let taps = match (root.get("taps"), root.get("terms")) {
            (Some(_), Some(_)) => {
                return Err(bad(
                    "has both `taps` (a rank-1 kernel) and `terms` (a multi-term kernel)".into(),
                ));
            }
            (None, None) => {
                return Err(bad(
                    "missing `taps` (a rank-1 kernel) or `terms` (a multi-term kernel)".into(),
                ));
            }
            (Some(t), None) => {
                let a = kernel1d(t, "taps")?;
                let sum = a.sum();
                if let Some(c) = (0..3).find(|&c| sum[c] < 0.0) {
                    return Err(bad(format!(
                        "taps: the weights of channel {c} sum to {}; a rank-1 kernel's must not \
                         sum to a negative value",
                        show(sum[c])
                    )));
                }
                ShaderTaps::Rank1(a)
            }
            (None, Some(Value::Array(items))) => {
                if items.is_empty() {
                    return Err(bad("terms: the list is empty".into()));
                }
                if items.len() > MAX_TERMS {
                    return Err(bad(format!(
                        "terms: {} terms, more than the {MAX_TERMS} a kernel file may have",
                        items.len()
                    )));
                }
                let mut terms = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    let name = format!("terms[{i}]");
                    let Value::Object(t) = item else {
                        return Err(bad(format!(
                            "{name}: expected an object {{\"horizontal\": [...], \"vertical\": [...]}}, got {}",
                            kind(item)
                        )));
                    };
                    if let Some(k) = t.keys().find(|k| *k != "horizontal" && *k != "vertical") {
                        return Err(bad(format!(
                            "{name}: unknown key `{}` (the keys are horizontal, vertical)",
                            k.escape_debug()
                        )));
                    }
                    let pass = |p: &str| -> Result<Kernel1d, SeparableError> {
                        let v = t
                            .get(p)
                            .ok_or_else(|| bad(format!("{name}: missing `{p}`")))?;
                        kernel1d(v, &format!("{name}.{p}"))
                    };
                    terms.push(SeparableTerm {
                        horizontal: pass("horizontal")?,
                        vertical: pass("vertical")?,
                    });
                }
                ShaderTaps::Terms(terms)
            }
            (None, Some(v)) => {
                return Err(bad(format!(
                    "terms: expected a list of terms, got {}",
                    kind(v)
                )));
            }
        };
        let file = KernelFile {
            method,
            model,
            normalized,
            total_diffuse_reflectance,
            taps,
        };
        if passes != file.passes() as u64 {
            return Err(bad(format!(
                "passes = {passes}, but the kernel has {} term(s), so {} passes",
                file.passes() / 2,
                file.passes()
            )));
        }
        Ok(file)
    }

    /// The kernel the taps describe, as the screen-space filter applies it: for a rank-1 file
    /// a(x) a(y) / Σa per channel (split evenly between the passes,
    /// [`SeparableKernel::symmetric`]; a channel whose weights sum to 0 stays 0), for a
    /// multi-term file the terms as stored. Its energy is the total diffuse reflectance, or 1
    /// when [`KernelFile::normalized`] ([`SeparableKernel::with_energy`] rescales it). The file
    /// has no support size: the kernel's is its largest offset. Errors if the kernel is not
    /// finite (a rank-1 channel summing to almost but not exactly zero).
    pub fn kernel(&self) -> Result<SeparableKernel, SeparableError> {
        let kernel = match &self.taps {
            ShaderTaps::Rank1(a) => {
                let sum = a.sum();
                let energy: Rgb = std::array::from_fn(|c| sum[c].max(0.0));
                SeparableKernel::symmetric(a, energy, 0.0)?
            }
            ShaderTaps::Terms(terms) => {
                let mut k = SeparableKernel {
                    terms: terms.clone(),
                    support_mm: 0.0,
                };
                k.support_mm = k.radius_mm();
                k
            }
        };
        if kernel.is_finite() {
            Ok(kernel)
        } else {
            Err(bad(
                "the kernel's weights overflow when split into two passes".into(),
            ))
        }
    }
}

/// A number for a message: plain (`0.25`, `-2`) when that is short, else in exponent form
/// (`1e300`, `3e-12`).
fn show(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn bad(message: String) -> SeparableError {
    SeparableError::KernelFile(message)
}

/// What kind of JSON value `v` is, for messages.
fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

fn field<'a>(map: &'a Map<String, Value>, key: &str) -> Result<&'a Value, SeparableError> {
    map.get(key).ok_or_else(|| bad(format!("missing `{key}`")))
}

fn string(map: &Map<String, Value>, key: &str) -> Result<String, SeparableError> {
    match field(map, key)? {
        Value::String(s) => Ok(s.clone()),
        v => Err(bad(format!("{key}: expected a string, got {}", kind(v)))),
    }
}

/// A finite number of magnitude at most [`MAX_ABS`].
fn finite(v: &Value, name: &dyn Fn() -> String) -> Result<f64, SeparableError> {
    let x = match v {
        Value::Number(n) => n.as_f64(),
        _ => None,
    };
    match x {
        Some(x) if x.is_finite() && x.abs() <= MAX_ABS => Ok(x),
        Some(x) => Err(bad(format!(
            "{}: {} is not a finite number of magnitude at most {MAX_ABS:e}",
            name(),
            show(x)
        ))),
        None => Err(bad(format!(
            "{}: expected a number, got {}",
            name(),
            kind(v)
        ))),
    }
}

/// Three numbers `[r, g, b]`.
fn rgb(v: &Value, name: &str) -> Result<Rgb, SeparableError> {
    let Value::Array(items) = v else {
        return Err(bad(format!(
            "{name}: expected a list of 3 numbers [r, g, b], got {}",
            kind(v)
        )));
    };
    if items.len() != 3 {
        return Err(bad(format!(
            "{name}: expected 3 numbers [r, g, b], got {}",
            items.len()
        )));
    }
    let mut out = [0.0; 3];
    for (c, item) in items.iter().enumerate() {
        out[c] = finite(item, &|| format!("{name}[{c}]"))?;
    }
    Ok(out)
}

/// A list of taps `[{"offset_mm": x, "weights": [r, g, b]}, ...]`: 1 to [`MAX_TAPS`] of them,
/// offsets not decreasing.
fn kernel1d(v: &Value, name: &str) -> Result<Kernel1d, SeparableError> {
    let Value::Array(items) = v else {
        return Err(bad(format!(
            "{name}: expected a list of taps, got {}",
            kind(v)
        )));
    };
    if items.is_empty() {
        return Err(bad(format!("{name}: the list of taps is empty")));
    }
    if items.len() > MAX_TAPS {
        return Err(bad(format!(
            "{name}: {} taps, more than the {MAX_TAPS} a 1D kernel may have",
            items.len()
        )));
    }
    let mut taps: Vec<Tap> = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        let Value::Object(t) = item else {
            return Err(bad(format!(
                "{name}[{i}]: expected a tap {{\"offset_mm\": x, \"weights\": [r, g, b]}}, got {}",
                kind(item)
            )));
        };
        if let Some(k) = t.keys().find(|k| *k != "offset_mm" && *k != "weights") {
            return Err(bad(format!(
                "{name}[{i}]: unknown key `{}` (the keys are offset_mm, weights)",
                k.escape_debug()
            )));
        }
        let offset = t
            .get("offset_mm")
            .ok_or_else(|| bad(format!("{name}[{i}]: missing `offset_mm`")))?;
        let offset_mm = finite(offset, &|| format!("{name}[{i}].offset_mm"))?;
        let weights = t
            .get("weights")
            .ok_or_else(|| bad(format!("{name}[{i}]: missing `weights`")))?;
        let weight = rgb(weights, &format!("{name}[{i}].weights"))?;
        if let Some(prev) = taps.last()
            && offset_mm < prev.offset_mm
        {
            return Err(bad(format!(
                "{name}[{i}].offset_mm = {} is below the previous tap's {}: taps must be \
                 sorted by increasing offset",
                show(offset_mm),
                show(prev.offset_mm)
            )));
        }
        taps.push(Tap { offset_mm, weight });
    }
    Ok(Kernel1d { taps })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Energy;

    fn tap(offset_mm: f64, weight: Rgb) -> Tap {
        Tap { offset_mm, weight }
    }

    fn rank1() -> KernelFile {
        KernelFile {
            method: "preintegrated".into(),
            model: "better-dipole".into(),
            normalized: false,
            total_diffuse_reflectance: [0.5, 0.25, 0.125],
            taps: ShaderTaps::Rank1(Kernel1d {
                taps: vec![
                    tap(-1.5, [0.125, 0.0625, 0.1 / 3.0]),
                    tap(0.0, [0.25, 0.125, 0.125 - 0.2 / 3.0]),
                    tap(1.5, [0.125, 0.0625, 0.1 / 3.0]),
                ],
            }),
        }
    }

    fn terms() -> KernelFile {
        let h = Kernel1d {
            taps: vec![
                tap(-2.0, [0.1, -1e-17, 3e-300]),
                tap(-4.440892098500626e-16, [0.7, 0.6, 0.5]),
                tap(2.0, [0.1, 0.2, 0.3]),
            ],
        };
        let v = Kernel1d {
            taps: vec![tap(-1.0, [0.2, 0.2, 0.2]), tap(1.0, [0.3, -0.3, 0.1])],
        };
        KernelFile {
            method: "svd3".into(),
            model: "standard-dipole".into(),
            normalized: true,
            total_diffuse_reflectance: [0.9, 0.8, 1e-3],
            taps: ShaderTaps::Terms(vec![
                SeparableTerm {
                    horizontal: h.clone(),
                    vertical: v.clone(),
                },
                SeparableTerm {
                    horizontal: v,
                    vertical: h,
                },
            ]),
        }
    }

    /// write → read gives the same taps and metadata bit for bit, for both shapes.
    #[test]
    fn write_then_read_gives_the_same_file() {
        for file in [rank1(), terms()] {
            let text = file.to_json().unwrap();
            assert!(text.ends_with("}\n") && text.lines().count() == 1, "{text}");
            let back = KernelFile::from_json(&text).unwrap();
            assert_eq!(back, file, "{text}");
            assert_eq!(back.to_json().unwrap(), text);
        }
        // Names that need escaping survive.
        let mut f = rank1();
        f.method = "artist:\"odd\"\\name\n".into();
        assert_eq!(KernelFile::from_json(&f.to_json().unwrap()).unwrap(), f);
    }

    /// The writer's exact spelling (what `sss kernel --format json` has always printed).
    #[test]
    fn the_text_is_spelled_as_before() {
        let f = KernelFile {
            taps: ShaderTaps::Rank1(Kernel1d {
                taps: vec![tap(-1.5, [0.25, 1.0, 3e20]), tap(0.0, [0.5, 2.0, 1e-9])],
            }),
            ..rank1()
        };
        assert_eq!(
            f.to_json().unwrap(),
            "{\"method\": \"preintegrated\", \"model\": \"better-dipole\", \"normalized\": false, \
             \"total_diffuse_reflectance\": [5e-1, 2.5e-1, 1.25e-1], \"passes\": 2, \"taps\": \
             [{\"offset_mm\": -1.5e0, \"weights\": [2.5e-1, 1e0, 3e20]}, {\"offset_mm\": 0e0, \
             \"weights\": [5e-1, 2e0, 1e-9]}]}\n"
        );
        let t = terms().to_json().unwrap();
        assert!(
            t.contains("\"passes\": 4, \"terms\": [{\"horizontal\": [{\"offset_mm\": -2e0, "),
            "{t}"
        );
    }

    /// A rank-1 file's kernel is a(x) a(y) / Σa: its 2D weights are the taps' products over
    /// their sum; exported again through `ShaderTaps::new` it gives the file's taps.
    #[test]
    fn rank1_kernel_is_the_outer_product_over_the_sum() {
        let f = rank1();
        let ShaderTaps::Rank1(a) = &f.taps else {
            unreachable!()
        };
        let k = f.kernel().unwrap();
        assert_eq!(k.terms.len(), 1);
        let (h, v) = (&k.terms[0].horizontal, &k.terms[0].vertical);
        let s = a.sum();
        for (i, ti) in a.taps.iter().enumerate() {
            for (j, tj) in a.taps.iter().enumerate() {
                for c in 0..3 {
                    let want = ti.weight[c] * tj.weight[c] / s[c];
                    let got = h.taps[i].weight[c] * v.taps[j].weight[c];
                    assert!((got - want).abs() <= 1e-15 * want.abs(), "{got} vs {want}");
                }
            }
        }
        assert_eq!(k.support_mm, 1.5);
        let again = ShaderTaps::new(&k, f.total_diffuse_reflectance, Energy::TotalReflectance);
        let ShaderTaps::Rank1(b) = again else {
            unreachable!()
        };
        for (x, y) in a.taps.iter().zip(&b.taps) {
            assert_eq!(x.offset_mm, y.offset_mm);
            for c in 0..3 {
                assert!((x.weight[c] - y.weight[c]).abs() <= 1e-15 * x.weight[c].abs());
            }
        }
        // A channel whose weights are all zero stays zero.
        let mut z = rank1();
        if let ShaderTaps::Rank1(a) = &mut z.taps {
            for t in &mut a.taps {
                t.weight[2] = 0.0;
            }
        }
        let e = z.kernel().unwrap().total_weight();
        assert_eq!(e[2], 0.0);
        assert!((e[0] - 0.5).abs() < 1e-15);
        // A multi-term file's kernel is its terms as stored.
        let t = terms();
        let k = t.kernel().unwrap();
        let ShaderTaps::Terms(stored) = &t.taps else {
            unreachable!()
        };
        assert_eq!(&k.terms, stored);
        assert_eq!(k.support_mm, 2.0);
    }

    /// Each bad input is refused with a one-line message naming the field and the problem.
    #[test]
    fn bad_files_are_refused_with_the_field_named() {
        let good = rank1().to_json().unwrap();
        let multi = terms().to_json().unwrap();
        let cases: Vec<(String, &str)> = vec![
            ("".into(), "not a JSON kernel file"),
            ("[1, 2]".into(), "expected a JSON object"),
            (
                good.replace("\"method\": \"preintegrated\", ", ""),
                "missing `method`",
            ),
            (good.replace("\"passes\": 2, ", ""), "missing `passes`"),
            (good.replace("\"taps\"", "\"tap\""), "unknown key `tap`"),
            (good.replace("\"passes\": 2", "\"passes\": 4"), "passes = 4"),
            (
                good.replace("\"passes\": 2", "\"passes\": -2"),
                "passes: expected a whole",
            ),
            (
                good.replace("\"passes\": 2", "\"passes\": 2.5"),
                "passes: expected a whole",
            ),
            (
                good.replace("\"normalized\": false", "\"normalized\": 0"),
                "normalized: expected",
            ),
            (
                good.replace("\"model\": \"better-dipole\"", "\"model\": 7"),
                "model: expected a string",
            ),
            (
                good.replace("[5e-1, 2.5e-1, 1.25e-1]", "[5e-1, 2.5e-1]"),
                "total_diffuse_reflectance: expected 3 numbers",
            ),
            (
                good.replace("[5e-1, 2.5e-1, 1.25e-1]", "[5e-1, -2.5e-1, 1]"),
                "total_diffuse_reflectance[1] = -0.25 is negative",
            ),
            (
                good.replace("[5e-1, 2.5e-1, 1.25e-1]", "[5e-1, 1e999, 1]"),
                "not a JSON kernel file",
            ),
            (
                good.replace("[5e-1, 2.5e-1, 1.25e-1]", "[5e-1, 1e300, 1]"),
                "total_diffuse_reflectance[1]: 1e300 is not a finite number",
            ),
            (
                good.replace("[5e-1, 2.5e-1, 1.25e-1]", "[5e-1, null, 1]"),
                "total_diffuse_reflectance[1]: expected a number, got null",
            ),
            (
                good.replace("\"offset_mm\": -1.5e0", "\"offset_mm\": 2"),
                "taps[1].offset_mm = 0 is below",
            ),
            (
                good.replace("\"offset_mm\": -1.5e0", "\"offset_mm\": \"x\""),
                "taps[0].offset_mm: expected a number",
            ),
            (
                good.replace("\"offset_mm\": -1.5e0, ", ""),
                "taps[0]: missing `offset_mm`",
            ),
            (
                good.replace("\"offset_mm\": -1.5e0", "\"offset_mm\": -1.5e0, \"w\": 1"),
                "taps[0]: unknown key `w`",
            ),
            (
                good.replacen("[1.25e-1, ", "[-1.25e1, ", 1),
                "channel 0 sum to",
            ),
            (
                good.replacen(
                    "\"weights\": [1.25e-1, 6.25e-2, ",
                    "\"weights\": [6.25e-2, ",
                    1,
                ),
                "taps[0].weights: expected 3 numbers [r, g, b], got 2",
            ),
            (
                format!("{}[]}}", &good[..good.find("[{").unwrap()]),
                "taps: the list of taps is empty",
            ),
            (
                good.replace("\"taps\": ", "\"terms\": [], \"taps\": "),
                "has both",
            ),
            (
                multi.replace(", \"terms\": [", ", \"x\": 0, \"terms\": ["),
                "unknown key `x`",
            ),
            (
                multi.replace(", \"terms\": [", ", \"terms\": [7, "),
                "terms[0]: expected an object",
            ),
            (
                multi.replace("\"vertical\"", "\"vert\""),
                "terms[0]: unknown key `vert`",
            ),
            (
                multi.replacen("\"offset_mm\": -1e0", "\"offset_mm\": 1e7", 1),
                "terms[0].vertical[0].offset_mm: 1e7 is not a finite number",
            ),
            (
                multi.replacen("\"passes\": 4", "\"passes\": 2", 1),
                "passes = 2, but the kernel has 2 term(s), so 4 passes",
            ),
            ("{\"a\": ".repeat(200), "not a JSON kernel file"),
        ];
        for (text, needle) in cases {
            let e = KernelFile::from_json(&text).expect_err(&text).to_string();
            assert!(e.contains(needle), "`{needle}` not in `{e}` for {text}");
            assert!(e.starts_with("kernel file: "), "{e}");
            assert_eq!(e.lines().count(), 1, "{e}");
        }
        // Caps on the number of taps and terms, and on the size.
        let many = |n: usize| {
            let taps: Vec<String> = (0..n)
                .map(|i| format!("{{\"offset_mm\": {i}, \"weights\": [1, 1, 1]}}"))
                .collect();
            format!(
                "{{\"method\": \"m\", \"model\": \"x\", \"normalized\": true, \
                 \"total_diffuse_reflectance\": [1, 1, 1], \"passes\": 2, \"taps\": [{}]}}",
                taps.join(",")
            )
        };
        assert!(KernelFile::from_json(&many(MAX_TAPS)).is_ok());
        let e = KernelFile::from_json(&many(MAX_TAPS + 1))
            .unwrap_err()
            .to_string();
        assert!(e.contains("1026 taps, more than the 1025"), "{e}");
        let term = "{\"horizontal\": [{\"offset_mm\": 0, \"weights\": [1, 1, 1]}], \
                    \"vertical\": [{\"offset_mm\": 0, \"weights\": [1, 1, 1]}]}";
        let terms = |n: usize| {
            format!(
                "{{\"method\": \"m\", \"model\": \"x\", \"normalized\": true, \
                 \"total_diffuse_reflectance\": [1, 1, 1], \"passes\": {}, \"terms\": [{}]}}",
                2 * n,
                vec![term; n].join(",")
            )
        };
        assert!(KernelFile::from_json(&terms(MAX_TERMS)).is_ok());
        let e = KernelFile::from_json(&terms(MAX_TERMS + 1))
            .unwrap_err()
            .to_string();
        assert!(e.contains("17 terms, more than the 16"), "{e}");
        let huge = format!("{}{}", " ".repeat(MAX_BYTES), good);
        let e = KernelFile::from_json(&huge).unwrap_err().to_string();
        assert!(e.contains("more than the 8388608"), "{e}");
    }

    /// The writer refuses what JSON cannot hold instead of writing `NaN` or `inf`.
    #[test]
    fn non_finite_values_are_not_written() {
        let mut f = terms();
        if let ShaderTaps::Terms(t) = &mut f.taps {
            t[1].vertical.taps[2].weight[1] = f64::NAN;
        }
        let e = f.to_json().unwrap_err().to_string();
        assert!(e.contains("terms[1].vertical[2].weights[1]"), "{e}");
        let mut f = rank1();
        f.total_diffuse_reflectance[2] = f64::INFINITY;
        assert!(
            f.to_json()
                .unwrap_err()
                .to_string()
                .contains("total_diffuse_reflectance[2]")
        );
    }
}
