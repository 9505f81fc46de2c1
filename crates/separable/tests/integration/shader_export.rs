//! The shader constants of [`sss_separable::shader`] (what `sss kernel --format glsl|wgsl`
//! prints) and the example pass `examples/separable_sss.wgsl`, parsed and validated by naga
//! (its GLSL and WGSL front ends, then `naga::valid::Validator` with the default flags and
//! capabilities), for every kernel method, every tap count of the `cargo xtask compare` sweep
//! (3, 7, 15, 31; 7 is the paper's and the CLI's default) and 1, importance and uniform
//! placement, and both energies (weights summing to R, and normalised). Each export is wrapped
//! in a minimal shader whose entry point reads every array, and the parsed constants are
//! checked value for value against [`Kernel1d::to_float4`].
//!
//! HLSL is not validated: naga has no HLSL front end (it only writes HLSL). The HLSL text
//! shares `shader::array`'s tap formatting with GLSL and WGSL and is pinned by the unit tests
//! of `shader.rs` and `sss kernel`'s CLI tests.

use crate::common;

use naga::valid::{Capabilities, ValidationFlags, Validator};
use naga::{Expression, Literal, Module, ShaderStage};
use sss_separable::shader::{self, ShaderLanguage, ShaderTaps};
use sss_separable::{
    Energy, Kernel1d, SeparableKernel, TapPlacement, artist, gaussians, guided, preintegrated, svd,
};

/// The tap counts of the separable sweep of `cargo xtask compare` (`Sweep` in
/// `sss-render`'s `integrators/separable.rs`), and 1.
const TAPS: [usize; 5] = [1, 3, 7, 15, 31];

/// The methods of `sss-render`'s `KernelMethod` that export a separable kernel.
const METHODS: [&str; 8] = [
    "preintegrated",
    "svd1",
    "svd3",
    "svd6",
    "artist",
    "guided",
    "gaussians1",
    "gaussians6",
];

/// The fits every tap count shares (built once; `sss-render`'s `build_kernel` does the same
/// per call).
struct Fits {
    k2: sss_separable::Kernel2d,
    svd: svd::SvdKernel,
    artist: artist::ArtistParams,
    guided: guided::GuidedResult,
    gaussians1: gaussians::GaussianFit,
    gaussians6: gaussians::GaussianFit,
    total: [f64; 3],
}

fn fits() -> Fits {
    let model = common::model("skin1");
    let k2 = sss_separable::Kernel2d::from_model(model.as_ref(), &Default::default()).unwrap();
    let svd = svd::decompose(&k2).unwrap();
    let artist = artist::fit(&preintegrated::profile(&k2)).unwrap().params;
    let guided = guided::optimize(&k2, &guided::GuidedOptions::default()).unwrap();
    let g1 = gaussians::fit_model(model.as_ref(), 1).unwrap();
    let g6 = gaussians::fit_model(model.as_ref(), 6).unwrap();
    let total = std::array::from_fn(|c| model.total_diffuse_reflectance(c));
    Fits {
        svd,
        artist,
        guided,
        gaussians1: g1.last().unwrap().clone(),
        gaussians6: g6.last().unwrap().clone(),
        total,
        k2,
    }
}

impl Fits {
    /// `method`'s kernel with `taps` taps per pass (SVD terms always uniform).
    fn kernel(&self, method: &str, taps: usize, importance: bool) -> SeparableKernel {
        let placement = if importance {
            TapPlacement::Importance(taps)
        } else {
            TapPlacement::Uniform(taps)
        };
        let total = self.k2.total;
        let k = match method {
            "preintegrated" => preintegrated::kernel(&self.k2, placement),
            "svd1" => self.svd.separable(1, TapPlacement::Uniform(taps)),
            "svd3" => self.svd.separable(3, TapPlacement::Uniform(taps)),
            "svd6" => self.svd.separable(6, TapPlacement::Uniform(taps)),
            "artist" => artist::kernel(&self.artist, total, placement),
            "guided" => self.guided.kernel(placement),
            "gaussians1" => self.gaussians1.kernel(total, placement),
            "gaussians6" => self.gaussians6.kernel(total, placement),
            _ => unreachable!("{method}"),
        }
        .unwrap_or_else(|e| panic!("{method}, {taps} taps: {e}"));
        assert!(k.is_finite());
        k
    }

