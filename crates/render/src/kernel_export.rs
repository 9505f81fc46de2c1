//! A separable subsurface-scattering kernel (Jimenez et al. 2015) for a
//! material exported as JSON, CSV, or GLSL/HLSL/WGSL constants in the `float4(r, g, b, offset)` layout
//! of the public 2012 separable-SSS shader code.
//!
//! Weights: for a rank-1 kernel (every method but `svd3`, `svd6` and `gaussians6`) the exported
//! taps are the 1D profile a(x) of Eq. 5 whose weights sum to the model's total diffuse
//! reflectance R per channel; the 2D kernel is a(x) a(y) / R, so a shader applies the taps in
//! both passes and divides by R once (or, with `--normalize`, uses weights summing to 1 in both
//! passes and multiplies by R, or by its own albedo, afterwards). Multi-term kernels export
//! each term's horizontal and vertical taps as stored (their products sum to R).
//!
//! The JSON text comes from `sss_separable::kernel_json` (`KernelFile::to_json`), whose
//! `KernelFile::from_json` reads it back. The shader text comes from `sss_separable::shader`
//! (the same constants for engines that use the library directly): one array `sssKernel` for a
//! rank-1 kernel, `sssKernelH{i}` and `sssKernelV{i}` per term otherwise; WGSL adds each
//! array's tap count `{name}Taps`, which WGSL cannot query.
//! `crates/separable/examples/separable_sss.wgsl` is a two-pass compute shader that applies a
//! pasted WGSL export with the CPU filter's silhouette rules.

//!
//! [`KernelRequest`] names the kernel (medium, model, method, taps, format); [`export`] returns
//! the text `sss kernel` prints and the Python `Kernel.export` returns.
//!
//! ```
//! use sss_bssrdf::MediumSpec;
//! use sss_render::kernel_export::{KernelFormat, KernelRequest, export};
//! let req = KernelRequest {
//!     format: KernelFormat::Csv,
//!     ..KernelRequest::new(MediumSpec::Preset("skin1".into()))
//! };
//! let csv = export(&req)?;
//! assert!(csv.starts_with("term,direction,offset_mm,weight_r,weight_g,weight_b\n0,both,"));
//! # Ok::<(), sss_render::Error>(())
//! ```

use crate::Error;
use crate::kernel_choice::{
    KernelMethod, MaterialKernel, SeparableSettings, build_kernel, check_separable_options,
};
use sss_bssrdf::{MediumSpec, ModelKind, Rgb, make_model};
use sss_separable::kernel_json::KernelFile;
use sss_separable::shader::{self, ShaderLanguage, ShaderTaps};
use sss_separable::{Energy, Kernel1d, TapPlacement, artist};
use std::fmt::Write as _;

/// Output formats of `sss kernel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelFormat {
    /// `{"method": ..., "taps": [{"offset_mm": x, "weights": [r, g, b]}, ...], ...}`.
    Json,
    /// `term,direction,offset_mm,weight_r,weight_g,weight_b`.
    Csv,
    /// GLSL `vec4` array constants (`const vec4 sssKernel[N] = vec4[](...);`).
    Glsl,
    /// HLSL `float4` array constants (`static const float4 sssKernel[N] = {...};`).
    Hlsl,
    /// WGSL `vec4<f32>` array constants (`const sssKernel: array<vec4<f32>, N> = ...;`) and
    /// their tap counts (`const sssKernelTaps: u32 = Nu;`).
    Wgsl,
}

impl KernelFormat {
    /// Every format, in the order the help lists them.
    pub const ALL: [KernelFormat; 5] = [
        KernelFormat::Json,
        KernelFormat::Csv,
        KernelFormat::Glsl,
        KernelFormat::Hlsl,
        KernelFormat::Wgsl,
    ];

    /// The format's name on the command line and in Python (`json`, `csv`, `glsl`, ...).
    pub fn name(self) -> &'static str {
        match self {
            KernelFormat::Json => "json",
            KernelFormat::Csv => "csv",
            KernelFormat::Glsl => "glsl",
            KernelFormat::Hlsl => "hlsl",
            KernelFormat::Wgsl => "wgsl",
        }
    }
}

