//! The `exact` reference: at each shading point, the sum over every irradiance sample of its
//! object of the model's contribution, with no hierarchy and no culling. Ground truth for the
//! hierarchical methods (single tree, dual tree, many-light) on the same points: their error
//! against it is the hierarchy's error alone.
//!
//! Each sample's R_d is [`TranslucentShading::rd_sample_scene`]: R_d averaged over the
//! sample's own disk (its area A_i) near the shading point, where peaked profiles would
//! otherwise let the nearest sample dominate, and the (corrected) point value far away. So
//! the sum is a good estimate of the surface integral pixel by pixel, not only on average
//! (per-pixel agreement with `pathtrace`: `tests/disk_average.rs`).
//!
//! [`shade_subset`] computes the same values for a subset of pixels only: a reference at
//! resolutions where shading every pixel would take too long, scored with
//! [`crate::metrics::subset_error`].

use super::{LitSamples, lit_samples};
use crate::Error;
use crate::frame::Frame;
use crate::frame::assembled_subsurface;
use crate::gbuffer::GSample;
use crate::integrators::Converges;
use crate::integrators::options::SAMPLE_OPTIONS;
use crate::integrators::options::sample_settings;
use crate::integrators::{Integrator, Method, MethodOptions, Shaded, Stat, Sweep, add_weighted};
use crate::irradiance::{IrradianceSample, IrradianceSettings, ObjectSamples};
use crate::local_radius::{FrameBalls, LocalBalls};
use crate::progress::Progress;
use crate::shading::TranslucentShading;
use rayon::prelude::*;
use sss_bssrdf::{EntryDrift, Rgb, SurfacePoint};

/// The irradiance-sample spacing (mean free paths) of `cargo xtask compare`'s reference: the
/// default, or twice it with `--quick`.
pub fn reference_spacing(quick: bool) -> f64 {
    let default = IrradianceSettings::default().spacing_mfp;
    if quick { 2.0 * default } else { default }
}

/// The registry entry.
pub const METHOD: Method = Method {
    name: "exact",
    about: "Brute-force sum over all irradiance samples",
    options: &SAMPLE_OPTIONS,
    build: |o| Ok(Box::new(Exact::from_options(o)?)),
    sweep: Sweep {
        option: "spacing",
        label: "spacing_mfp",
        // Coarser samples than the reference (×8, ×4, ×2; ×4, ×2 with --quick): how the error
        // grows as the samples thin out.
        values: |quick| {
            let factors: &[f64] = if quick { &[4.0, 2.0] } else { &[8.0, 4.0, 2.0] };
            factors
                .iter()
                .map(|f| f * reference_spacing(quick))
                .collect()
        },
    },
    converges_to: Converges::Model,
};

/// The `exact` integrator and its settings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Exact {
    /// Irradiance sample placement and lighting.
    pub irradiance: IrradianceSettings,
}

impl Exact {
    /// The settings `options` describe.
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        Ok(Exact {
            irradiance: sample_settings(o)?,
        })
    }
}

impl Integrator for Exact {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!(
            "irradiance sample spacing {} mean free paths, at most {} per object",
            self.irradiance.spacing_mfp, self.irradiance.max_samples
        )
    }

    fn irradiance_settings(&self) -> Option<IrradianceSettings> {
        Some(self.irradiance)
    }

    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error> {
        let LitSamples {
            samples,
            balls,
            stats: light_stats,
        } = lit_samples(frame, &self.irradiance)?;
        let by_object = frame.samples_by_object(&samples);
        let values: Vec<Rgb> = frame.timed("shading", || {
            frame
                .gbuffer
                .samples
                .par_iter()
                .enumerate()
                .map(|(k, g)| {
                    progress.advance(1);
                    match (frame.shading_of(g.object), by_object[g.object as usize]) {
                        (Some(sh), Some(s)) => shade_with(g, sh, s, ball_of(&balls, k, g)),
                        _ => [0.0; 3],
                    }
                })
                .collect()
        });
        let evaluations: usize = frame
            .gbuffer
            .samples
            .iter()
            .filter(|g| frame.shading_of(g.object).is_some())
            .map(|g| by_object[g.object as usize].map_or(0, |s| s.samples.len()))
            .sum();
        let mut stats = vec![Stat {
            name: "sample_pairs",
            value: evaluations as f64,
        }];
        stats.extend(light_stats);
        let mut layers = Vec::new();
        super::ball_outputs(frame, &balls, &mut stats, &mut layers);
        Ok(Shaded {
            values,
            stats,
            layers,
            ..Shaded::default()
        })
    }
}

/// The subsurface radiance leaving `g` towards the camera, with the material's one profile: a
/// material that gives each point its own ball (`sphere_radius = "local"`) needs the radii of
/// its frame ([`crate::local_radius::frame_balls`]) through [`shade_with`].
pub fn shade(g: &GSample, shading: &TranslucentShading, samples: &ObjectSamples) -> Rgb {
    shade_with(g, shading, samples, None)
}