    /// Every exported kernel: (label, taps).
    fn exports(&self) -> Vec<(String, ShaderTaps)> {
        let mut out = Vec::new();
        for method in METHODS {
            for taps in TAPS {
                for importance in [true, false] {
                    let k = self.kernel(method, taps, importance);
                    for energy in [Energy::TotalReflectance, Energy::Unit] {
                        let label = format!(
                            "{method}, {taps} {} taps, {energy:?}",
                            if importance { "importance" } else { "uniform" }
                        );
                        out.push((label, ShaderTaps::new(&k, self.total, energy)));
                    }
                }
            }
        }
        out
    }
}

fn validate(module: &Module) -> Result<(), String> {
    Validator::new(ValidationFlags::default(), Capabilities::default())
        .validate(module)
        .map(|_| ())
        .map_err(|e| format!("{e:?}"))
}

/// Parses and validates WGSL source.
fn wgsl(source: &str) -> Result<Module, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    validate(&module).map_err(|e| format!("{e}\n{source}"))?;
    Ok(module)
}

/// Parses and validates a GLSL fragment shader.
fn glsl(source: &str) -> Result<Module, String> {
    let module = naga::front::glsl::Frontend::default()
        .parse(&ShaderStage::Fragment.into(), source)
        .map_err(|e| format!("{}\n{source}", e.emit_to_string(source)))?;
    validate(&module).map_err(|e| format!("{e}\n{source}"))?;
    Ok(module)
}

/// A `#version 450` fragment shader around the GLSL constants whose `main` sums every array.
fn glsl_shader(constants: &str, names: &[String]) -> String {
    let loops: String = names
        .iter()
        .map(|n| format!("    for (int i = 0; i < {n}.length(); ++i) {{ s += {n}[i]; }}\n"))
        .collect();
    format!(
        "#version 450\n{constants}\nlayout(location = 0) out vec4 sssOut;\n\nvoid main() {{\n    vec4 s = vec4(0.0);\n{loops}    sssOut = s;\n}}\n"
    )
}

/// A WGSL fragment shader around the WGSL constants whose entry point sums every array. Each
/// array is also copied into a constant of type `array<vec4<f32>, {name}Taps>`, so a tap count
/// that disagrees with the array's length fails validation.
fn wgsl_shader(constants: &str, names: &[String]) -> String {
    let checks: String = names
        .iter()
        .map(|n| format!("const {n}Checked: array<vec4<f32>, {n}Taps> = {n};\n"))
        .collect();
    let loops: String = names
        .iter()
        .map(|n| format!("    for (var i = 0u; i < {n}Taps; i++) {{ s += {n}Checked[i]; }}\n"))
        .collect();
    format!(
        "{constants}\n{checks}\n@fragment\nfn main() -> @location(0) vec4<f32> {{\n    var s = vec4<f32>(0.0);\n{loops}    return s;\n}}\n"
    )
}

/// The f32 values of a constant expression (nested `Compose`s of literals), flattened.
fn values(module: &Module, expr: naga::Handle<Expression>, out: &mut Vec<f32>) {
    match &module.global_expressions[expr] {
        Expression::Literal(Literal::F32(v)) => out.push(*v),
        Expression::Compose { components, .. } => {
            for &c in components {
                values(module, c, out);
            }
        }
        Expression::Splat { size, value } => {
            for _ in 0..*size as usize {
                values(module, *value, out);
            }
        }
        Expression::ZeroValue(ty) => match module.types[*ty].inner {
            naga::TypeInner::Vector { size, .. } => out.extend(vec![0.0; size as usize]),
            ref other => panic!("zero value of {other:?}"),
        },
        other => panic!("not a constant f32 expression: {other:?}"),
    }
}

/// The module's constant `name`, flattened to f32s.
fn constant(module: &Module, name: &str) -> Vec<f32> {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no constant {name}"));
    let mut out = Vec::new();
    values(module, c.init, &mut out);
    out
}

/// The constants hold exactly the f32 taps of every array, and (WGSL) the tap counts.
fn check_values(module: &Module, exported: &ShaderTaps, label: &str, lang: ShaderLanguage) {
    for (name, k) in exported.arrays() {
        let want: Vec<u32> = k
            .to_float4()
            .iter()
            .flatten()
            .map(|v| v.to_bits())
            .collect();
        let got: Vec<u32> = constant(module, &name)
            .iter()
            .map(|v| v.to_bits())
            .collect();
        assert_eq!(got, want, "{label}, {lang}: values of {name}");
        if lang == ShaderLanguage::Wgsl {
            let count = module
                .constants
                .iter()
                .find(|(_, c)| c.name.as_deref() == Some(&format!("{name}Taps")))
                .map(|(_, c)| &module.global_expressions[c.init]);
            assert!(
                matches!(count, Some(Expression::Literal(Literal::U32(n))) if *n as usize == k.taps.len()),
                "{label}: {name}Taps is {count:?}"
            );
        }
    }
}

