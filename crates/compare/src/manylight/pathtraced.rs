//! The independent reference of `compare --manylight`: the path tracer's BSSRDF importance
//! sampling ([`Sampler`], pbrt 3rd ed. §15.4) on the scored pixels, with as many paths as each
//! pixel needs for its standard error to reach a target.
//!
//! It shares no code path with the many-light estimator or its baselines: no VPLs (area lights
//! are sampled continuously, so the reference also measures the VPL discretisation), no
//! triangle or light clusters, no bounds, no stopping rule. It estimates the same pixel values:
//! the same G-buffer (the frame's camera samples, seeded by the run's seed), a pixel's value
//! the sum of its camera samples' values over the camera samples per pixel, as
//! `sss_render::assembled_subsurface` assembles them. Its one bias is the profile
//! energy beyond the probe spheres ([`Reference::missed`], at most 1 − the probe energy).
//!
//! **No stopping bias.** A pilot of [`Budget::pilot`] paths per camera sample estimates each
//! pixel's variance; the paths the pixel then gets are fixed from the pilot alone, and the
//! estimate and its standard error come from those fresh paths only (the pilot is discarded).
//! Heavy-tailed pixels whose pilot underestimates their variance end with a standard error
//! above the target; they are not scored at the ε their error cannot resolve (see
//! [`Reference::resolves`]).

use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_render::frame::Frame;
use sss_render::integrators::pathtrace::{
    ProbeRadii, Sampler, Scratch, default_probe_energy, probe_radii,
};
use sss_render::rng::{Stream, rng};
use std::time::Instant;

use super::lum;

/// Paths per parallel work item: one camera sample's paths are cut into chunks of this many, so
/// that a few expensive pixels still spread over every thread.
const CHUNK: u64 = 2048;

/// The relative standard error a pixel's pilot must reach before its variance sets its paths.
const PILOT_REL_SE: f64 = 0.1;

/// How many paths the reference spends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budget {
    /// Paths per camera sample of the pilot that sets each pixel's path count.
    pub pilot: u64,
    /// The relative standard error (of the pixel's luminance) to reach.
    pub target_rel_se: f64,
    /// The first this many pixels of the subset (a seeded uniform choice, so not chosen by
    /// their variance) aim at [`Budget::fine_rel_se`] instead: the smallest ε is scored on
    /// them alone, where a whole subset at that precision is out of reach.
    pub fine_pixels: usize,
    /// The relative standard error the first [`Budget::fine_pixels`] pixels aim at.
    pub fine_rel_se: f64,
    /// Paths per pixel at most (over all its camera samples).
    pub max_paths: u64,
}

/// The path-traced values of the scored pixels.
#[derive(Clone, Debug, Default)]
pub struct Reference {
    /// Pixel indices (row-major), the scored subset.
    pub pixels: Vec<usize>,
    /// Subsurface radiance of each pixel.
    pub values: Vec<Rgb>,
    /// Standard error of each pixel's luminance over its luminance (0 for a black pixel).
    pub rel_se: Vec<f64>,
    /// Paths traced after the pilots.
    pub paths: u64,
    /// The largest fraction of a profile's energy beyond the probe spheres, over the materials
    /// and channels (the reference's one bias, an upper bound per channel).
    pub missed: f64,
    /// Wall seconds, pilots included.
    pub seconds: f64,
}

impl Reference {
    /// Whether pixel `k`'s own error can resolve a relative error of `eps`: a reference
    /// standard error at most `eps`/4 (a perfectly calibrated 95 % interval then still scores
    /// ≥ 92 %: the measured error is the estimate's and the reference's, √(1/1.96² + 1/16)·ε
    /// = 0.57 ε wide, and 1/0.57 = 1.76 standard deviations hold 92 %).
    pub fn resolves(&self, k: usize, eps: f64) -> bool {
        let v = lum(self.values[k]);
        v > 0.0 && self.rel_se[k] <= 0.25 * eps
    }
}

