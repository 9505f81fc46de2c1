//! The `pathtrace` reference: BSSRDF importance sampling as in pbrt 3rd ed. §15.4. From each
//! shading point x_o a radius is drawn from one channel's profile, mapped onto the object by a
//! probe chord along one of three axes of the local frame (normal with probability 1/2, each
//! tangent 1/4) inside the sphere holding a fraction `--probe-energy` (default
//! [`default_probe_energy`]) of that channel's energy, one of the chord's hits on the same
//! object is chosen uniformly, and the direct light there (shadow rays, one light sample per
//! area or environment light) is weighted by the BSSRDF over the combined density of all
//! 3 × 3 axis-channel techniques (multiple importance sampling, the balance heuristic).
//!
//! The density of a hit sums, for each technique, its radial density times the probability of
//! choosing that hit among the hits on the technique's own chord through it; a technique whose
//! probe sphere cannot reach the hit contributes nothing. Choosing one of the chord's n hits
//! uniformly and dividing by its density (which carries the 1/n) is unbiased: the count
//! cancels, as in pbrt, whose division by the number of hits is not a source of bias either.
//! pbrt-v3's bias is elsewhere: its MIS density (`SeparableBSSRDF::Pdf_Sp`) sums the radial
//! density of every axis–channel technique, including those whose probe sphere (radius r_max
//! of that channel) cannot reach the hit, which makes it too large and the image too dark
//! (measured on the sphere with `pbd`: stock pbrt-v3 is 2.2 % dark in red; with those
//! techniques skipped it agrees with this integrator to 0.1 % per channel). Here every
//! technique's term is skipped when the hit lies outside its sphere, so the estimator is
//! unbiased up to the energy beyond the largest probe sphere.
//!
//! That energy is the one bias: a point farther from x_o than every channel's probe radius is
//! never sampled. Per channel it is the fraction of R_d,total beyond the largest probe radius,
//! at most 1 − `probe-energy` (less for the channels whose own radius is smaller); it is
//! reported as the stat `probe_missed_energy` (the largest fraction over the image's materials
//! and channels). On a flat surface under irradiance at most E_max the radiance it removes is at
//! most F_t/(cπ) · E_max · R_d,total · that fraction; relative to a pixel it matters most where
//! the pixel's light comes from far away (pixels in shadow, lit from around the terminator).
//! Measured on the test sphere of `tests/pathtrace_bias.rs` (skin1, 10 mm per unit), the
//! default's red sphere already spans the object and deep-shadow pixels agree with `exact`
//! within 1.5 standard errors at 400 000 samples. Short runs there read low with a small
//! standard error: the estimate is heavy-tailed (skew, not bias), so per-pixel agreement in
//! shadow needs many samples (`--spp 4096` on that sphere, `docs/usage.md`), not a larger sphere.
//!
//! It converges to the surface integral that the `exact` sum approximates with discrete
//! irradiance samples, so it is the reference of the whole pipeline, sample density included,
//! for the material's BSSRDF model: exact for the model only. Real light transport in the
//! object, which no model is, is `volpath`'s.

pub use crate::probe::{
    ChordHits, ProbeRadii, Sampler, Scratch, default_probe_energy, probe_radii,
};

use super::{
    Converges, Integrator, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep,
    mean_and_variance, pixel_std_error,
};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::options::{PROBE_ENERGY, declared};
use crate::progress::Progress;
use crate::rng::{Stream, rng};
use rayon::prelude::*;
use sss_bssrdf::Rgb;

/// The options of `pathtrace`.
const OPTIONS: [OptionSpec; 2] = [
    OptionSpec {
        name: "spp",
        value_name: "N",
        default: "16",
        help: "BSSRDF samples per pixel sample",
        kind: OptionKind::Value,
        values: &[],
    },
    PROBE_ENERGY,
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "pathtrace",
    about: "BSSRDF importance-sampled path tracing (pbrt §15.4)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(PathTrace::from_options(o)?)),
    sweep: Sweep {
        option: "spp",
        label: "spp",
        values: |quick| {
            if quick {
                vec![1.0, 4.0, 16.0]
            } else {
                vec![1.0, 4.0, 16.0, 64.0]
            }
        },
    },
    converges_to: Converges::Model,
};

