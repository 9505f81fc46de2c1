//! The estimators compared ([`Variant`]: ours, the paper's estimator, MDLC and EELC over
//! importance-sampled or uniform points) and how each shades a pixel subset, and the
//! path-traced reference they are scored against.

use super::*;

/// One estimator configuration of the comparison (ours, the paper's, MDLC or EELC, with its
/// settings); not an entry of the method registry, though each runs one.
#[derive(Clone, Copy, Debug)]
pub(super) enum Variant {
    /// Nabata & Iwasaki's.
    Ours(ManyLight),
    /// Multidimensional Lightcuts over fixed points.
    Mdlc(Mdlc),
    /// The error estimation for Lightcuts over fixed points.
    Eelc(Eelc),
}

/// The name of `manylight` in the CSV's `method` column.
pub(super) const OURS: &str = "manylight";

/// The label of manylight with the paper's final estimate (the samples the stopping test saw).
pub(super) const PAPER: &str = "manylight-paper";

impl Variant {
    /// The `method` column: `manylight`, or the baseline and its points (`mdlc-is`,
    /// `eelc-uniform`, …).
    pub(super) fn label(&self) -> &'static str {
        match self {
            Variant::Ours(m) if !m.fresh_final => PAPER,
            Variant::Ours(_) => OURS,
            Variant::Mdlc(m) if m.points.uniform => "mdlc-uniform",
            Variant::Mdlc(_) => "mdlc-is",
            Variant::Eelc(m) if m.points.uniform => "eelc-uniform",
            Variant::Eelc(_) => "eelc-is",
        }
    }

    pub(super) fn eps(&self) -> f64 {
        match self {
            Variant::Ours(m) => m.eps,
            Variant::Mdlc(m) => m.eps,
            Variant::Eelc(m) => m.eps,
        }
    }

    /// Irradiance points per shading point (0 for ours, which has none fixed).
    pub(super) fn points(&self) -> u32 {
        match self {
            Variant::Ours(_) => 0,
            Variant::Mdlc(m) => m.points.irradiance_points,
            Variant::Eelc(m) => m.points.irradiance_points,
        }
    }

    pub(super) fn vpls(&self) -> u32 {
        match self {
            Variant::Ours(m) => m.vpls,
            Variant::Mdlc(m) => m.points.vpls,
            Variant::Eelc(m) => m.points.vpls,
        }
    }

    /// The `selection` column (`-` for the baselines, which select by their own rules).
    pub(super) fn selection(&self) -> &'static str {
        match self {
            Variant::Ours(m) => selection_name(m.selection),
            _ => "-",
        }
    }

    /// The same method on estimator stream `stream` (new points for the baselines).
    pub(super) fn with_stream(self, stream: u64) -> Variant {
        match self {
            Variant::Ours(m) => Variant::Ours(ManyLight { stream, ..m }),
            Variant::Mdlc(m) => Variant::Mdlc(Mdlc {
                points: PointOptions { stream, ..m.points },
                ..m
            }),
            Variant::Eelc(m) => Variant::Eelc(Eelc {
                points: PointOptions { stream, ..m.points },
                ..m
            }),
        }
    }

    pub(super) fn shade_pixels(
        &self,
        frame: &Frame<'_>,
        pixels: &[usize],
    ) -> Result<Vec<PixelResult>, sss_render::Error> {
        match self {
            Variant::Ours(m) => m.shade_pixels(frame, pixels),
            Variant::Mdlc(m) => m.shade_pixels(frame, pixels),
            Variant::Eelc(m) => m.shade_pixels(frame, pixels),
        }
    }
}

/// The method with `vpls` VPLs drawn from one fixed seed (the run's), so that the reference
/// and every run estimate the same integral whatever their own seeds.
pub(super) fn base(ctx: &Context<'_>, vpls: u32) -> ManyLight {
    ManyLight {
        vpls,
        vpl_seed: Some(ctx.config.seed),
        ..ManyLight::default()
    }
}

/// The baselines' points: `n` per shading point, importance-sampled or uniform, with the
/// VPLs of [`base`] (the run's seed, [`VPLS`]).
pub(super) fn points(ctx: &Context<'_>, n: u32, uniform: bool) -> PointOptions {
    PointOptions {
        irradiance_points: n,
        uniform,
        vpls: VPLS,
        vpl_seed: Some(ctx.config.seed),
        ..PointOptions::default()
    }
}

/// MDLC at `eps` over `points`.
pub(super) fn mdlc(eps: f64, points: PointOptions) -> Variant {
    Variant::Mdlc(Mdlc { eps, points })
}

/// EELC at `eps` (α = 95 %) over `points`.
pub(super) fn eelc(eps: f64, points: PointOptions) -> Variant {
    Variant::Eelc(Eelc {
        eps,
        points,
        ..Eelc::default()
    })
}

/// Runs `m` on the subset `pixels` of `scene` with estimator stream `stream`, timed (frame
/// set-up included). The G-buffer is always the run's seed's: every run estimates the same
/// pixel values (the camera samples depend on the frame's seed).
pub(super) fn shade(
    ctx: &Context<'_>,
    scene: &Scene,
    m: &Variant,
    pixels: &[usize],
    stream: u64,
) -> Result<(Vec<PixelResult>, f64), Error> {
    let t0 = Instant::now();
    let frame = Frame::prepare(scene, ctx.config.seed);
    let out = m
        .with_stream(stream)
        .shade_pixels(&frame, pixels)
        .map_err(|e| Error(format!("scene {}: {}: {e}", scene.name, m.label())))?;
    Ok((out, t0.elapsed().as_secs_f64()))
}

/// The subset of `scene`'s translucent pixels and their path-traced reference.
pub(super) fn reference(ctx: &Context<'_>, scene: &Scene, p: &Plan) -> Result<Reference, Error> {
    let seed = ctx.config.seed;
    let frame = Frame::prepare(scene, seed);
    let all = translucent_pixels(&frame);
    let pixels = subset_pixels(&all, p.subset, seed ^ 0x4d4c);
    (ctx.log)(&format!(
        "manylight: {} path-traced reference of {} pixels",
        scene.name,
        pixels.len()
    ));
    // A seed of its own: the reference's paths are independent of every run it scores.
    Ok(path_reference(
        &frame,
        &pixels,
        p.reference,
        seed ^ 0x5245_4600,
        ctx.log,
    ))
}