/// Sums of one work item's paths: per channel Σv, and the luminance's Σ and Σ².
#[derive(Clone, Copy, Default)]
struct Sums {
    n: u64,
    s: [f64; 3],
    l: f64,
    l2: f64,
}

impl Sums {
    fn add(&mut self, o: &Sums) {
        self.n += o.n;
        for c in 0..3 {
            self.s[c] += o.s[c];
        }
        self.l += o.l;
        self.l2 += o.l2;
    }

    fn mean(&self) -> Rgb {
        let n = self.n.max(1) as f64;
        self.s.map(|s| s / n)
    }

    /// Variance of the mean of the luminance.
    fn var_of_mean(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        let n = self.n as f64;
        let m = self.l / n;
        ((self.l2 - n * m * m) / (n - 1.0)).max(0.0) / n
    }
}

/// `n` paths from G-buffer sample `g` (index `gi`), chunk `chunk`, under `seed`.
fn trace(
    frame: &Frame<'_>,
    radii: &[Option<ProbeRadii>],
    item: (usize, u64, u64),
    seed: u64,
) -> Sums {
    let (gi, chunk, n) = item;
    let g = &frame.gbuffer.samples[gi];
    let m = frame.scene.objects[g.object as usize].material;
    let (Some(shading), Some(radii)) = (frame.shading[m].as_ref(), radii[m].as_ref()) else {
        return Sums::default();
    };
    let sampler = Sampler {
        geom: &frame.geom,
        lights: &frame.scene.lights,
        shading,
        radii,
    };
    let mut r = rng(seed, Stream::Path, ((gi as u64) << 24) | chunk);
    let mut scratch = Scratch::default();
    let mut out = Sums {
        n,
        ..Sums::default()
    };
    for _ in 0..n {
        let v = sampler.sample(g, &mut r, &mut scratch);
        for (s, x) in out.s.iter_mut().zip(v) {
            *s += x;
        }
        let l = lum(v);
        out.l += l;
        out.l2 += l * l;
    }
    out
}

/// Runs `items` ((sample index, chunk, paths)) in parallel, deterministic for any thread count
/// (each item has its own stream), and adds each item's sums into its sample's slot.
fn run(
    frame: &Frame<'_>,
    radii: &[Option<ProbeRadii>],
    items: &[(usize, u64, u64)],
    seed: u64,
    sums: &mut [Sums],
) {
    let out: Vec<Sums> = items
        .par_iter()
        .map(|&it| trace(frame, radii, it, seed))
        .collect();
    for (it, s) in items.iter().zip(&out) {
        sums[it.0].add(s);
    }
}

/// Chunks of `n` paths from sample `gi`.
fn chunks(gi: usize, n: u64, out: &mut Vec<(usize, u64, u64)>) {
    let mut left = n;
    let mut k = 0;
    while left > 0 {
        let m = left.min(CHUNK);
        out.push((gi, k, m));
        left -= m;
        k += 1;
    }
}

