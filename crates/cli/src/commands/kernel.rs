//! `sss kernel`: exports a separable subsurface-scattering kernel (Jimenez et al. 2015) for a
//! material as JSON, CSV, or GLSL/HLSL constants in the `float4(r, g, b, offset)` layout of the
//! public 2012 separable-SSS shader code.
//!
//! Weights: for a rank-1 kernel (every method but `svd3`, `svd6` and `gaussians6`) the exported
//! taps are the 1D profile a(x) of Eq. 5 whose weights sum to the model's total diffuse
//! reflectance R per channel; the 2D kernel is a(x) a(y) / R, so a shader applies the taps in
//! both passes and divides by R once (or, with `--normalize`, uses weights summing to 1 in both
//! passes and multiplies by R, or by its own albedo, afterwards). Multi-term kernels export
//! each term's horizontal and vertical taps as stored (their products sum to R).

use crate::args::MediumArgs;
use crate::profile_table::{MediumSpec, build_medium};
use clap::{Args, ValueEnum};
use sss_bssrdf::{ModelKind, Rgb, make_model};
use sss_render::Error;
use sss_render::kernel_choice::check_separable_options;
use sss_render::kernel_choice::{KernelMethod, MaterialKernel, SeparableSettings, build_kernel};
use sss_separable::{Kernel1d, SeparableKernel, TapPlacement, artist};
use std::fmt::Write as _;

/// Output formats of `sss kernel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum KernelFormat {
    /// `{"method": ..., "taps": [{"offset_mm": x, "weights": [r, g, b]}, ...], ...}`.
    Json,
    /// `term,direction,offset_mm,weight_r,weight_g,weight_b`.
    Csv,
    /// GLSL `vec4` array constants.
    Glsl,
    /// HLSL `float4` array constants.
    Hlsl,
}

/// Arguments of `sss kernel`.
#[derive(Debug, Args)]
pub struct KernelArgs {
    /// The medium.
    #[command(flatten)]
    pub medium: MediumArgs,
    /// The BSSRDF model whose R_d is approximated.
    #[arg(long, default_value = "better-dipole")]
    pub model: ModelKind,
    /// The kernel: preintegrated, svd1, svd3, svd6, artist (fitted to the material), guided,
    /// gaussians1, gaussians6.
    #[arg(long, default_value = "preintegrated")]
    pub method: KernelMethod,
    /// With `--method artist`: use a Table 2 parameter set (`close-fit` or `production`)
    /// instead of fitting the material.
    #[arg(long)]
    pub artist_preset: Option<String>,
    /// Guided-optimisation exponent k in [0, 4].
    #[arg(long, default_value_t = 2.0, allow_hyphen_values = true)]
    pub k: f64,
    /// Taps per 1D pass.
    #[arg(long, default_value_t = 7)]
    pub taps: usize,
    /// Place taps uniformly instead of by importance (SVD terms always are).
    #[arg(long)]
    pub uniform: bool,
    /// Output format.
    #[arg(long, value_enum, default_value_t = KernelFormat::Json)]
    pub format: KernelFormat,
    /// Scale the weights to sum to 1 instead of the total diffuse reflectance.
    #[arg(long)]
    pub normalize: bool,
}

/// The exported kernel: rank-1 taps (weights summing to R or 1), or the terms.
struct Export {
    method: String,
    taps: Option<Kernel1d>,
    terms: Vec<(Kernel1d, Kernel1d)>,
    total: Rgb,
}

fn export_of(kernel: &SeparableKernel, method: String, total: Rgb, normalize: bool) -> Export {
    if kernel.terms.len() == 1 {
        // A rank-1 kernel of a radial profile has v ∝ h; a = h · R / Σh keeps h's shape, sums
        // to R, and a(x) a(y) / R = h(x) v(y) because Σh · Σv = R.
        let h = &kernel.terms[0].horizontal;
        let sum = h.sum();
        let scale: Rgb = std::array::from_fn(|c| {
            let target = if normalize { 1.0 } else { total[c].max(0.0) };
            if sum[c] > 0.0 { target / sum[c] } else { 0.0 }
        });
        return Export {
            method,
            taps: Some(h.scaled(scale)),
            terms: Vec::new(),
            total,
        };
    }
    let terms = kernel
        .terms
        .iter()
        .map(|t| {
            if normalize {
                let inv: Rgb =
                    std::array::from_fn(|c| if total[c] > 0.0 { 1.0 / total[c] } else { 0.0 });
                (t.horizontal.clone(), t.vertical.scaled(inv))
            } else {
                (t.horizontal.clone(), t.vertical.clone())
            }
        })
        .collect();
    Export {
        method,
        taps: None,
        terms,
        total,
    }
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:e}")
    } else {
        "0".into()
    }
}

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

