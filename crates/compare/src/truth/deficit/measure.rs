//! Image means with their standard errors: what every row of `--deficit` measures, for
//! `volpath` (real transport, all light and single scattering alone) and for the model under
//! `pathtrace` (its integral: nothing discretised, so the model's own image).

use super::*;

/// An image's mean over the scored pixels, per channel, with its standard error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Mean {
    pub mean: Rgb,
    pub se: Rgb,
    /// Samples per pixel sample it took.
    pub spp: u32,
    /// Seconds of its last render.
    pub seconds: f64,
}

/// The mean of `image` over `pixels` and its standard error from the pixels' own (`se`;
/// their paths are independent, so the variances add).
pub(crate) fn mean_over(image: &[Rgb], se: &[Rgb], pixels: &[usize]) -> (Rgb, Rgb) {
    let mut m = [0.0; 3];
    let mut v = [0.0; 3];
    for &p in pixels {
        for c in 0..3 {
            m[c] += image[p][c];
            let s = se.get(p).map_or(0.0, |s| s[c]);
            v[c] += s * s;
        }
    }
    let n = pixels.len().max(1) as f64;
    let mut out = ([0.0; 3], [0.0; 3]);
    for c in 0..3 {
        out.0[c] = m[c] / n;
        out.1[c] = v[c].sqrt() / n;
    }
    out
}

/// The largest relative standard error over the channels whose mean is at least 10⁻³ of the
/// largest channel's (a channel the medium all but absorbs, such as ketchup's blue, would
/// otherwise ask for paths without end); 0 where every mean is 0.
pub(crate) fn relative_se(mean: Rgb, se: Rgb) -> f64 {
    let top = mean.iter().fold(0.0f64, |a, &b| a.max(b));
    (0..3)
        .filter(|&c| top > 0.0 && mean[c] >= 1e-3 * top)
        .map(|c| se[c] / mean[c])
        .fold(0.0, f64::max)
}

/// The samples per pixel that bring a pilot's relative error `rel` at `pilot` samples to
/// `target` (error falls as one over the square root of the samples), within
/// `pilot..=most`.
pub(crate) fn samples_for(pilot: u32, rel: f64, target: f64, most: u32) -> u32 {
    if !(rel > 0.0 && target > 0.0) {
        return pilot;
    }
    let want = (pilot as f64 * (rel / target).powi(2)).ceil();
    if want.is_finite() {
        want.clamp(pilot as f64, most.max(pilot) as f64) as u32
    } else {
        most.max(pilot)
    }
}

/// `scene`'s image mean under the method `make(spp)` builds, over the scored pixels (the
/// translucent pixels whose eight neighbours are translucent), with enough samples that its
/// relative standard error is about `target`: a pilot at `pilot` samples, then the samples
/// it asks for (at most `most`). Also returns the scored pixels.
pub(crate) fn measure(
    scene: &Scene,
    make: &dyn Fn(u32) -> Box<dyn Integrator>,
    (pilot, most): (u32, u32),
    target: f64,
    seed: u64,
) -> Result<(Mean, Vec<usize>), Error> {
    let settings = RenderSettings {
        seed,
        ..RenderSettings::default()
    };
    let run = |spp: u32| -> Result<(Rgb, Rgb, Vec<usize>, f64), Error> {
        let method = make(spp);
        let t = Instant::now();
        let out = render(scene, method.as_ref(), &settings, &NoProgress)
            .map_err(|e| Error(format!("deficit {}: {}: {e}", scene.name, method.name())))?;
        let seconds = t.elapsed().as_secs_f64();
        let pixels = interior(&out.translucent_pixels(), out.width, out.height);
        if pixels.is_empty() {
            return Err(Error(format!(
                "deficit {}: no pixel is inside the translucent silhouette",
                scene.name
            )));
        }
        let se = out.std_error.clone().unwrap_or_default();
        let (m, s) = mean_over(&out.subsurface, &se, &pixels);
        Ok((m, s, pixels, seconds))
    };
    let pilot_run = run(pilot)?;
    let spp = samples_for(pilot, relative_se(pilot_run.0, pilot_run.1), target, most);
    let (m, s, pixels, seconds) = if spp == pilot { pilot_run } else { run(spp)? };
    Ok((
        Mean {
            mean: m,
            se: s,
            spp,
            seconds,
        },
        pixels,
    ))
}

/// `a / b` per channel with its standard error (first order, independent errors); None for a
/// channel where `b` is 0.
pub(crate) fn ratio(a: &Mean, b: &Mean) -> [Option<(f64, f64)>; 3] {
    std::array::from_fn(|c| {
        let (x, y) = (a.mean[c], b.mean[c]);
        (y > 0.0).then(|| {
            // ∂(x/y)/∂x = 1/y, ∂(x/y)/∂y = −x/y².
            let (da, db) = (a.se[c] / y, x * b.se[c] / (y * y));
            (x / y, (da * da + db * db).sqrt())
        })
    })
}
