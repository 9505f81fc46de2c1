//! A kernel as shader source: constant arrays of `float4(r, g, b, offset_mm)` in the layout of
//! Jimenez's public separable-SSS shader code (2012; [`Kernel1d::to_float4`]: one 4-vector
//! per tap, the centre tap first), in GLSL, HLSL or WGSL, ready to paste above a screen-space
//! pass (`examples/separable_sss.wgsl` in this crate is such a pass). `sss kernel --format
//! glsl|hlsl|wgsl` prints the same text.
//!
//! What the weights mean ([`ShaderTaps::new`]):
//! - **Rank-1 kernels** (one term: pre-integrated, SVD rank 1, artist, guided, one Gaussian)
//!   export one array, `sssKernel`: the 1D profile a(x) of Jimenez et al. 2015, Eq. 5, whose
//!   weights sum to the total diffuse reflectance R per channel. The 2D kernel is
//!   a(x) a(y) / R, so a shader applies the same taps in both passes and divides by R once;
//!   with [`Energy::Unit`] the weights sum to 1 in both passes and the shader multiplies by R
//!   (or by its own albedo) afterwards.
//! - **Multi-term kernels** (SVD rank ≥ 2, several Gaussians) export each term i as stored,
//!   `sssKernelH{i}` (horizontal pass) and `sssKernelV{i}` (vertical pass), whose products
//!   sum to R (to 1 with [`Energy::Unit`]: the vertical weights are divided by R). The shader
//!   runs one horizontal and one vertical pass per term and adds the terms' results.
//!
//! The syntax per language, for a 3-tap kernel:
//!
//! ```text
//! GLSL: const vec4 sssKernel[3] = vec4[](
//!           vec4(0.5, 0.4, 0.3, 0.0), ...
//!       );
//! HLSL: static const float4 sssKernel[3] = {
//!           float4(0.5, 0.4, 0.3, 0.0), ...
//!       };
//! WGSL: const sssKernel: array<vec4<f32>, 3> = array<vec4<f32>, 3>(
//!           vec4<f32>(0.5, 0.4, 0.3, 0.0), ...
//!       );
//!       const sssKernelTaps: u32 = 3u;
//! ```
//!
//! WGSL has no `.length()` for fixed-size arrays, so every WGSL array comes with its tap count
//! `{name}Taps`. Numbers are the f32 values in Rust's shortest round-trip form (`0.5`, `1.0`,
//! `-2.5e-7`, `1e20`), which is a valid float literal in all three languages and parses back
//! to the same f32; a non-finite value (or one that overflows f32) is an error, never `inf` or
//! `NaN` in the text.
//!
//! [`wgsl_pass`] pastes the WGSL constants into the example compute pass, [`WGSL_PASS`] (the
//! crate `sss-gpu` runs the result through wgpu and checks it against the CPU filter).
//!
//! ```
//! use sss_bssrdf::{make_model, Medium, ModelKind};
//! use sss_separable::shader::{self, ShaderLanguage, ShaderTaps};
//! use sss_separable::{preintegrated, Energy, Kernel2d, Kernel2dSpec, TapPlacement};
//!
//! let model = make_model(ModelKind::BetterDipole, &Medium::preset("skin1")?);
//! let spec = Kernel2dSpec { cells: 63, ..Default::default() };
//! let k2 = Kernel2d::from_model(model.as_ref(), &spec)?;
//! let kernel = preintegrated::kernel(&k2, TapPlacement::Importance(7))?;
//! // Weights summing to 1 in each pass; the shader multiplies by its albedo.
//! let taps = ShaderTaps::new(&kernel, kernel.total_weight(), Energy::Unit);
//! let wgsl = shader::constants(&taps, ShaderLanguage::Wgsl)?;
//! assert!(wgsl.starts_with("const sssKernel: array<vec4<f32>, 7> = array<vec4<f32>, 7>(\n"));
//! assert!(wgsl.ends_with("const sssKernelTaps: u32 = 7u;\n"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::Rgb;
use crate::error::{SeparableError, ensure};
use crate::kernel::{Energy, Kernel1d, SeparableKernel, SeparableTerm};
use std::fmt::{self, Write as _};