fn float4_array(k: &Kernel1d, glsl: bool, name: &str) -> String {
    let v = k.to_float4();
    let items: Vec<String> = v
        .iter()
        .map(|f| {
            let ty = if glsl { "vec4" } else { "float4" };
            format!("    {ty}({:?}, {:?}, {:?}, {:?})", f[0], f[1], f[2], f[3])
        })
        .collect();
    if glsl {
        format!(
            "const vec4 {name}[{}] = vec4[](\n{}\n);\n",
            v.len(),
            items.join(",\n")
        )
    } else {
        format!(
            "static const float4 {name}[{}] = {{\n{}\n}};\n",
            v.len(),
            items.join(",\n")
        )
    }
}

/// Runs `sss kernel`: the kernel text for stdout.
pub fn run(args: &KernelArgs) -> Result<String, Error> {
    check_separable_options(args.taps, args.k, 0.0)?;
    if args.method == KernelMethod::Exact2d {
        return Err(Error::Input(
            "--method exact2d is the full 2D kernel, not a separable one; choose preintegrated, svd1, svd3, svd6, artist, guided, gaussians1 or gaussians6".into(),
        ));
    }
    if args.artist_preset.is_some() && args.method != KernelMethod::Artist {
        return Err(Error::Input("--artist-preset needs --method artist".into()));
    }
    let spec = args.medium.spec()?;
    let medium = build_medium(&spec, args.medium.eta)?;
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
    let e = export_of(&kernel, method, total, args.normalize);
    let mut out = String::new();
    match args.format {
        KernelFormat::Json => {
            let _ = write!(
                out,
                "{{\"method\": \"{}\", \"model\": \"{}\", \"normalized\": {}, \"total_diffuse_reflectance\": [{}, {}, {}], \"passes\": {}",
                e.method,
                args.model,
                args.normalize,
                num(e.total[0]),
                num(e.total[1]),
                num(e.total[2]),
                kernel.passes()
            );
            if let Some(t) = &e.taps {
                let _ = write!(out, ", \"taps\": {}", taps_json(t));
            } else {
                let terms: Vec<String> = e
                    .terms
                    .iter()
                    .map(|(h, v)| {
                        format!(
                            "{{\"horizontal\": {}, \"vertical\": {}}}",
                            taps_json(h),
                            taps_json(v)
                        )
                    })
                    .collect();
                let _ = write!(out, ", \"terms\": [{}]", terms.join(", "));
            }
            out.push_str("}\n");
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
            if let Some(t) = &e.taps {
                rows(0, "both", t);
            } else {
                for (i, (h, v)) in e.terms.iter().enumerate() {
                    rows(i, "horizontal", h);
                    rows(i, "vertical", v);
                }
            }
        }
        KernelFormat::Glsl | KernelFormat::Hlsl => {
            let glsl = args.format == KernelFormat::Glsl;
            let _ = writeln!(
                out,
                "// {} kernel of {} ({}), {} taps: float4(r, g, b, offset in mm), centre tap first.",
                e.method,
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
                num(e.total[0]),
                num(e.total[1]),
                num(e.total[2])
            );
            if let Some(t) = &e.taps {
                out.push_str(&float4_array(t, glsl, "sssKernel"));
            } else {
                for (i, (h, v)) in e.terms.iter().enumerate() {
                    out.push_str(&float4_array(h, glsl, &format!("sssKernelH{i}")));
                    out.push_str(&float4_array(v, glsl, &format!("sssKernelV{i}")));
                }
            }
        }
    }
    Ok(out)
}