/// The `pathtrace` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathTrace {
    /// BSSRDF samples per G-buffer sample (≥ 1).
    pub spp: u32,
    /// Fraction of each channel's profile energy inside its probe sphere, in (0, 1) (default
    /// [`default_probe_energy`]); see the module docs for the bias it leaves.
    pub probe_energy: f64,
}

impl Default for PathTrace {
    /// The declared defaults of `--spp` and `--probe-energy`.
    fn default() -> Self {
        PathTrace {
            spp: declared(&OPTIONS, "spp"),
            probe_energy: declared(&OPTIONS, "probe-energy"),
        }
    }
}

impl PathTrace {
    /// The settings `options` describe.
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        let spp: u32 = o.get(&OPTIONS, "spp")?;
        if spp == 0 {
            return Err(Error::Input("--spp must be at least 1".into()));
        }
        let probe_energy: f64 = o.get(&OPTIONS, "probe-energy")?;
        if !(probe_energy > 0.0 && probe_energy < 1.0) {
            return Err(Error::Input(format!(
                "--probe-energy must lie strictly between 0 and 1, got {probe_energy}"
            )));
        }
        Ok(PathTrace { spp, probe_energy })
    }
}

impl Integrator for PathTrace {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!(
            "bssrdf samples per pixel sample: {}, probe-sphere energy fraction {}",
            self.spp, self.probe_energy
        )
    }

    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error> {
        for &o in &frame.visible {
            if let Some(sh) = frame.shading_of(o) {
                sh.one_profile(METHOD.name)?;
            }
        }
        let scene = frame.scene;
        let t = std::time::Instant::now();
        // `missed`: the largest energy fraction never sampled, over the materials the image
        // shows.
        let (radii, missed) = probe_radii(&frame.shading, self.probe_energy);
        let spp = self.spp.max(1);
        let sampler = |shading, radii| Sampler {
            geom: &frame.geom,
            lights: &scene.lights,
            shading,
            radii,
        };
        let gspp = frame.gbuffer.samples_per_pixel as u64;
        let results: Vec<(Rgb, Rgb)> = frame
            .gbuffer
            .samples
            .par_iter()
            .map_init(Scratch::default, |scratch, g| {
                progress.advance(1);
                let m = scene.objects[g.object as usize].material;
                let (Some(sh), Some(rad)) = (frame.shading[m].as_ref(), radii[m].as_ref()) else {
                    return ([0.0; 3], [0.0; 3]);
                };
                let mut r = rng(
                    frame.seed,
                    Stream::Path,
                    g.pixel as u64 * gspp + g.index as u64,
                );
                let mut sum = [0.0; 3];
                let mut sum2 = [0.0; 3];
                for _ in 0..spp {
                    let v = sampler(sh, rad).sample(g, &mut r, scratch);
                    for c in 0..3 {
                        sum[c] += v[c];
                        sum2[c] += v[c] * v[c];
                    }
                }
                let (mean, var) = mean_and_variance(sum, sum2, spp);
                (mean, var)
            })
            .collect();
        frame.record("shading", t.elapsed().as_secs_f64());
        let values: Vec<Rgb> = results.iter().map(|r| r.0).collect();
        let variances: Vec<Rgb> = results.iter().map(|r| r.1).collect();
        let se = pixel_std_error(&frame.gbuffer, &variances);
        let gb = &frame.gbuffer;
        let shaded = gb
            .samples
            .iter()
            .filter(|g| frame.shading_of(g.object).is_some())
            .count();
        Ok(Shaded {
            values,
            std_error: Some(se),
            stats: vec![
                Stat {
                    name: "paths",
                    value: shaded as f64 * spp as f64,
                },
                Stat {
                    name: "probe_missed_energy",
                    value: missed,
                },
            ],
            layers: Vec::new(),
        })
    }
}