fn names(exported: &ShaderTaps) -> Vec<String> {
    exported.arrays().into_iter().map(|(n, _)| n).collect()
}

/// Every method × tap count × placement × energy: the GLSL and WGSL exports parse, validate
/// and hold the taps' exact f32 values; rank-1 kernels export one array, the others two per
/// term.
#[test]
fn every_export_parses_and_validates() {
    let fits = fits();
    let exports = fits.exports();
    assert_eq!(exports.len(), METHODS.len() * TAPS.len() * 2 * 2);
    for (label, exported) in &exports {
        let terms = match exported {
            ShaderTaps::Rank1(_) => 1,
            ShaderTaps::Terms(t) => t.len(),
        };
        let expected_terms = match label.split(',').next().unwrap() {
            "svd3" => 3,
            "svd6" | "gaussians6" => 6,
            _ => 1,
        };
        assert_eq!(terms, expected_terms, "{label}");
        assert_eq!(
            matches!(exported, ShaderTaps::Rank1(_)),
            terms == 1,
            "{label}"
        );
        let names = names(exported);
        let text = shader::constants(exported, ShaderLanguage::Glsl).unwrap();
        let module = glsl(&glsl_shader(&text, &names)).unwrap_or_else(|e| panic!("{label}: {e}"));
        check_values(&module, exported, label, ShaderLanguage::Glsl);
        let text = shader::constants(exported, ShaderLanguage::Wgsl).unwrap();
        let module = wgsl(&wgsl_shader(&text, &names)).unwrap_or_else(|e| panic!("{label}: {e}"));
        check_values(&module, exported, label, ShaderLanguage::Wgsl);
    }
}

/// Extreme but finite f32 values (the largest, the smallest normal and a subnormal, negative
/// zero, integers) are valid literals in both languages and parse back bit for bit.
#[test]
fn extreme_values_stay_valid_literals() {
    let taps = Kernel1d {
        taps: [
            (0.0, [7.0, 3.4028235e38, 1.1754944e-38]),
            (-1e-30, [1e-45, -0.0, 1.0]),
            (2.5e-7, [123456.79, -6.0e-12, 16777216.0]),
            (-3.0e20, [1e16, 0.1, 1e-5]),
        ]
        .iter()
        .map(|&(offset_mm, weight)| sss_separable::Tap { offset_mm, weight })
        .collect(),
    };
    let exported = ShaderTaps::Rank1(taps);
    let n = names(&exported);
    let text = shader::constants(&exported, ShaderLanguage::Glsl).unwrap();
    let module = glsl(&glsl_shader(&text, &n)).unwrap();
    check_values(&module, &exported, "extremes", ShaderLanguage::Glsl);
    let text = shader::constants(&exported, ShaderLanguage::Wgsl).unwrap();
    let module = wgsl(&wgsl_shader(&text, &n)).unwrap();
    check_values(&module, &exported, "extremes", ShaderLanguage::Wgsl);
}