/// The shading language of the constants.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShaderLanguage {
    /// GLSL: `const vec4 NAME[N] = vec4[](vec4(r, g, b, offset), ...);`.
    Glsl,
    /// HLSL: `static const float4 NAME[N] = { float4(r, g, b, offset), ... };`.
    Hlsl,
    /// WGSL: `const NAME: array<vec4<f32>, N> = array<vec4<f32>, N>(vec4<f32>(...), ...);`
    /// and `const NAMETaps: u32 = Nu;`.
    Wgsl,
}

impl ShaderLanguage {
    /// Every language.
    pub const ALL: [ShaderLanguage; 3] = [
        ShaderLanguage::Glsl,
        ShaderLanguage::Hlsl,
        ShaderLanguage::Wgsl,
    ];

    /// Lower-case name (`glsl`, `hlsl`, `wgsl`).
    pub fn name(self) -> &'static str {
        match self {
            ShaderLanguage::Glsl => "glsl",
            ShaderLanguage::Hlsl => "hlsl",
            ShaderLanguage::Wgsl => "wgsl",
        }
    }
}

impl fmt::Display for ShaderLanguage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The name of the one array of a rank-1 kernel.
pub const RANK1_NAME: &str = "sssKernel";

/// A kernel's taps as a shader applies them (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub enum ShaderTaps {
    /// One 1D kernel a(x) for both passes (array `sssKernel`); 2D kernel a(x) a(y) / R.
    Rank1(Kernel1d),
    /// One (horizontal, vertical) pair per term (arrays `sssKernelH{i}`, `sssKernelV{i}`).
    Terms(Vec<SeparableTerm>),
}

impl ShaderTaps {
    /// The taps of `kernel` for a shader whose weights sum to `energy`: `total` is R per
    /// channel (normally the model's total diffuse reflectance, or
    /// [`SeparableKernel::total_weight`] of a kernel built with
    /// [`Energy::TotalReflectance`]).
    ///
    /// A one-term kernel becomes [`ShaderTaps::Rank1`] with a = h · R / Σh per channel (the
    /// horizontal taps' shape; for a radial profile v ∝ h, so a(x) a(y) / R = h(x) v(y)), or
    /// h / Σh with [`Energy::Unit`]; a channel whose taps sum to ≤ 0 gets weight 0. Other
    /// kernels become [`ShaderTaps::Terms`] as stored, with the vertical weights divided by R
    /// for [`Energy::Unit`] (0 where R ≤ 0).
    pub fn new(kernel: &SeparableKernel, total: Rgb, energy: Energy) -> ShaderTaps {
        let unit = energy == Energy::Unit;
        if kernel.terms.len() == 1 {
            let h = &kernel.terms[0].horizontal;
            let sum = h.sum();
            let scale: Rgb = std::array::from_fn(|c| {
                let target = if unit { 1.0 } else { total[c].max(0.0) };
                if sum[c] > 0.0 { target / sum[c] } else { 0.0 }
            });
            return ShaderTaps::Rank1(h.scaled(scale));
        }
        let inv: Rgb = std::array::from_fn(|c| if total[c] > 0.0 { 1.0 / total[c] } else { 0.0 });
        ShaderTaps::Terms(
            kernel
                .terms
                .iter()
                .map(|t| SeparableTerm {
                    horizontal: t.horizontal.clone(),
                    vertical: if unit {
                        t.vertical.scaled(inv)
                    } else {
                        t.vertical.clone()
                    },
                })
                .collect(),
        )
    }

    /// The arrays in output order: (name, taps).
    pub fn arrays(&self) -> Vec<(String, &Kernel1d)> {
        match self {
            ShaderTaps::Rank1(a) => vec![(RANK1_NAME.to_string(), a)],
            ShaderTaps::Terms(terms) => terms
                .iter()
                .enumerate()
                .flat_map(|(i, t)| {
                    [
                        (format!("{RANK1_NAME}H{i}"), &t.horizontal),
                        (format!("{RANK1_NAME}V{i}"), &t.vertical),
                    ]
                })
                .collect(),
        }
    }
}