/// The path-traced reference of `pixels` of `frame` (see the module doc), seeded by `seed`
/// (independent of every run it scores). `log` reports progress.
pub fn path_reference(
    frame: &Frame<'_>,
    pixels: &[usize],
    budget: Budget,
    seed: u64,
    log: &dyn Fn(&str),
) -> Reference {
    let t0 = Instant::now();
    let (radii, missed) = probe_radii(&frame.shading, default_probe_energy());
    let gb = &frame.gbuffer;
    let k = f64::from(gb.samples_per_pixel.max(1));
    // The translucent camera samples of each pixel.
    let samples: Vec<Vec<usize>> = pixels
        .iter()
        .map(|&p| {
            (gb.offsets[p] as usize..gb.offsets[p + 1] as usize)
                .filter(|&i| frame.shading_of(gb.samples[i].object).is_some())
                .collect()
        })
        .collect();
    // Pilot, in rounds: a pixel whose pilot is still too noisy to give its variance (a
    // relative standard error above PILOT_REL_SE: a dark pixel, lit from afar, whose first
    // paths found little light) doubles its pilot, up to an eighth of its path budget.
    let mut pilot = vec![Sums::default(); gb.samples.len()];
    let mut round = budget.pilot;
    let mut open: Vec<usize> = (0..pixels.len())
        .filter(|&j| !samples[j].is_empty())
        .collect();
    let mut r = 0u64;
    while !open.is_empty() {
        let mut items = Vec::new();
        for &j in &open {
            for &s in &samples[j] {
                chunks(s, round, &mut items);
            }
        }
        // Each round its own stream.
        run(
            frame,
            &radii,
            &items,
            seed ^ 0x0070_696c_6f74 ^ (r << 40),
            &mut pilot,
        );
        let spent = 2 * round;
        round *= 2;
        r += 1;
        open.retain(|&j| {
            let ss = &samples[j];
            let l: f64 = ss
                .iter()
                .map(|&i| pilot[i].l / pilot[i].n.max(1) as f64)
                .sum();
            let v: f64 = ss.iter().map(|&i| pilot[i].var_of_mean()).sum();
            let noisy = l.is_nan() || l <= 0.0 || v.sqrt() / l > PILOT_REL_SE;
            noisy && spent * (ss.len() as u64) * 8 <= budget.max_paths
        });
    }
    // Paths per camera sample of each pixel: Σ_k var_k / n over K² below (t L)².
    let per_sample: Vec<u64> = samples
        .iter()
        .enumerate()
        .map(|(j, ss)| {
            if ss.is_empty() {
                return 0;
            }
            let l: f64 = ss
                .iter()
                .map(|&i| pilot[i].l / pilot[i].n.max(1) as f64)
                .sum::<f64>()
                / k;
            let v: f64 = ss
                .iter()
                .map(|&i| pilot[i].var_of_mean() * pilot[i].n as f64)
                .sum();
            let cap = (budget.max_paths / ss.len() as u64).max(budget.pilot);
            let n0 = ss
                .iter()
                .map(|&i| pilot[i].n)
                .min()
                .unwrap_or(0)
                .max(budget.pilot);
            let target = if j < budget.fine_pixels {
                budget.fine_rel_se.min(budget.target_rel_se)
            } else {
                budget.target_rel_se
            };
            let t = target * l * k;
            if t.is_nan() || t <= 0.0 {
                // No light found in the whole pilot: as many paths as its pilot had.
                return n0.min(cap);
            }
            let need = (v / (t * t)).ceil();
            if need.is_finite() {
                (need as u64).clamp(budget.pilot, cap)
            } else {
                cap
            }
        })
        .collect();
    let total: u64 = samples
        .iter()
        .zip(&per_sample)
        .map(|(ss, n)| ss.len() as u64 * n)
        .sum();
    log(&format!(
        "manylight: path-traced reference, {} pixels, {:.3e} paths (pilot {:.1} s)",
        pixels.len(),
        total as f64,
        t0.elapsed().as_secs_f64()
    ));
    let mut items = Vec::new();
    for (ss, &n) in samples.iter().zip(&per_sample) {
        for &s in ss {
            chunks(s, n, &mut items);
        }
    }
    let mut sums = vec![Sums::default(); gb.samples.len()];
    run(frame, &radii, &items, seed, &mut sums);
    let mut values = Vec::with_capacity(pixels.len());
    let mut rel_se = Vec::with_capacity(pixels.len());
    for ss in &samples {
        let mut v = [0.0; 3];
        let mut lvar = 0.0;
        for &i in ss {
            let m = sums[i].mean();
            for c in 0..3 {
                v[c] += m[c] / k;
            }
            lvar += sums[i].var_of_mean() / (k * k);
        }
        let l = lum(v);
        values.push(v);
        rel_se.push(if l > 0.0 { lvar.sqrt() / l } else { 0.0 });
    }
    Reference {
        pixels: pixels.to_vec(),
        values,
        rel_se,
        paths: total,
        missed,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss_render::integrators::exact::{shade_subset, translucent_pixels};
    use sss_render::irradiance::IrradianceSettings;
    use sss_render::metrics::subset_pixels;
    use sss_render::scene::{LoadOptions, builtin};

    /// The reference agrees with `exact` (irradiance samples summed against R_d: no probe
    /// rays, no path sampling) on the built-in sphere within its own standard errors and
    /// `exact`'s spacing error, reaches about its targets (the finer one on its first pixels),
    /// and is the same for the same seed and independent across seeds.
    #[test]
    fn agrees_with_exact_and_reaches_its_targets() {
        let mut s = builtin("sphere", &LoadOptions::default()).unwrap();
        s.camera.width = 16;
        s.camera.height = 12;
        s.camera.pixel_samples = 2;
        let frame = Frame::prepare(&s, 7);
        let pixels = subset_pixels(&translucent_pixels(&frame), 8, 3);
        assert_eq!(pixels.len(), 8);
        let budget = Budget {
            pilot: 64,
            target_rel_se: 0.04,
            fine_pixels: 2,
            fine_rel_se: 0.012,
            max_paths: 1 << 20,
        };
        let r = path_reference(&frame, &pixels, budget, 11, &|_| {});
        let ex = shade_subset(
            &frame,
            &IrradianceSettings {
                spacing_mfp: 0.25,
                ..IrradianceSettings::default()
            },
            &pixels,
        )
        .unwrap();
        for (k, e) in ex.iter().enumerate() {
            let (a, b) = (lum(r.values[k]), lum(*e));
            eprintln!(
                "pixel {k}: path {a:.5e} ± {:.4}, exact {b:.5e}, ratio {:.4}",
                r.rel_se[k],
                a / b
            );
            assert!(a > 0.0 && b > 0.0, "pixel {k}: {a} {b}");
            // The pilot sets the paths, so the result lands near (not at) its target.
            let target = if k < 2 { 0.012 } else { 0.04 };
            assert!(
                r.rel_se[k] < 1.5 * target && r.rel_se[k] > 0.5 * target,
                "pixel {k}: relative SE {} for target {target}",
                r.rel_se[k]
            );
            // 4 standard errors, and 1 % for `exact`'s spacing (measured within 0.3 % at
            // this spacing on the sphere).
            let tol = 4.0 * r.rel_se[k] * a + 0.01 * b;
            assert!((a - b).abs() < tol, "pixel {k}: path {a} vs exact {b}");
        }
        assert!(r.resolves(0, 4.0 * 0.012 * 1.5) && !r.resolves(5, 0.04));
        assert!(r.missed > 0.0 && r.missed <= 1e-4 + 1e-12, "{}", r.missed);
        let again = path_reference(&frame, &pixels, budget, 11, &|_| {});
        assert_eq!(again.values, r.values);
        let other = path_reference(&frame, &pixels, budget, 12, &|_| {});
        assert_ne!(other.values, r.values);
        // Two seeds differ by about √2 standard errors: their squared differences in units
        // of the combined SE average 1 (a χ² with 8 degrees of freedom over 8: below 3 with
        // probability > 0.997).
        let chi2: f64 = (0..pixels.len())
            .map(|k| {
                let (a, b) = (lum(r.values[k]), lum(other.values[k]));
                let se2 = (r.rel_se[k] * a).powi(2) + (other.rel_se[k] * b).powi(2);
                (a - b).powi(2) / se2
            })
            .sum::<f64>()
            / pixels.len() as f64;
        assert!(chi2 < 3.0 && chi2 > 0.05, "χ²/n = {chi2}");
    }
}