/// The balls of G-buffer sample `k` (`g`): its object's and its own radius, when its material
/// gives each point its own ball.
fn ball_of<'b>(balls: &'b FrameBalls, k: usize, g: &GSample) -> Option<(&'b LocalBalls, f64)> {
    let own = balls.objects.get(g.object as usize)?.as_ref()?;
    Some((own, balls.points.get(k).copied().unwrap_or(f64::NAN)))
}

/// [`shade`], with each pair's own ball where `ball` gives the object's balls and the shading
/// point's radius (mm) ([`crate::local_radius`]).
pub fn shade_with(
    g: &GSample,
    shading: &TranslucentShading,
    samples: &ObjectSamples,
    ball: Option<(&LocalBalls, f64)>,
) -> Rgb {
    let mut sum = [0.0; 3];
    if shading.directional() {
        // Full S of the directional dipole, positions in mm.
        let u = shading.units_per_mm;
        let model = shading.bssrdf();
        let xo = SurfacePoint { p: g.p / u, n: g.n };
        for (i, s) in samples.samples.iter().enumerate() {
            let xi = SurfacePoint {
                p: s.position / u,
                n: s.normal,
            };
            let a = s.area / (u * u);
            for packet in samples.incident_of(i) {
                let sv = model.s(&xi, packet.dir, &xo, g.wo);
                for c in 0..3 {
                    sum[c] += sv[c] * packet.e_cos[c] * a;
                }
            }
        }
        return sum;
    }
    // A drifting material's irradiance depends on the shading point: each sample's packets,
    // each moved by the drift towards g ([`TranslucentShading::entering_towards`]); with each
    // point's own ball, by the drift of the pair's ball.
    let toward_g = |i: usize, s: &IrradianceSample, drift: Option<&EntryDrift>| match drift {
        Some(d) => shading.entering_towards_with(
            Some(d),
            samples.incident_of(i),
            (s.position, s.normal),
            (g.p, g.n, g.wo),
        ),
        None => s.irradiance,
    };
    match ball {
        Some((balls, radius)) => shading.add_point_sum_local(
            &mut sum,
            g.p,
            &balls.family,
            samples
                .samples
                .iter()
                .zip(&balls.samples)
                .enumerate()
                .map(|(i, (s, &ri))| {
                    let pair = (radius * ri).sqrt();
                    (
                        s.position,
                        s.area,
                        toward_g(i, s, balls.family.drift(pair)),
                        pair,
                    )
                }),
        ),
        None => shading.add_point_sum(
            &mut sum,
            g.p,
            samples
                .samples
                .iter()
                .enumerate()
                .map(|(i, s)| (s.position, s.area, toward_g(i, s, shading.drift.as_deref()))),
        ),
    }
    let mut out = [0.0; 3];
    add_weighted(&mut out, sum, shading.exit_weights(g.n, g.wo));
    out
}

/// The pixels of `frame` with at least one G-buffer sample on a visible translucent object:
/// the pixels with translucent coverage ([`crate::pipeline::RenderOutput::translucent_pixels`]
/// of a render of the same frame), in increasing order.
pub fn translucent_pixels(frame: &Frame<'_>) -> Vec<usize> {
    frame.translucent_pixels()
}

/// The subsurface values that `exact` with `irradiance` gives the pixels `pixels` of `frame`,
/// assembled as [`crate::render`] assembles them (the mean over the pixel's camera
/// samples, those off translucent objects counting 0), so equal to the full render's
/// `subsurface` at those pixels to rounding. Only the listed pixels are shaded; the irradiance
/// samples are built for every visible translucent object (check their memory first with
/// [`crate::budget::check_irradiance`]). Shading is timed as stage `shading`. A pixel index
/// past the image is an error.
pub fn shade_subset(
    frame: &Frame<'_>,
    irradiance: &IrradianceSettings,
    pixels: &[usize],
) -> Result<Vec<Rgb>, Error> {
    let n = frame.gbuffer.pixels();
    if let Some(&bad) = pixels.iter().find(|&&i| i >= n) {
        return Err(Error::Input(format!(
            "subset reference: pixel {bad} is past the image's {n} pixels"
        )));
    }
    let LitSamples { samples, balls, .. } = lit_samples(frame, irradiance)?;
    let by_object = frame.samples_by_object(&samples);
    let gb = &frame.gbuffer;
    Ok(frame.timed("shading", || {
        pixels
            .par_iter()
            .map(|&i| {
                let first = gb.offsets[i] as usize;
                let values: Vec<Option<Rgb>> = gb
                    .pixel(i)
                    .iter()
                    .enumerate()
                    .map(|(j, g)| {
                        match (frame.shading_of(g.object), by_object[g.object as usize]) {
                            (Some(sh), Some(s)) => {
                                Some(shade_with(g, sh, s, ball_of(&balls, first + j, g)))
                            }
                            (Some(_), None) => Some([0.0; 3]),
                            _ => None,
                        }
                    })
                    .collect();
                assembled_subsurface(&values, gb.samples_per_pixel)
            })
            .collect()
    }))
}