/// One f32 as a float literal valid in GLSL, HLSL and WGSL: Rust's shortest round-trip form,
/// which always has a `.` or an exponent (`1.0`, `0.25`, `-3e-8`, `1e20`). Errors if `v` is
/// not finite.
pub fn float_literal(v: f32) -> Result<String, SeparableError> {
    ensure(v.is_finite(), || {
        format!("{v} has no float literal in a shader")
    })?;
    Ok(format!("{v:?}"))
}

/// The constant array `name` holding `taps` in the `(r, g, b, offset_mm)` layout, centre tap
/// first ([`Kernel1d::to_float4`]), in `language`, ending with a newline; in WGSL followed by
/// `const {name}Taps: u32 = {n}u;`. Errors if there are no taps, if a value is not finite in
/// f32, or if `name` is not an ASCII identifier.
pub fn array(
    name: &str,
    taps: &Kernel1d,
    language: ShaderLanguage,
) -> Result<String, SeparableError> {
    ensure(
        name.chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'),
        || format!("`{name}` is not a shader identifier"),
    )?;
    let v = taps.to_float4();
    ensure(!v.is_empty(), || format!("the kernel `{name}` has no taps"))?;
    let ty = match language {
        ShaderLanguage::Glsl => "vec4",
        ShaderLanguage::Hlsl => "float4",
        ShaderLanguage::Wgsl => "vec4<f32>",
    };
    let mut items = Vec::with_capacity(v.len());
    for f in &v {
        let [r, g, b, o] = f.map(float_literal);
        items.push(format!("    {ty}({}, {}, {}, {})", r?, g?, b?, o?));
    }
    let (n, items) = (v.len(), items.join(",\n"));
    Ok(match language {
        ShaderLanguage::Glsl => format!("const vec4 {name}[{n}] = vec4[](\n{items}\n);\n"),
        ShaderLanguage::Hlsl => format!("static const float4 {name}[{n}] = {{\n{items}\n}};\n"),
        ShaderLanguage::Wgsl => format!(
            "const {name}: array<vec4<f32>, {n}> = array<vec4<f32>, {n}>(\n{items}\n);\nconst {name}Taps: u32 = {n}u;\n"
        ),
    })
}

/// Every array of `taps` ([`ShaderTaps::arrays`]) in `language`, one after the other.
pub fn constants(taps: &ShaderTaps, language: ShaderLanguage) -> Result<String, SeparableError> {
    let mut out = String::new();
    for (name, k) in taps.arrays() {
        let _ = write!(out, "{}", array(&name, k, language)?);
    }
    Ok(out)
}

/// `examples/separable_sss.wgsl`: the separable pass as two WGSL compute entry points,
/// `sss_horizontal` and `sss_vertical`, with the CPU filter's footprint, sub-pixel-skip and
/// silhouette rules and no jitter ([`crate::screen_space`] with `jitter_radius` 0), holding a
/// 3-tap placeholder kernel between the lines `// BEGIN sss kernel` and `// END sss kernel`.
/// [`wgsl_pass`] pastes a kernel in.
pub const WGSL_PASS: &str = include_str!("../examples/separable_sss.wgsl");

const WGSL_BEGIN: &str = "// BEGIN sss kernel\n";
const WGSL_END: &str = "// END sss kernel\n";

