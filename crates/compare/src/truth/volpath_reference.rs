//! The reference of each case: `volpath` with enough paths per pixel that its own relative
//! noise is below [`Plan::reference_noise`] (a pilot measures the noise per path), cached in
//! `<cache>/truth_<case>_<key>.bin` with a checksum sidecar like every cache entry (a damaged
//! entry is reported and re-rendered). The key covers the scene text, the case, the
//! resolution, the seed, the plan's noise target and [`TRUTH_VERSION`].

use super::*;

/// The pixels whose eight neighbours are scored too (the rule is shared:
/// `sss_render::metrics::interior_pixels`).
pub(crate) use sss_render::metrics::interior_pixels as interior;

/// Bumped whenever `volpath`'s output or this cache's layout changes.
const TRUTH_VERSION: u32 = 1;

/// First line of a cache entry.
const HEADER: &str = "sss-truth-reference v1";

/// A case's reference image with its per-pixel standard error.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Truth {
    pub width: u32,
    pub height: u32,
    /// The subsurface image.
    pub image: Vec<Rgb>,
    /// Its per-pixel standard error.
    pub se: Vec<Rgb>,
    /// The pixels with translucent coverage, ascending.
    pub translucent: Vec<usize>,
    /// The pixels everything is scored on, ascending: the translucent pixels whose eight
    /// neighbours are translucent too. At the silhouette a pixel's value depends on how the
    /// renderer samples the pixel's area (ours at fixed camera samples, Mitsuba's box filter
    /// over the whole pixel) by more than on the light transport, so peers and methods are
    /// compared away from it.
    pub pixels: Vec<usize>,
    /// Paths per pixel sample.
    pub spp: u32,
    /// Seconds the render took (when it was rendered, maybe in an earlier run).
    pub seconds: f64,
}

impl Truth {
    /// The reference's relative noise: the RMS of its standard error over the translucent
    /// pixels and channels, over its mean there (the floor under any relative RMSE scored
    /// against it, which [`score`] removes).
    pub fn noise(&self) -> f64 {
        relative_noise(&self.image, &self.se, &self.pixels)
    }
}

/// RMS of `se` over `pixels` and channels, over the mean of `image` there (0 for no pixels).
pub(crate) fn relative_noise(image: &[Rgb], se: &[Rgb], pixels: &[usize]) -> f64 {
    let (mut v, mut m) = (0.0, 0.0);
    for &i in pixels {
        for c in 0..3 {
            v += se[i][c] * se[i][c];
            m += image[i][c];
        }
    }
    let n = (3 * pixels.len()) as f64;
    if n > 0.0 && m > 0.0 {
        (v / n).sqrt() / (m / n)
    } else {
        0.0
    }
}

/// The reference of `case` (its scene `scene`, loaded with the fast methods' model), from the
/// cache or rendered.
pub(crate) fn reference(
    ctx: &Context<'_>,
    case: &Case,
    scene: &Scene,
    plan: &Plan,
) -> Result<Truth, Error> {
    let cfg = ctx.config;
    let key = fnv1a64(
        format!(
            "v{TRUTH_VERSION}|{}|{}|{}|{}x{}|{}|{}|{:?}",
            case.text,
            case.name(),
            case.medium.name,
            scene.camera.width,
            scene.camera.height,
            cfg.seed,
            plan.reference_noise,
            plan.reference_spp
        )
        .as_bytes(),
    );
    let dir = cfg.cache_dir();
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
    let path = dir.join(format!("truth_{}_{key:016x}.bin", case.name()));
    let subject = format!("truth {}", case.name());
    if !cfg.fresh {
        let read = match checked::check(&path) {
            Entry::Missing => Ok(None),
            Entry::Corrupt(why) => Err(why),
            Entry::Good(bytes) => decode(&bytes).map(Some),
        };
        if let Some(t) = checked::usable(read, &subject, "reference", ctx.log) {
            (ctx.log)(&format!(
                "{subject}: reference from cache ({} paths per pixel, noise {:.2} %)",
                t.spp,
                100.0 * t.noise()
            ));
            return Ok(t);
        }
    }
    let settings = RenderSettings {
        seed: cfg.seed,
        ..RenderSettings::default()
    };
    let (pilot, most) = plan.reference_spp;
    let run = |spp: u32| -> Result<(RenderOutput, f64), Error> {
        let method = VolPath {
            spp,
            ..VolPath::default()
        };
        let t = Instant::now();
        let out = render(scene, &method, &settings, &NoProgress)
            .map_err(|e| Error(format!("{subject}: reference: {e}")))?;
        Ok((out, t.elapsed().as_secs_f64()))
    };
    let (out, _) = run(pilot)?;
    let se = out.std_error.clone().unwrap_or_default();
    let scored = interior(&out.translucent_pixels(), out.width, out.height);
    let noise = relative_noise(&out.subsurface, &se, &scored);
    // Noise falls as 1/√paths.
    let want = (pilot as f64 * (noise / plan.reference_noise).powi(2)).ceil();
    let spp = if want.is_finite() {
        want.clamp(pilot as f64, most as f64) as u32
    } else {
        most
    };
    (ctx.log)(&format!(
        "{subject}: rendering the volpath reference, {spp} paths per pixel (the pilot's {pilot} \
         gave {:.2} % noise)",
        100.0 * noise
    ));
    let (out, seconds) = run(spp)?;
    let translucent = out.translucent_pixels();
    let truth = Truth {
        width: out.width,
        height: out.height,
        pixels: interior(&translucent, out.width, out.height),
        translucent,
        se: out.std_error.clone().unwrap_or_default(),
        image: out.subsurface,
        spp,
        seconds,
    };
    checked::write_entry(&path, &encode(&truth))?;
    (ctx.log)(&format!(
        "{subject}: reference took {seconds:.1} s, noise {:.2} %",
        100.0 * truth.noise()
    ));
    Ok(truth)
}