impl std::fmt::Display for KernelFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for KernelFormat {
    type Err = Error;

    /// A format by its name ([`KernelFormat::name`]).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        KernelFormat::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = KernelFormat::ALL.iter().map(|f| f.name()).collect();
                Error::Input(format!(
                    "unknown format `{s}` (one of: {})",
                    names.join(", ")
                ))
            })
    }
}

/// Everything that names an exported kernel: what `sss kernel`'s flags say.
#[derive(Clone, Debug, PartialEq)]
pub struct KernelRequest {
    /// The medium.
    pub medium: MediumSpec,
    /// Relative index of refraction; `None` keeps the presets' 1.3.
    pub eta: Option<f64>,
    /// The BSSRDF model whose R_d is approximated.
    pub model: ModelKind,
    /// The kernel (a separable one; `artist` is fitted to the material).
    pub method: KernelMethod,
    /// With `method` artist: a Table 2 parameter set by name instead of a fit.
    pub artist_preset: Option<String>,
    /// Guided-optimisation exponent k in [0, 4].
    pub k: f64,
    /// Taps per 1D pass.
    pub taps: usize,
    /// Taps placed uniformly instead of by importance (SVD terms always are).
    pub uniform: bool,
    /// The output format.
    pub format: KernelFormat,
    /// Weights scaled to sum to 1 instead of the total diffuse reflectance.
    pub normalize: bool,
}

impl KernelRequest {
    /// The request with `sss kernel`'s defaults for `medium`: the better dipole, the
    /// pre-integrated kernel, 7 importance-placed taps, k = 2, JSON, weights summing to the
    /// total diffuse reflectance.
    pub fn new(medium: MediumSpec) -> Self {
        KernelRequest {
            medium,
            eta: None,
            model: ModelKind::BetterDipole,
            method: KernelMethod::Preintegrated,
            artist_preset: None,
            k: 2.0,
            taps: 7,
            uniform: false,
            format: KernelFormat::Json,
            normalize: false,
        }
    }
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:e}")
    } else {
        "0".into()
    }
}

/// What every format of `sss kernel` prints: the kernel's name, the model's total diffuse
/// reflectance, and the taps as a shader applies them.
struct Exported {
    /// `preintegrated`, `artist:production`, `guided:k=2`, ...
    method: String,
    /// The medium as given.
    spec: MediumSpec,
    /// The model's total diffuse reflectance per channel.
    total: Rgb,
    /// The taps ([`ShaderTaps::new`] with the energy `--normalize` asks for).
    taps: ShaderTaps,
}

/// Builds the kernel `args` ask for and its exported taps.
fn export_taps(args: &KernelRequest) -> Result<Exported, Error> {
    check_separable_options(args.taps, args.k, 0.0)?;
    if !args.method.is_separable() {
        return Err(Error::Input(format!(
            "--method {} is the full 2D kernel, not a separable one; choose one of {}",
            args.method,
            KernelMethod::separable_names().join(", ")
        )));
    }
    if args.artist_preset.is_some() && args.method != KernelMethod::Artist {
        return Err(Error::Input("--artist-preset needs --method artist".into()));
    }
    let spec = args.medium.clone();
    let medium = spec.medium(args.eta)?;
    let model = make_model(args.model, &medium);
    let total: Rgb = std::array::from_fn(|c| model.total_diffuse_reflectance(c));
    let placement = if args.uniform {
        TapPlacement::Uniform(args.taps)
    } else {
        TapPlacement::Importance(args.taps)
    };
    let kernel = match &args.artist_preset {
        Some(name) => {
            let params = artist::preset(name).map_err(|e| Error::Input(e.to_string()))?;
            artist::kernel(&params, total, placement).map_err(|e| Error::Input(e.to_string()))?
        }
        None => {
            let settings = SeparableSettings {
                kernel: args.method,
                taps: args.taps,
                importance: !args.uniform,
                k: args.k,
                jitter: 0.0,
            };
            match build_kernel(model.as_ref(), &settings)
                .map_err(|e| Error::Input(e.to_string()))?
            {
                MaterialKernel::Separable(k) => k,
                MaterialKernel::Full(_) => unreachable!("exact2d is rejected above"),
            }
        }
    };
    if !kernel.is_finite() {
        return Err(Error::NonFinite(format!(
            "the {} kernel has a non-finite weight",
            args.method
        )));
    }
    let method = match &args.artist_preset {
        Some(p) => format!("artist:{p}"),
        None if args.method == KernelMethod::Guided => format!("guided:k={}", args.k),
        None => args.method.to_string(),
    };
    let energy = if args.normalize {
        Energy::Unit
    } else {
        Energy::TotalReflectance
    };
    Ok(Exported {
        method,
        spec,
        total,
        taps: ShaderTaps::new(&kernel, total, energy),
    })
}