/// The validation above has teeth: a wrong array length, a missing comma, a malformed or
/// non-finite literal, or a missing tap-count constant is rejected, in GLSL and in WGSL.
#[test]
fn corrupted_exports_are_rejected() {
    let fits = fits();
    let k = fits.kernel("preintegrated", 7, true);
    let exported = ShaderTaps::new(&k, fits.total, Energy::TotalReflectance);
    let n = names(&exported);
    let glsl_text = shader::constants(&exported, ShaderLanguage::Glsl).unwrap();
    let wgsl_text = shader::constants(&exported, ShaderLanguage::Wgsl).unwrap();
    // The untouched exports pass.
    glsl(&glsl_shader(&glsl_text, &n)).unwrap();
    wgsl(&wgsl_shader(&wgsl_text, &n)).unwrap();

    let once = |text: &str, from: &str, to: &str| {
        assert!(text.contains(from), "{from} in {text}");
        text.replacen(from, to, 1)
    };
    let glsl_bad = [
        (
            "length N + 1",
            glsl_text.replace("sssKernel[7]", "sssKernel[8]"),
        ),
        (
            "length N - 1",
            glsl_text.replace("sssKernel[7]", "sssKernel[6]"),
        ),
        ("missing comma", once(&glsl_text, "),\n", ")\n")),
        ("comma inside a vec4", once(&glsl_text, ", ", " ")),
        ("malformed literal", once(&glsl_text, "(0.", "(0..")),
        ("inf", once(&glsl_text, ", 0.0)", ", inf)")),
        ("NaN", once(&glsl_text, ", 0.0)", ", NaN)")),
        ("a vec3", once(&glsl_text, ", 0.0)", ")")),
    ];
    for (what, text) in glsl_bad {
        assert!(
            glsl(&glsl_shader(&text, &n)).is_err(),
            "GLSL with {what} was accepted:\n{text}"
        );
    }
    let wgsl_bad = [
        (
            "length N + 1",
            wgsl_text.replace("array<vec4<f32>, 7>", "array<vec4<f32>, 8>"),
        ),
        (
            "declared length N + 1",
            once(&wgsl_text, "array<vec4<f32>, 7> =", "array<vec4<f32>, 8> ="),
        ),
        (
            "constructed length N - 1",
            once(
                &wgsl_text,
                "= array<vec4<f32>, 7>(",
                "= array<vec4<f32>, 6>(",
            ),
        ),
        ("missing comma", once(&wgsl_text, "),\n", ")\n")),
        ("comma inside a vec4", once(&wgsl_text, ", ", " ")),
        ("malformed literal", once(&wgsl_text, "(0.", "(0..")),
        ("inf", once(&wgsl_text, ", 0.0)", ", inf)")),
        ("NaN", once(&wgsl_text, ", 0.0)", ", NaN)")),
        ("a vec3", once(&wgsl_text, ", 0.0)", ")")),
        (
            "no tap count",
            once(&wgsl_text, "const sssKernelTaps: u32 = 7u;\n", ""),
        ),
        ("tap count N + 1", once(&wgsl_text, "= 7u;", "= 8u;")),
        ("a signed tap count", once(&wgsl_text, "= 7u;", "= -7;")),
    ];
    for (what, text) in wgsl_bad {
        assert!(
            wgsl(&wgsl_shader(&text, &n)).is_err(),
            "WGSL with {what} was accepted:\n{text}"
        );
    }
}

const EXAMPLE: &str = include_str!("../../examples/separable_sss.wgsl");
const BEGIN: &str = "// BEGIN sss kernel\n";
const END: &str = "// END sss kernel\n";

/// The example with the lines between its markers replaced by `constants`, and its SSS_H /
/// SSS_V aliases pointed at `h` and `v`.
fn example_with(constants: &str, h: &str, v: &str) -> String {
    let (head, rest) = EXAMPLE.split_once(BEGIN).expect("BEGIN marker");
    let (_, tail) = rest.split_once(END).expect("END marker");
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
        assert_eq!(tail.matches(from).count(), 1, "{from}");
        tail = tail.replacen(from, &to, 1);
    }
    format!("{head}{BEGIN}{constants}{END}{tail}")
}

/// The example pass validates as shipped and with every export pasted in: rank-1 kernels as
/// they are, multi-term kernels with SSS_H / SSS_V pointed at each term. Its two compute
/// entry points are there.
#[test]
fn the_example_validates_with_every_export() {
    let module = wgsl(EXAMPLE).unwrap();
    let entries: Vec<&str> = module
        .entry_points
        .iter()
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(entries, ["sss_horizontal", "sss_vertical"]);

    let fits = fits();
    for (label, exported) in fits.exports() {
        let text = shader::constants(&exported, ShaderLanguage::Wgsl).unwrap();
        let pairs: Vec<(String, String)> = match &exported {
            ShaderTaps::Rank1(_) => vec![("sssKernel".into(), "sssKernel".into())],
            ShaderTaps::Terms(t) => (0..t.len())
                .map(|i| (format!("sssKernelH{i}"), format!("sssKernelV{i}")))
                .collect(),
        };
        for (h, v) in pairs {
            let source = example_with(&text, &h, &v);
            let module = wgsl(&source).unwrap_or_else(|e| panic!("{label}, {h}/{v}: {e}"));
            check_values(&module, &exported, &label, ShaderLanguage::Wgsl);
        }
    }
    // The example is not trivially valid: a kernel whose tap count disagrees with its array
    // type, pasted in, is rejected.
    let k = fits.kernel("artist", 7, true);
    let bad = shader::constants(
        &ShaderTaps::new(&k, fits.total, Energy::Unit),
        ShaderLanguage::Wgsl,
    )
    .unwrap()
    .replace("array<vec4<f32>, 7>(", "array<vec4<f32>, 8>(");
    assert!(wgsl(&example_with(&bad, "sssKernel", "sssKernel")).is_err());
}