/// The cache entry of `t`: a header line with the size, paths and seconds, the translucent
/// pixels' count, then per pixel the image and standard error as little-endian f64, then the
/// translucent pixels' indices as little-endian u32 (the scored ones are derived from them).
pub(crate) fn encode(t: &Truth) -> Vec<u8> {
    let mut b = format!(
        "{HEADER} {} {} {} {:e} {}\n",
        t.width,
        t.height,
        t.spp,
        t.seconds,
        t.translucent.len()
    )
    .into_bytes();
    for (p, s) in t.image.iter().zip(&t.se) {
        for v in p.iter().chain(s) {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    for &i in &t.translucent {
        b.extend_from_slice(&(i as u32).to_le_bytes());
    }
    b
}

/// Reads an entry written by [`encode`]; any inconsistency is an error saying what.
pub(crate) fn decode(bytes: &[u8]) -> Result<Truth, String> {
    let nl = bytes
        .iter()
        .position(|&b| b == b'\n')
        .ok_or("no header line")?;
    let head = std::str::from_utf8(&bytes[..nl]).map_err(|_| "header is not text")?;
    let rest = head.strip_prefix(HEADER).ok_or("unknown header")?;
    let f: Vec<&str> = rest.split_whitespace().collect();
    if f.len() != 5 {
        return Err(format!("{} header fields, 5 expected", f.len()));
    }
    let num = |i: usize| {
        f[i].parse::<f64>()
            .map_err(|_| format!("bad field `{}`", f[i]))
    };
    let (w, h, spp, seconds, n) = (num(0)?, num(1)?, num(2)?, num(3)?, num(4)?);
    let pixels = w * h;
    if !(w >= 1.0 && h >= 1.0 && pixels <= 1e8 && n <= pixels && spp >= 1.0) {
        return Err(format!("bad sizes in `{head}`"));
    }
    let (pixels, n) = (pixels as usize, n as usize);
    let body = &bytes[nl + 1..];
    if body.len() != pixels * 48 + n * 4 {
        return Err(format!(
            "{} bytes after the header, {} expected",
            body.len(),
            pixels * 48 + n * 4
        ));
    }
    let f64_at = |k: usize| {
        let mut a = [0u8; 8];
        a.copy_from_slice(&body[8 * k..8 * k + 8]);
        f64::from_le_bytes(a)
    };
    let mut image = Vec::with_capacity(pixels);
    let mut se = Vec::with_capacity(pixels);
    for p in 0..pixels {
        image.push([0, 1, 2].map(|c| f64_at(6 * p + c)));
        se.push([0, 1, 2].map(|c| f64_at(6 * p + 3 + c)));
    }
    if image.iter().chain(&se).flatten().any(|v| !v.is_finite()) {
        return Err("a value is not finite".into());
    }
    let idx = &body[pixels * 48..];
    let list: Vec<usize> = idx
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize)
        .collect();
    if list.iter().any(|&i| i >= pixels) || list.windows(2).any(|w| w[0] >= w[1]) {
        return Err("translucent pixel list out of range or unsorted".into());
    }
    Ok(Truth {
        width: w as u32,
        height: h as u32,
        image,
        se,
        pixels: interior(&list, w as u32, h as u32),
        translucent: list,
        spp: spp as u32,
        seconds,
    })
}