/// The kernel `args` name, as text in their format: what `sss kernel` prints.
pub fn export(args: &KernelRequest) -> Result<String, Error> {
    let Exported {
        method,
        spec,
        total,
        taps: exported,
    } = export_taps(args)?;
    let mut out = String::new();
    match args.format {
        KernelFormat::Json => {
            let file = KernelFile {
                method,
                model: args.model.to_string(),
                normalized: args.normalize,
                total_diffuse_reflectance: total,
                taps: exported,
            };
            let text = file
                .to_json()
                .map_err(|e| Error::NonFinite(format!("the {} kernel: {e}", args.method)))?;
            out.push_str(&text);
        }
        KernelFormat::Csv => {
            out.push_str("term,direction,offset_mm,weight_r,weight_g,weight_b\n");
            let mut rows = |term: usize, dir: &str, k: &Kernel1d| {
                for t in &k.taps {
                    let _ = writeln!(
                        out,
                        "{term},{dir},{},{},{},{}",
                        num(t.offset_mm),
                        num(t.weight[0]),
                        num(t.weight[1]),
                        num(t.weight[2])
                    );
                }
            };
            match &exported {
                ShaderTaps::Rank1(t) => rows(0, "both", t),
                ShaderTaps::Terms(terms) => {
                    for (i, t) in terms.iter().enumerate() {
                        rows(i, "horizontal", &t.horizontal);
                        rows(i, "vertical", &t.vertical);
                    }
                }
            }
        }
        KernelFormat::Glsl | KernelFormat::Hlsl | KernelFormat::Wgsl => {
            let language = match args.format {
                KernelFormat::Glsl => ShaderLanguage::Glsl,
                KernelFormat::Hlsl => ShaderLanguage::Hlsl,
                _ => ShaderLanguage::Wgsl,
            };
            let _ = writeln!(
                out,
                "// {} kernel of {} ({}), {} taps: float4(r, g, b, offset in mm), centre tap first.",
                method,
                match &spec {
                    MediumSpec::Preset(p) => p.clone(),
                    MediumSpec::Coefficients { .. } => "custom medium".into(),
                },
                args.model,
                args.taps
            );
            let _ = writeln!(
                out,
                "// Weights sum to {}; total diffuse reflectance ({}, {}, {}).",
                if args.normalize {
                    "1"
                } else {
                    "the total diffuse reflectance"
                },
                num(total[0]),
                num(total[1]),
                num(total[2])
            );
            let text = shader::constants(&exported, language)
                .map_err(|e| Error::NonFinite(format!("the {} kernel: {e}", args.method)))?;
            out.push_str(&text);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The JSON writer `sss kernel` had before it moved to `sss_separable::kernel_json`,
    /// verbatim: the library's text must stay byte for byte what users' files hold.
    fn old_json(args: &KernelRequest, e: &Exported, passes: usize) -> String {
        fn taps_json(k: &Kernel1d) -> String {
            let items: Vec<String> = k
                .taps
                .iter()
                .map(|t| {
                    format!(
                        "{{\"offset_mm\": {}, \"weights\": [{}, {}, {}]}}",
                        num(t.offset_mm),
                        num(t.weight[0]),
                        num(t.weight[1]),
                        num(t.weight[2])
                    )
                })
                .collect();
            format!("[{}]", items.join(", "))
        }
        let mut out = String::new();
        let total = e.total;
        let _ = write!(
            out,
            "{{\"method\": \"{}\", \"model\": \"{}\", \"normalized\": {}, \"total_diffuse_reflectance\": [{}, {}, {}], \"passes\": {}",
            e.method,
            args.model,
            args.normalize,
            num(total[0]),
            num(total[1]),
            num(total[2]),
            passes
        );
        match &e.taps {
            ShaderTaps::Rank1(t) => {
                let _ = write!(out, ", \"taps\": {}", taps_json(t));
            }
            ShaderTaps::Terms(terms) => {
                let terms: Vec<String> = terms
                    .iter()
                    .map(|t| {
                        format!(
                            "{{\"horizontal\": {}, \"vertical\": {}}}",
                            taps_json(&t.horizontal),
                            taps_json(&t.vertical)
                        )
                    })
                    .collect();
                let _ = write!(out, ", \"terms\": [{}]", terms.join(", "));
            }
        }
        out.push_str("}\n");
        out
    }

    /// The request `sss kernel` builds from `args` (the flags of the cases below).
    fn kernel_args(args: &[&str]) -> KernelRequest {
        let mut req = KernelRequest::new(MediumSpec::Preset("marble".into()));
        let mut it = args.iter();
        while let Some(flag) = it.next() {
            let mut value = || it.next().expect("a value").to_string();
            match *flag {
                "--preset" => req.medium = MediumSpec::Preset(value()),
                "--method" => req.method = value().parse().expect("a kernel method"),
                "--taps" => req.taps = value().parse().expect("a tap count"),
                "--k" => req.k = value().parse().expect("an exponent"),
                "--artist-preset" => req.artist_preset = Some(value()),
                "--uniform" => req.uniform = true,
                "--normalize" => req.normalize = true,
                other => panic!("no case for {other}"),
            }
        }
        req
    }

    /// `sss kernel --format json` prints what the old writer printed, for rank-1 and
    /// multi-term kernels, plain and normalised, and the library reads it back to the same
    /// taps.
    #[test]
    fn kernel_json_is_the_old_text_and_reads_back() {
        for method in [
            &["--method", "preintegrated"][..],
            &["--method", "svd3", "--taps", "5"],
            &["--method", "gaussians6", "--taps", "3"],
            &["--method", "guided", "--k", "1.5"],
            &["--method", "artist", "--artist-preset", "production"],
            &["--method", "svd1", "--uniform", "--taps", "4"],
        ] {
            for normalize in [false, true] {
                let mut a = vec!["--preset", "marble"];
                a.extend_from_slice(method);
                if normalize {
                    a.push("--normalize");
                }
                let args = kernel_args(&a);
                let e = export_taps(&args).unwrap();
                // The old writer printed the kernel's `passes()`, 2 per term; `ShaderTaps::new`
                // gives `Rank1` exactly for one term.
                let passes = match &e.taps {
                    ShaderTaps::Rank1(_) => 2,
                    ShaderTaps::Terms(t) => 2 * t.len(),
                };
                let text = export(&args).unwrap();
                assert_eq!(text, old_json(&args, &e, passes), "{a:?}");
                let back = KernelFile::from_json(&text).unwrap();
                assert_eq!(back.taps, e.taps, "{a:?}");
                assert_eq!(back.total_diffuse_reflectance, e.total);
                assert_eq!(back.normalized, normalize);
                assert_eq!(
                    (back.method.as_str(), back.passes()),
                    (e.method.as_str(), passes)
                );
            }
        }
    }

    #[test]
    fn formats_parse_back_by_name() {
        for f in KernelFormat::ALL {
            assert_eq!(f.name().parse::<KernelFormat>().unwrap(), f);
        }
        let e = "yaml".parse::<KernelFormat>().unwrap_err().to_string();
        assert!(e.contains("`yaml`") && e.contains("wgsl"), "{e}");
    }
}