/// [`WGSL_PASS`] with the WGSL constants of `taps` ([`constants`]) pasted between its marker
/// lines and its horizontal and vertical taps (`SSS_H`, `SSS_V`) pointed at term `term`: the
/// one array `sssKernel` of a rank-1 kernel (`term` must be 0), or `sssKernelH{term}` and
/// `sssKernelV{term}`. The text is exactly what a user gets by pasting `sss kernel --format
/// wgsl` into the example by hand. A multi-term kernel needs one module per term, whose
/// vertical passes are summed (see the example's header for the bindings).
pub fn wgsl_pass(taps: &ShaderTaps, term: usize) -> Result<String, SeparableError> {
    let (h, v) = match taps {
        ShaderTaps::Rank1(_) => {
            ensure(term == 0, || {
                format!("a rank-1 kernel has one term, not term {term}")
            })?;
            (RANK1_NAME.to_string(), RANK1_NAME.to_string())
        }
        ShaderTaps::Terms(t) => {
            ensure(term < t.len(), || {
                format!("the kernel has {} terms, not term {term}", t.len())
            })?;
            (
                format!("{RANK1_NAME}H{term}"),
                format!("{RANK1_NAME}V{term}"),
            )
        }
    };
    let constants = constants(taps, ShaderLanguage::Wgsl)?;
    let markers = || SeparableError::InvalidArgument("the example pass lost its markers".into());
    let (head, rest) = WGSL_PASS.split_once(WGSL_BEGIN).ok_or_else(markers)?;
    let (_, tail) = rest.split_once(WGSL_END).ok_or_else(markers)?;
    let mut tail = tail.to_string();
    for (from, to) in [
        (
            "SSS_H_TAPS = sssKernelTaps;",
            format!("SSS_H_TAPS = {h}Taps;"),
        ),
        ("SSS_H_TAPS> = sssKernel;", format!("SSS_H_TAPS> = {h};")),
        (
            "SSS_V_TAPS = sssKernelTaps;",
            format!("SSS_V_TAPS = {v}Taps;"),
        ),
        ("SSS_V_TAPS> = sssKernel;", format!("SSS_V_TAPS> = {v};")),
    ] {
        ensure(tail.matches(from).count() == 1, || {
            format!("the example pass lost the line `{from}`")
        })?;
        tail = tail.replacen(from, &to, 1);
    }
    Ok(format!("{head}{WGSL_BEGIN}{constants}{WGSL_END}{tail}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Tap;

    fn three() -> Kernel1d {
        Kernel1d {
            taps: vec![
                Tap {
                    offset_mm: -1.5,
                    weight: [0.25, 0.125, 1e-9],
                },
                Tap {
                    offset_mm: 0.0,
                    weight: [0.5, 1.0, 3.0e20],
                },
                Tap {
                    offset_mm: 1.5,
                    weight: [0.25, 0.125, 1e-9],
                },
            ],
        }
    }

    #[test]
    fn the_three_languages_spell_the_same_taps() {
        let k = three();
        assert_eq!(
            array("k", &k, ShaderLanguage::Glsl).unwrap(),
            "const vec4 k[3] = vec4[](\n    vec4(0.5, 1.0, 3e20, 0.0),\n    vec4(0.25, 0.125, 1e-9, -1.5),\n    vec4(0.25, 0.125, 1e-9, 1.5)\n);\n"
        );
        assert_eq!(
            array("k", &k, ShaderLanguage::Hlsl).unwrap(),
            "static const float4 k[3] = {\n    float4(0.5, 1.0, 3e20, 0.0),\n    float4(0.25, 0.125, 1e-9, -1.5),\n    float4(0.25, 0.125, 1e-9, 1.5)\n};\n"
        );
        assert_eq!(
            array("k", &k, ShaderLanguage::Wgsl).unwrap(),
            "const k: array<vec4<f32>, 3> = array<vec4<f32>, 3>(\n    vec4<f32>(0.5, 1.0, 3e20, 0.0),\n    vec4<f32>(0.25, 0.125, 1e-9, -1.5),\n    vec4<f32>(0.25, 0.125, 1e-9, 1.5)\n);\nconst kTaps: u32 = 3u;\n"
        );
    }

    #[test]
    fn no_inf_nan_empty_or_bad_names() {
        let mut k = three();
        k.taps[0].weight[1] = 1e300; // finite in f64, infinite in f32
        for lang in ShaderLanguage::ALL {
            assert!(array("k", &k, lang).is_err());
            assert!(array("k", &Kernel1d::default(), lang).is_err());
            assert!(array("1k", &three(), lang).is_err());
            assert!(array("k[2]", &three(), lang).is_err());
        }
        k.taps[0].weight[1] = f64::NAN;
        assert!(array("k", &k, ShaderLanguage::Wgsl).is_err());
        assert!(float_literal(f32::INFINITY).is_err());
        for v in [
            0.0f32,
            -0.0,
            1.0,
            7.0,
            1e-45,
            f32::MIN_POSITIVE,
            3.4028235e38,
            123456.79,
        ] {
            let s = float_literal(v).unwrap();
            assert!(s.contains('.') || s.contains('e'), "{s}");
            assert_eq!(s.parse::<f32>().unwrap().to_bits(), v.to_bits(), "{s}");
        }
    }

    #[test]
    fn rank1_and_terms_name_their_arrays() {
        let k = SeparableKernel::symmetric(&three(), [0.5, 0.25, 0.125], 2.0).unwrap();
        let t = ShaderTaps::new(&k, [0.5, 0.25, 0.125], Energy::TotalReflectance);
        let ShaderTaps::Rank1(a) = &t else {
            panic!("one term is rank 1")
        };
        for (s, r) in a.sum().iter().zip([0.5, 0.25, 0.125]) {
            assert!((s - r).abs() < 1e-15);
        }
        let names: Vec<String> = t.arrays().into_iter().map(|(n, _)| n).collect();
        assert_eq!(names, ["sssKernel"]);
        let mut two = k.clone();
        two.terms.push(k.terms[0].clone());
        let t = ShaderTaps::new(&two, [1.0, 0.5, 0.25], Energy::Unit);
        let names: Vec<String> = t.arrays().into_iter().map(|(n, _)| n).collect();
        assert_eq!(
            names,
            ["sssKernelH0", "sssKernelV0", "sssKernelH1", "sssKernelV1"]
        );
        let text = constants(&t, ShaderLanguage::Wgsl).unwrap();
        assert_eq!(text.matches("const sssKernel").count(), 8);
    }

    /// `wgsl_pass` pastes the constants in place of the placeholder, points SSS_H / SSS_V at
    /// the term asked for, and the result validates with naga; a term the kernel does not
    /// have is an error.
    #[test]
    fn wgsl_pass_points_the_passes_at_one_term() {
        let validate = |src: &str| {
            let module = naga::front::wgsl::parse_str(src).unwrap();
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::default(),
            )
            .validate(&module)
            .unwrap();
        };
        let k = SeparableKernel::symmetric(&three(), [0.5, 0.25, 0.125], 2.0).unwrap();
        let rank1 = ShaderTaps::new(&k, [0.5, 0.25, 0.125], Energy::TotalReflectance);
        let src = wgsl_pass(&rank1, 0).unwrap();
        validate(&src);
        assert!(src.contains(&constants(&rank1, ShaderLanguage::Wgsl).unwrap()));
        assert!(!src.contains("A 3-tap placeholder"));
        assert!(src.contains("const SSS_V: array<vec4<f32>, SSS_V_TAPS> = sssKernel;"));
        assert!(wgsl_pass(&rank1, 1).is_err());

        let mut two = k.clone();
        two.terms.push(k.terms[0].clone());
        let terms = ShaderTaps::new(&two, [1.0, 0.5, 0.25], Energy::TotalReflectance);
        let src = wgsl_pass(&terms, 1).unwrap();
        validate(&src);
        assert!(src.contains("const SSS_H_TAPS = sssKernelH1Taps;"));
        assert!(src.contains("const SSS_H: array<vec4<f32>, SSS_H_TAPS> = sssKernelH1;"));
        assert!(src.contains("const SSS_V_TAPS = sssKernelV1Taps;"));
        assert!(src.contains("const SSS_V: array<vec4<f32>, SSS_V_TAPS> = sssKernelV1;"));
        assert!(wgsl_pass(&terms, 2).is_err());
        validate(WGSL_PASS);
    }
}
