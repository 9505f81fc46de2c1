//! The physics every integrator shares, written once: what a translucent material needs at
//! shading time ([`TranslucentShading`]), the split between radial models and the full S of
//! the directional dipole ([`ShadingModel`]), the Fresnel-transmitted, textured irradiance
//! entering the surface ([`transmitted_irradiance`]) and the exit weight F_t(η, cos θ_o)/(cπ)
//! ([`TranslucentShading::exit_weight`]), or, for a material with `angular = "albedo"`, the
//! half-space's directional albedo in their place ([`BoundaryWeights`]).
//!
//! Every integrator computes (pbrt 3rd ed. Eq. 11.6–11.7, with c = 1 − 2C₁(η) the
//! normalisation of pbrt's S_ω):
//!
//! L(x_o, ω_o) = F_t(η, cos θ_o)/(cπ) Σ_i R_d(‖x_i − x_o‖) E_i A_i  for radial models, and
//! Σ_i A_i Σ_k S(x_i, ω_k; x_o, ω_o) E_k for the directional dipole,
//!
//! or the integral these sums approximate, with E_i = Σ_k F_t(η, cos θ_k) E_k · texture(x_i).
//! In the radial sum, R_d(‖x_i − x_o‖) stands for
//! [`rd_sample_scene`](TranslucentShading::rd_sample_scene): R_d averaged over sample i's own
//! disk of area A_i near x_o, the point value with its second-order correction farther away,
//! so that the sum estimates the integral pixel by pixel even for peaked profiles.

use crate::lights::Incident;
use glam::DVec3;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{
    Bssrdf, DirectionalAlbedo, DriftAt, EntryDrift, ModelKind, Rgb, SphereDelta, SphereProfile,
    fresnel_normalization, make_model,
};
use sss_scene::{Angular, Scene, Texture, Translucent};
use std::f64::consts::PI;
use std::sync::Arc;

/// A radial model's angular factors, S = W_i(θ_i) R_d(r) W_o(θ_o), as the material asks
/// ([`Angular`]): Fresnel's (every model's own) or the half-space's directional albedo from
/// the random walk ([`DirectionalAlbedo`]).
#[derive(Clone, Debug)]
pub enum BoundaryWeights {
    /// W_i = F_t(η, cos θ_i), W_o = F_t(η, cos θ_o)/(cπ).
    Fresnel {
        /// Relative index of refraction.
        eta: f64,
        /// 1/(cπ).
        norm: f64,
    },
    /// W_i = F_t(η, 1) A(θ_i)/A(0°), W_o = A(θ_o)/(πĀ), per channel.
    Albedo {
        /// Relative index of refraction.
        eta: f64,
        /// A(θ) of the material's medium.
        table: Arc<DirectionalAlbedo>,
    },
}

impl BoundaryWeights {
    /// The weights of material `t` (the directional albedo walked once per medium and process,
    /// [`DirectionalAlbedo::cached`]).
    pub fn of(t: &Translucent) -> Self {
        let eta = t.medium.eta();
        match t.angular {
            Angular::Fresnel => BoundaryWeights::Fresnel {
                eta,
                norm: 1.0 / (fresnel_normalization(eta) * PI),
            },
            Angular::Albedo => BoundaryWeights::Albedo {
                eta,
                table: DirectionalAlbedo::cached(&t.medium),
            },
        }
    }

    /// The irradiance entering the medium at a point with shading normal `n`:
    /// Σ_k W_i(n·ω_k) E_k · `tex` per channel (for Fresnel's weights exactly
    /// [`transmitted_irradiance`]). The texture is multiplied into each packet in place.
    pub fn entering(&self, packets: &mut [Incident], n: DVec3, tex: Rgb) -> Rgb {
        match self {
            BoundaryWeights::Fresnel { eta, .. } => transmitted_irradiance(packets, n, *eta, tex),
            BoundaryWeights::Albedo { eta, table } => {
                let mut e = [0.0; 3];
                for packet in packets {
                    let w = table.entry_weight(n.dot(packet.dir).abs(), *eta);
                    for c in 0..3 {
                        packet.e_cos[c] *= tex[c];
                        e[c] += w[c] * packet.e_cos[c];
                    }
                }
                e
            }
        }
    }

    /// W_i of one packet arriving from direction `dir` at a point with shading normal `n`,
    /// per channel (the factor [`Self::entering`] gives that packet).
    #[inline]
    pub fn entry_weight(&self, n: DVec3, dir: DVec3) -> Rgb {
        match self {
            BoundaryWeights::Fresnel { eta, .. } => [ft_dielectric(n.dot(dir), *eta); 3],
            BoundaryWeights::Albedo { eta, table } => table.entry_weight(n.dot(dir).abs(), *eta),
        }
    }

    /// W_o at a point with shading normal `n` seen from `wo`, per channel.
    pub fn leaving(&self, n: DVec3, wo: DVec3) -> Rgb {
        match self {
            BoundaryWeights::Fresnel { eta, norm } => [ft_dielectric(n.dot(wo), *eta) * norm; 3],
            BoundaryWeights::Albedo { table, .. } => table.exit_weight(n.dot(wo).abs()),
        }
    }

    /// True for Fresnel's weights, the same in every channel.
    pub fn is_fresnel(&self) -> bool {
        matches!(self, BoundaryWeights::Fresnel { .. })
    }
}

/// A material's model, split by what integrators may do with it.
pub enum ShadingModel {
    /// A radial model: S = F_t(η, cos θ_i) R_d(r) F_t(η, cos θ_o)/(cπ), so contributions can be
    /// summed as R_d · E · A (and clustered: trees, many-light methods, separable kernels).
    Radial(Box<dyn Bssrdf>),
    /// The directional dipole (Frisvad et al. 2014): S depends on the incident direction, so
    /// each irradiance sample keeps its incident light packets and S is evaluated per packet.
    Directional(Box<dyn Bssrdf>),
}

impl ShadingModel {
    /// The model, whatever its kind.
    pub fn bssrdf(&self) -> &dyn Bssrdf {
        match self {
            ShadingModel::Radial(m) | ShadingModel::Directional(m) => m.as_ref(),
        }
    }

    /// The model if it is radial.
    pub fn radial(&self) -> Option<&dyn Bssrdf> {
        match self {
            ShadingModel::Radial(m) => Some(m.as_ref()),
            ShadingModel::Directional(_) => None,
        }
    }
}

/// What an integrator needs of one translucent material, in scene units.
pub struct TranslucentShading {
    /// The material's name (for messages).
    pub name: String,
    /// The model kind it was built from.
    pub kind: ModelKind,
    /// The model (built once per material).
    pub model: ShadingModel,
    /// Scene units per millimetre.
    pub units_per_mm: f64,
    /// Relative index of refraction.
    pub eta: f64,
    /// 1/(cπ), the radial models' directional normalisation.
    pub norm: f64,
    /// The pre-scatter texture.
    pub texture: Option<Texture>,
    /// The angular factors of the material's radial model.
    pub weights: BoundaryWeights,
    /// The walk's drift of obliquely entering light (`drift = true`), or `None`.
    pub drift: Option<Arc<EntryDrift>>,
    /// Whether each point has its own ball (`sphere_radius = "local"`,
    /// [`crate::local_radius`]); the model is then the half-space's, and a drifting material's
    /// drift is its balls' ([`sss_bssrdf::BallFamily::with_drift`]), not [`Self::drift`].
    pub local_radius: bool,
    /// `drift = true` with `sphere_radius = "local"`: each pair's ball drifts.
    pub local_drift: bool,
    /// The one ball's radius in mm where the material's profile is a ball's (`sphere_radius` a
    /// number or `"auto"`, [`SphereProfile`]): its profile is tabulated and ends at the ball's
    /// diameter.
    pub ball_mm: Option<f64>,
    /// `unscattered = true`: the split of the light between what goes straight through and
    /// what scatters ([`crate::unscattered::Collision`]), or `None`.
    pub collision: Option<crate::unscattered::Collision>,
    /// The disk-average quadrature of [`rd_sample_scene`](Self::rd_sample_scene).
    disk: DiskRule,
}

/// The model of a translucent material: its kind for its medium
/// ([`sss_bssrdf::make_model`]), reshaped to a ball when the material names a
/// `sphere_radius` ([`SphereProfile`]: the radius converted to mm). The scene loader refuses a
/// sphere radius on the directional dipole and radii that are not finite and positive, the only
/// cases [`SphereProfile::new`] refuses; were one to reach here, the half-space's model is kept.
pub fn material_model(t: &Translucent) -> Box<dyn Bssrdf> {
    let base = make_model(t.model, &t.medium);
    let delta = match t.sphere_radius {
        Some(radius) if t.model != ModelKind::DirectionalDipole => {
            SphereDelta::cached(&t.medium, radius / t.units_per_mm).ok()
        }
        _ => None,
    };
    match delta {
        Some(delta) => Box::new(SphereProfile::with_delta(base, delta)),
        None => base,
    }
}

/// The factors that turn R_d and its first two radial derivatives, per mm, into scene units:
/// 1/u², 1/u³ and 1/u⁴, u the scene units per mm (R_d(r/u)/u² per scene unit², R_d′(r/u)/u³,
/// R_d″(r/u)/u⁴). The one place the scene-unit factor is written: every method's R_d in scene
/// units goes through it.
#[inline]
pub fn scene_unit_factors(u: f64) -> [f64; 3] {
    let s0 = 1.0 / (u * u);
    [s0, s0 / u, s0 / (u * u)]
}

impl TranslucentShading {
    /// Builds the model of a translucent material named `name`.
    pub fn new(name: &str, t: &Translucent) -> Self {
        let bssrdf = material_model(t);
        let eta = t.medium.eta();
        let model = if t.model == ModelKind::DirectionalDipole {
            ShadingModel::Directional(bssrdf)
        } else {
            ShadingModel::Radial(bssrdf)
        };
        let disk = DiskRule::new(model.bssrdf(), &t.medium, t.units_per_mm);
        // The loader refuses `drift` on the directional dipole; the walk refuses only radii
        // the loader refuses too.
        let local = t.local_radius && t.model != ModelKind::DirectionalDipole;
        let drift = if t.drift && !local && t.model != ModelKind::DirectionalDipole {
            EntryDrift::cached(&t.medium, t.sphere_radius.map(|r| r / t.units_per_mm)).ok()
        } else {
            None
        };
        TranslucentShading {
            name: name.to_string(),
            kind: t.model,
            model,
            units_per_mm: t.units_per_mm,
            eta,
            norm: 1.0 / (fresnel_normalization(eta) * PI),
            texture: t.texture.clone(),
            weights: BoundaryWeights::of(t),
            drift,
            local_radius: local,
            local_drift: local && t.drift,
            ball_mm: t
                .sphere_radius
                .filter(|_| !local && t.model != ModelKind::DirectionalDipole)
                .map(|r| r / t.units_per_mm),
            collision: crate::unscattered::Collision::of(t),
            disk,
        }
    }

    /// The model, whatever its kind.
    #[inline]
    pub fn bssrdf(&self) -> &dyn Bssrdf {
        self.model.bssrdf()
    }

    /// True for the directional dipole (S needs incident directions).
    #[inline]
    pub fn directional(&self) -> bool {
        matches!(self.model, ShadingModel::Directional(_))
    }

    /// The radial model, or an error naming the material and its model for methods that sum
    /// R_d · E · A (trees, many-light, separable kernels), which the directional dipole is not.
    pub fn radial(&self, method: &str) -> Result<&dyn Bssrdf, crate::Error> {
        self.model.radial().ok_or_else(|| {
            crate::Error::Unsupported(format!(
                "material `{}`: method {method} needs a radial model, but `{}` is the directional \
                 dipole, whose S depends on the incident direction (use exact or pathtrace, or \
                 another model)",
                self.name,
                self.kind.name()
            ))
        })
    }

    /// R_d at scene-unit distance `r`, per scene unit² (R_d(r/u)/u², u = units per mm).
    #[inline]
    pub fn rd_scene(&self, r: f64) -> Rgb {
        let u = self.units_per_mm;
        let rd = self.bssrdf().rd_rgb(r / u);
        let [s, _, _] = scene_unit_factors(u);
        [rd[0] * s, rd[1] * s, rd[2] * s]
    }

    /// R_d and its first two radial derivatives per channel at scene-unit distance `r`, in
    /// scene units (R_d(r/u)/u², R_d′(r/u)/u³, R_d″(r/u)/u⁴), from
    /// [`sss_bssrdf::Bssrdf::rd_derivatives`]: the local expansions of `dual-tree-fmm`.
    pub fn rd_derivatives_scene(&self, r: f64) -> [[f64; 3]; 3] {
        let u = self.units_per_mm;
        let m = self.bssrdf();
        let x = r / u;
        let [s0, s1, s2] = scene_unit_factors(u);
        std::array::from_fn(|c| {
            let (v, d1, d2) = m.rd_derivatives(c, x);
            [v * s0, d1 * s1, d2 * s2]
        })
    }
    /// The point sum Σ_i R_d(‖x − x_i‖) E_i A_i (Jensen & Buhler 2002, Eq. 2, with each
    /// sample's R_d averaged over its disk by [`rd_sample_scene`](Self::rd_sample_scene)) of
    /// irradiance samples given as (position x_i, area A_i, irradiance E_i), added to `acc`
    /// (before the exit weight). `exact` sums every sample with it, and the trees every sample
    /// of a leaf they do not accept as a cluster, so both compute the same sum.
    #[inline]
    pub fn add_point_sum(
        &self,
        acc: &mut Rgb,
        x: DVec3,
        points: impl IntoIterator<Item = (DVec3, f64, Rgb)>,
    ) {
        for (position, area, e) in points {
            let rd = self.rd_sample_scene((position - x).length(), area);
            for c in 0..3 {
                acc[c] += rd[c] * e[c] * area;
            }
        }
    }

    /// [`add_point_sum`](Self::add_point_sum) with each pair's own ball
    /// ([`crate::local_radius`]): the sample's R_d ([`rd_sample_scene`](Self::rd_sample_scene))
    /// reshaped by `family` to the ball of each point's last field, the pair's radius √(R_x R_i)
    /// in mm (NaN: the half-space's profile).
    pub fn add_point_sum_local(
        &self,
        acc: &mut Rgb,
        x: DVec3,
        family: &sss_bssrdf::BallFamily,
        points: impl IntoIterator<Item = (DVec3, f64, Rgb, f64)>,
    ) {
        for (position, area, e, radius) in points {
            let v = self.rd_sample_ball((position - x).length(), area, family, radius);
            for c in 0..3 {
                acc[c] += v[c] * e[c] * area;
            }
        }
    }

    /// [`rd_sample_scene`](Self::rd_sample_scene) of the profile `family` gives the ball of
    /// `radius` mm (NaN: the half-space's profile, unchanged), per scene unit²: one pair's
    /// term of [`add_point_sum_local`](Self::add_point_sum_local) (a tree node's value is
    /// [`rd_cluster_ball`](Self::rd_cluster_ball)). Near the shading point it is the disk's
    /// average of the ball's profile max(0, R_d + Δ); far, the corrected point value of R_d
    /// with Δ at r added. (Δ at r added to the disk's average of R_d, a point value beside the
    /// average of a peaked profile, took up to four fifths of a coarse sample's own term away,
    /// and was 5 % off two disk radii away.)
    #[inline]
    pub fn rd_sample_ball(
        &self,
        r: f64,
        area: f64,
        family: &sss_bssrdf::BallFamily,
        radius: f64,
    ) -> Rgb {
        if !(radius > 0.0) || radius.is_nan() {
            return self.rd_sample_scene(r, area);
        }
        self.rd_sample_with(r, area, self.ball_shape(family, radius))
    }

    /// The ball of `radius` mm's profile from the half-space's, in scene units:
    /// (r, R_d(r)) ↦ `family`'s reshaped value ([`sss_bssrdf::BallFamily::reshape_rgb`]).
    fn ball_shape<'f>(
        &self,
        family: &'f sss_bssrdf::BallFamily,
        radius: f64,
    ) -> impl Fn(f64, Rgb) -> Rgb + 'f {
        let u = self.units_per_mm;
        let [s, _, _] = scene_unit_factors(u);
        move |x, rd| {
            family
                .reshape_rgb(x / u, radius, rd.map(|v| v / s))
                .map(|v| v * s)
        }
    }

    /// A tree node's value under the ball of `radius` mm (NaN: the half-space's profile): the
    /// node's [`rd_sample_scene`](Self::rd_sample_scene) over its area with the ball's
    /// difference at the node's distance added. A node stands for samples spread over its
    /// disk, each summed far from its own (the trees accept a node only where it subtends a
    /// small solid angle), so what it approximates is the sum of their far values, not the
    /// disk's average of the reshaped profile that a sample near the shading point takes
    /// ([`rd_sample_ball`](Self::rd_sample_ball)): on a 10 mm ketchup sphere under the
    /// environment, that average over the nodes' disks put the trees 1.1 % below `exact` in
    /// the red, this value 0.1 %.
    #[inline]
    pub fn rd_cluster_ball(
        &self,
        r: f64,
        area: f64,
        family: &sss_bssrdf::BallFamily,
        radius: f64,
    ) -> Rgb {
        self.ball_shape(family, radius)(r.abs(), self.rd_sample_scene(r, area))
    }

    /// The far branch of [`rd_sample_scene`](Self::rd_sample_scene) with its first two
    /// radial derivatives, per channel in scene units: D = R_d (1 + t), D′ = R_d′ (1 + t) +
    /// R_d t′, D″ = R_d″ (1 + t) + 2 R_d′ t′ + R_d t″, with t = a²/8 · ∇²R_d/R_d the disk's
    /// correction and R_d′, R_d″ from [`sss_bssrdf::Bssrdf::rd_derivatives`]; t′ and t″ by
    /// central differences one step of the correction's table apart (the table is linear
    /// between its steps, so a narrower difference would see its kinks).
    ///
    /// Where `rd_sample_scene` takes its near branch (the disk average by quadrature): the
    /// quadrature [`disk_average`](Self::disk_average) at r and its central differences
    /// [`DISK_NEAR_STEP`] disk radii apart (the quadrature is a smooth function of r outside
    /// the disk, its rule's nodes moving with r), for r ≥ [`DISK_NEAR_MIN_RATIO`] disk radii
    /// only; `None` nearer (the average's derivatives are singular at the disk's edge, r =
    /// a), so a caller expanding a sample about another point falls back to summing it. The
    /// caller's expansion must also stay clear of the edge: its error grows as the distance
    /// from the expansion's points to the disk's edge shrinks.
    pub fn rd_sample_derivatives_scene(&self, r: f64, area: f64) -> Option<[[f64; 3]; 3]> {
        if !(area > 0.0 && area.is_finite() && r.is_finite() && r > 0.0) {
            return None;
        }
        let a2 = area / PI;
        let a = a2.sqrt();
        if r < DISK_FAR_RATIO * a {
            return self.near_derivatives(r, a);
        }
        let u = self.units_per_mm;
        let x = r / u;
        let scale = a2 / (u * u) * 0.125;
        let t = |x: f64| self.disk.laplacian(x).map(|l| scale * l);
        let t0 = t(x);
        if t0.iter().any(|t| !(t.abs() <= DISK_FAR_MAX_CORRECTION)) {
            return self.near_derivatives(r, a);
        }
        let h = x * (1.0 - (-1.0 / self.disk.per_ln).exp());
        let (tp, tm) = (t(x + h), t(x - h));
        let m = self.bssrdf();
        let [s0, s1, s2] = scene_unit_factors(u);
        let out: [[f64; 3]; 3] = std::array::from_fn(|c| {
            let (v, d1, d2) = m.rd_derivatives(c, x);
            let t1 = (tp[c] - tm[c]) / (2.0 * h);
            let t2 = (tp[c] - 2.0 * t0[c] + tm[c]) / (h * h);
            let k = 1.0 + t0[c];
            [
                v * k * s0,
                (d1 * k + v * t1) * s1,
                (d2 * k + 2.0 * d1 * t1 + v * t2) * s2,
            ]
        });
        out.iter().flatten().all(|v| v.is_finite()).then_some(out)
    }

    /// [`rd_sample_derivatives_scene`](Self::rd_sample_derivatives_scene)'s near branch: the
    /// quadrature and its central differences.
    fn near_derivatives(&self, r: f64, a: f64) -> Option<[[f64; 3]; 3]> {
        if !(r >= DISK_NEAR_MIN_RATIO * a) {
            return None;
        }
        let h = DISK_NEAR_STEP * a;
        let (lo, mid, hi) = (
            self.disk_average(r - h, a),
            self.disk_average(r, a),
            self.disk_average(r + h, a),
        );
        let out: [[f64; 3]; 3] = std::array::from_fn(|c| {
            [
                mid[c],
                (hi[c] - lo[c]) / (2.0 * h),
                (hi[c] - 2.0 * mid[c] + lo[c]) / (h * h),
            ]
        });
        out.iter().flatten().all(|v| v.is_finite()).then_some(out)
    }

    /// The R_d an irradiance sample of area `area` (scene units²) contributes per unit area at
    /// scene-unit distance `r` from the shading point x_o. The sample stands for a patch of the
    /// surface, so this is R_d averaged over a disk of that area (radius a = √(A/π)) centred
    /// at distance r from x_o, in the tangent plane (the planar approximation: the curvature of
    /// the surface over one sample's disk is neglected, as the models neglect it everywhere);
    /// far from x_o, the point value R_d(r) with its second-order correction. Every point-sum method (`exact`, the tree leaves)
    /// calls this, so they approximate the same sum.
    ///
    /// - **Near** (r < [`DISK_FAR_RATIO`]·a, or wherever the far branch's correction would
    ///   exceed [`DISK_FAR_MAX_CORRECTION`]): the disk average by a fixed quadrature of at most
    ///   [`DISK_EVALUATIONS_MAX`] evaluations of R_d, written in polar coordinates around x_o
    ///   so that peaked profiles (R_d → ∞ as r → 0) are integrated exactly where they peak;
    ///   see [`disk_average`](Self::disk_average). Within 0.3 % of a fine brute-force
    ///   quadrature for every model and r/a for disks of radius up to one reduced mean free
    ///   path, 2 % up to four (`disk_average_matches_brute_force`).
    /// - **Far**: the mean-value expansion of a smooth function over a disk,
    ///   R_d(r) (1 + (a²/8) ∇²R_d(r)/R_d(r)) + O(a⁴ ∇⁴R_d) (Pólya & Szegő; the Laplacian of a
    ///   radial profile is R_d'' + R_d'/r), with ∇²R_d/R_d from a per-material table
    ///   (built with the model: ∇²R_d/R_d by central differences on a geometric grid of 32
    ///   radii per decade, interpolated in log r): one R_d evaluation and a table look-up.
    ///   The correction matters even far away: for an exponential tail e^{−σr} it tends to (σa)²/8, not to 0, so the bare point
    ///   value would be off by a constant factor (up to 13 % for ketchup at a = ℓ/2). Taken
    ///   only where the correction is at most [`DISK_FAR_MAX_CORRECTION`], which bounds the
    ///   neglected fourth-order term; within 1.5 % of the brute force for every model and medium
    ///   tested (`far_branch_is_within_its_tolerance`).
    ///
    /// `area` ≤ 0 or not finite gives the point value; the result is finite and non-negative
    /// for every r ≥ 0 (including r = 0) and every area.
    #[inline]
    pub fn rd_sample_scene(&self, r: f64, area: f64) -> Rgb {
        self.rd_sample_with(r, area, |_, rd| rd)
    }

    /// [`rd_sample_scene`](Self::rd_sample_scene) of the profile `shape(s, R_d(s))` (s and R_d
    /// in scene units): the far branch reshapes the corrected point value at r, the near branch
    /// averages the reshaped profile over the disk ([`disk_average_of`](Self::disk_average_of)),
    /// so that a reshaping that is small beside R_d's peak stays small beside the disk's
    /// average of it.
    #[inline]
    fn rd_sample_with(&self, r: f64, area: f64, shape: impl Fn(f64, Rgb) -> Rgb) -> Rgb {
        let r = if r.is_finite() { r.abs() } else { r };
        if !(area > 0.0 && area.is_finite() && r.is_finite()) {
            return shape(r, self.rd_scene(r));
        }
        let a2 = area / PI;
        let a = a2.sqrt();
        if r >= DISK_FAR_RATIO * a {
            let lap = self.disk.laplacian(r / self.units_per_mm);
            let u2 = self.units_per_mm * self.units_per_mm;
            // a²/8 · ∇²R_d / R_d, with ∇² per mm² converted to per scene unit².
            let t = lap.map(|l| a2 / u2 * l * 0.125);
            if t.iter().all(|t| t.abs() <= DISK_FAR_MAX_CORRECTION) {
                let rd = self.rd_scene(r);
                return shape(r, [0, 1, 2].map(|c| rd[c] * (1.0 + t[c])));
            }
        }
        // A disk whose nearest point is so far that R_d has underflowed to 0 there averages to
        // 0 (the profiles are non-increasing in r): one evaluation instead of a quadrature,
        // which matters for huge disks (coarse samples on huge objects).
        // (Tested in mm: the conversion to scene units could turn 0 into 0·∞ for absurd units.)
        if r > a
            && self
                .bssrdf()
                .rd_rgb((r - a) / self.units_per_mm)
                .iter()
                .all(|&v| v == 0.0)
        {
            return shape(r, [0.0; 3]);
        }
        self.disk_average_of(r, a, shape)
    }

    /// R_d averaged over a disk of radius `a` centred at distance `r` from the shading point
    /// (scene units, r ≥ 0, a > 0), always by quadrature (the near branch of
    /// [`rd_sample_scene`](Self::rd_sample_scene)).
    ///
    /// The mean is written in polar coordinates around the shading point x_o (not around the
    /// disk's centre, where a peaked profile would sit off-centre): (1/πa²) ∫ 2π s φ(s) R_d(s)
    /// ds, with φ(s) the fraction of the circle of radius s around x_o inside the disk (1 for
    /// s ≤ a − r; arccos((s² + r² − a²)/(2sr))/π on |a − r| < s < a + r, the circle–circle
    /// intersection angle). The inner part ∫₀^{a−r} is Gauss–Legendre on panels shrinking by 4
    /// towards s = 0; the ring part Gauss–Legendre in τ after s = m − h cos τ
    /// (m = max(a, r), h = min(a, r)), which removes φ's square-root ends. At most
    /// [`DISK_EVALUATIONS_MAX`] evaluations of R_d.
    pub fn disk_average(&self, r: f64, a: f64) -> Rgb {
        self.disk_average_of(r, a, |_, rd| rd)
    }

    /// [`disk_average`](Self::disk_average) of the profile `shape(s, R_d(s))` (s and R_d in
    /// scene units), on the same nodes.
    fn disk_average_of(&self, r: f64, a: f64, shape: impl Fn(f64, Rgb) -> Rgb) -> Rgb {
        let rule = &self.disk;
        let mut acc = [0.0; 3];
        let mut add = |s: f64, w: f64| {
            let rd = shape(s, self.rd_scene(s));
            for c in 0..3 {
                acc[c] += w * s * rd[c];
            }
        };
        // Inside: circles of radius s ≤ a − r around x_o lie wholly in the disk, so this part
        // is ∫₀^{a−r} s R_d(s) ds, on panels shrinking by 4 towards s = 0 (down to a quarter of
        // the smallest mean free path, at most DISK_PANELS_MAX of them) where peaked profiles
        // vary fastest.
        if r < a {
            let b = a - r;
            let mut hi = b;
            let panels = disk_panels(b, rule.panel_floor);
            for k in 0..panels {
                let lo = if k + 1 == panels { 0.0 } else { 0.25 * hi };
                let (half, mid) = (0.5 * (hi - lo), 0.5 * (hi + lo));
                for &(x, w) in &rule.inner {
                    add(mid + half * x, w * half);
                }
                hi = lo;
            }
        }
        // The ring |a − r| < s < a + r, where a fraction φ(s) of the circle of radius s lies
        // in the disk: φ = arccos((s² + r² − a²)/(2sr))/π. With s = m − h cos τ, τ ∈ [0, π]
        // (m = max(a, r), h = min(a, r)), ds = h sin τ dτ removes the square-root behaviour of
        // φ at both ends, so Gauss–Legendre in τ converges fast.
        let (m, h) = if r < a { (a, r) } else { (r, a) };
        if h > 0.0 {
            for &(cos_t, w) in &rule.ring {
                let sin2 = (1.0 - cos_t * cos_t).max(0.0);
                let s = m - h * cos_t;
                if !(s > 0.0) {
                    continue;
                }
                // (s² + r² − a²)/(2sr), expanded so that it stays accurate as r or a → 0.
                let x = if r < a {
                    (r * (1.0 + cos_t * cos_t) - 2.0 * a * cos_t) / (2.0 * s)
                } else {
                    1.0 - a * a * sin2 / (2.0 * s * r)
                };
                let phi = x.clamp(-1.0, 1.0).acos() / PI;
                add(s, w * h * sin2.sqrt() * phi);
            }
        }
        // Mean = (2π/(πa²)) · (the two parts).
        let scale = 2.0 / (a * a);
        let out = acc.map(|v| v * scale);
        if out.iter().all(|v| v.is_finite()) {
            out.map(|v| v.max(0.0))
        } else {
            shape(r, self.rd_scene(r))
        }
    }

    /// The Fresnel exit weight F_t(η, n·ω_o)/(cπ) of a radial model at a point with shading
    /// normal `n` seen from direction `wo`: one number for every channel, as the methods that
    /// bound and cluster by it need (the many-light ones; they refuse
    /// [`BoundaryWeights::Albedo`], [`Self::scalar_weights`]).
    #[inline]
    pub fn exit_weight(&self, n: DVec3, wo: DVec3) -> f64 {
        ft_dielectric(n.dot(wo), self.eta) * self.norm
    }

    /// The material's exit weight W_o per channel ([`BoundaryWeights::leaving`]): equal to
    /// [`Self::exit_weight`] in every channel for Fresnel's weights.
    #[inline]
    pub fn exit_weights(&self, n: DVec3, wo: DVec3) -> Rgb {
        self.weights.leaving(n, wo)
    }

    /// Ok when the material's weights are Fresnel's (one number per point); otherwise an
    /// error naming the material and `method`, which needs them so.
    pub fn scalar_weights(&self, method: &str) -> Result<(), crate::Error> {
        if self.weights.is_fresnel() {
            Ok(())
        } else {
            Err(crate::Error::Unsupported(format!(
                "material `{}`: method {method} bounds and clusters with Fresnel's angular \
                 factors, one number per point; `angular = \"albedo\"` weighs each channel \
                 (use exact, pathtrace, the trees or separable)",
                self.name
            )))
        }
    }

    /// The irradiance entering at `xi` (shading normal `ni`) that leaves `xo` (shading
    /// normal `no`) towards `wo`: Σ_k W_i(θ_k) E_k, each packet times the drift's reciprocal
    /// factor 1 + k(r, θ_k) cos φ_k + k(r, θ_o) cos φ_o ([`EntryDrift::factor`]): φ_k
    /// between the packet's direction of travel along the surface at `xi` and the direction
    /// from `xi` towards `xo` along it, φ_o between the view ray's direction of travel (−`wo`)
    /// along the surface at `xo` and the direction from `xo` towards `xi` along it, r =
    /// |xo − xi| in mm. The packets carry the texture already. Without drift Σ_k W_i(θ_k) E_k.
    pub fn entering_towards(
        &self,
        packets: &[Incident],
        xi: (DVec3, DVec3),
        xo: (DVec3, DVec3, DVec3),
    ) -> Rgb {
        self.entering_towards_with(self.drift.as_deref(), packets, xi, xo)
    }

    /// [`entering_towards`](Self::entering_towards) with the drift `drift` (a pair's own
    /// ball's, [`sss_bssrdf::BallFamily::drift`]) instead of the material's.
    pub fn entering_towards_with(
        &self,
        drift: Option<&EntryDrift>,
        packets: &[Incident],
        (xi, ni): (DVec3, DVec3),
        (xo, no, wo): (DVec3, DVec3, DVec3),
    ) -> Rgb {
        // The drift read at this pair's chord, and the exit's k and azimuth, once per pair.
        let exit = drift.map(|drift| {
            let at = drift.at((xo - xi).length() / self.units_per_mm);
            (
                at,
                at.ks(no.dot(wo).abs()),
                along_surface_cos(-wo, xi - xo, no),
            )
        });
        let mut e = [0.0; 3];
        for packet in packets {
            let w = self.weights.entry_weight(ni, packet.dir);
            let m = match &exit {
                Some((at, ko, cos_phi_o)) => {
                    let cos_phi_i = along_surface_cos(-packet.dir, xo - xi, ni);
                    DriftAt::combine(at.ks(ni.dot(packet.dir).abs()), cos_phi_i, *ko, *cos_phi_o)
                }
                None => [1.0; 3],
            };
            for c in 0..3 {
                e[c] += w[c] * m[c] * packet.e_cos[c];
            }
        }
        e
    }

    /// Ok unless the material gives each point its own ball (`sphere_radius = "local"`),
    /// which only `exact`, `single-tree` and `dual-tree-fmm` read; otherwise an error naming
    /// the material and `method`.
    pub fn one_profile(&self, method: &str) -> Result<(), crate::Error> {
        if self.local_radius {
            Err(crate::Error::Unsupported(format!(
                "material `{}`: method {method} takes one profile per material; \
                 `sphere_radius = \"local\"` gives each pair of points its own ball (use \
                 exact, single-tree or dual-tree-fmm)",
                self.name
            )))
        } else {
            Ok(())
        }
    }

    /// Ok when the material neither drifts nor gives each point its own ball
    /// (`sphere_radius = "local"`); otherwise an error naming the material and `method`, which
    /// sums one irradiance per point with one profile (only `exact` and `pathtrace` keep each
    /// packet's direction; only `exact` and the point-sum trees each point's radius).
    pub fn no_drift(&self, method: &str) -> Result<(), crate::Error> {
        self.one_profile(method)?;
        self.one_irradiance(method)
    }

    /// Ok unless the material drifts (`drift = true`, with one ball or each point's own);
    /// otherwise an error naming the material and `method`, which sums one irradiance per
    /// point (only `exact`, and `pathtrace` with one profile, keep each packet's direction).
    pub fn one_irradiance(&self, method: &str) -> Result<(), crate::Error> {
        if self.drift.is_none() && !self.local_drift {
            Ok(())
        } else {
            let instead = if self.local_radius {
                "exact"
            } else {
                "exact or pathtrace"
            };
            Err(crate::Error::Unsupported(format!(
                "material `{}`: method {method} sums one irradiance per point; `drift = true` \
                 needs each light's direction at each point (use {instead})",
                self.name
            )))
        }
    }

    /// The pre-scatter texture at `p` (1 without a texture).
    #[inline]
    pub fn texture_at(&self, p: DVec3) -> Rgb {
        self.texture.as_ref().map_or([1.0; 3], |t| t.eval(p))
    }
}

/// The cosine between the components of `a` and `b` along the surface of unit normal `n`
/// (their projections on its tangent plane); 0 when either has none (less than 10⁻⁹ of its
/// length, whatever the scene's units).
fn along_surface_cos(a: DVec3, b: DVec3, n: DVec3) -> f64 {
    let pa = a - n * a.dot(n);
    let pb = b - n * b.dot(n);
    let (la, lb) = (pa.length(), pb.length());
    if la > 1e-9 * a.length() && lb > 1e-9 * b.length() && (la * lb).is_finite() {
        (pa.dot(pb) / (la * lb)).clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

/// The irradiance transmitted into the medium at a point with shading normal `n`:
/// Σ_k F_t(η, n·ω_k) E_k · `tex`. The texture is multiplied into each packet in place (the
/// directional dipole keeps the textured packets), then the Fresnel factor is applied.
pub fn transmitted_irradiance(packets: &mut [Incident], n: DVec3, eta: f64, tex: Rgb) -> Rgb {
    let mut e = [0.0; 3];
    for packet in packets {
        let ft = ft_dielectric(n.dot(packet.dir), eta);
        for c in 0..3 {
            packet.e_cos[c] *= tex[c];
            e[c] += ft * packet.e_cos[c];
        }
    }
    e
}

/// The shading data of every material that some translucent object in `objects` uses (None
/// for the others): models and tables are built only for what the image shows.
pub fn shading_for(scene: &Scene, objects: &[u32]) -> Vec<Option<TranslucentShading>> {
    let mut out: Vec<Option<TranslucentShading>> =
        (0..scene.materials.len()).map(|_| None).collect();
    for &o in objects {
        let m = scene.objects[o as usize].material;
        if out[m].is_none()
            && let Some(t) = scene.translucent(o as usize)
        {
            out[m] = Some(TranslucentShading::new(&scene.materials[m].name, t));
        }
    }
    out
}

/// At and beyond this many disk radii from the shading point,
/// [`TranslucentShading::rd_sample_scene`] may use the far branch (point value with the
/// second-order correction), when that correction is small ([`DISK_FAR_MAX_CORRECTION`]).
pub const DISK_FAR_RATIO: f64 = 3.0;

/// The far branch of [`TranslucentShading::rd_sample_scene`] is taken only where the relative
/// second-order correction (a²/8)|∇²R_d/R_d| is at most this in every channel; larger
/// corrections (coarse irradiance samples on steep profiles) mean that the neglected
/// fourth-order term may not be small, and the disk is integrated instead.
pub const DISK_FAR_MAX_CORRECTION: f64 = 0.125;

/// [`TranslucentShading::rd_sample_derivatives_scene`] differentiates the near branch's
/// quadrature only at and beyond this many disk radii (its derivatives are singular at the
/// disk's edge, one radius away).
pub const DISK_NEAR_MIN_RATIO: f64 = 1.25;

/// The step, in disk radii, of the near branch's central differences (at most a fifth of the
/// distance to the disk's edge at [`DISK_NEAR_MIN_RATIO`]).
pub const DISK_NEAR_STEP: f64 = 0.05;

/// Gauss–Legendre points per panel of the inner part of the disk average.
const DISK_INNER_POINTS: usize = 6;
/// Gauss–Legendre points in τ for the ring part of the disk average.
const DISK_RING_POINTS: usize = 16;
/// At most this many panels for the inner part.
const DISK_PANELS_MAX: usize = 8;

/// The most R_d evaluations one disk average makes.
pub const DISK_EVALUATIONS_MAX: usize = DISK_PANELS_MAX * DISK_INNER_POINTS + DISK_RING_POINTS;

/// Panels for ∫₀^b: from b down by factors of 4 until the innermost edge is at most
/// `floor` (at least 3 panels, at most [`DISK_PANELS_MAX`]).
fn disk_panels(b: f64, floor: f64) -> usize {
    let mut panels = 3;
    let mut edge = b / 16.0;
    while edge > floor && panels < DISK_PANELS_MAX {
        edge *= 0.25;
        panels += 1;
    }
    panels
}

/// The fixed quadrature behind [`TranslucentShading::disk_average`] and the Laplacian table of
/// the far branch, built once per material.
///
/// The mean of R_d over a disk D of radius a whose centre is at distance r from x_o is written
/// in polar coordinates around x_o (not around the disk's centre, where a peaked profile would
/// sit off-centre and anywhere): (1/πa²) ∫ 2π s φ(s) R_d(s) ds, with φ(s) the fraction of the
/// circle of radius s around x_o that lies in D (1 for s ≤ a − r; arccos((s² + r² − a²)/(2sr))/π
/// on |a − r| < s < a + r, the circle–circle intersection angle). The inner part is graded
/// Gauss–Legendre towards s = 0, the ring part Gauss–Legendre after s = m − h cos τ.
///
/// The table holds ∇²R_d/R_d = (R_d'' + R_d'/r)/R_d per channel (1/mm²), by central
/// differences (step 10⁻³ r) on a geometric grid of [`LAPLACIAN_PER_DECADE`] radii per decade
/// from 10⁻³ to 10⁴ smallest mean free paths, interpolated linearly in log r; past the radius
/// holding all but 10⁻⁵ of a channel's reflectance (where R_d is negligible and photon beam
/// diffusion's spline wiggles about 0) and wherever R_d vanishes the last value is carried
/// on, and beyond the grid the ends are held.
#[derive(Clone, Debug)]
struct DiskRule {
    /// Nodes on [−1, 1] and weights of one inner panel.
    inner: Vec<(f64, f64)>,
    /// (cos τ, weight) of the ring rule on τ ∈ [0, π].
    ring: Vec<(f64, f64)>,
    /// Innermost panel edge target (scene units): a quarter of the smallest mean free path.
    panel_floor: f64,
    /// ln of the table's first radius (mm).
    ln_r0: f64,
    /// Table entries per unit of ln r.
    per_ln: f64,
    /// ∇²R_d/R_d per channel at each grid radius (1/mm²).
    laplacian: Vec<Rgb>,
}

/// Radii per decade of the Laplacian table of [`DiskRule`].
const LAPLACIAN_PER_DECADE: f64 = 32.0;

impl DiskRule {
    fn new(model: &dyn Bssrdf, medium: &sss_bssrdf::Medium, units_per_mm: f64) -> Self {
        let (x, w) = sss_bssrdf::quadrature::gauss_legendre(DISK_INNER_POINTS);
        let inner = x.iter().copied().zip(w.iter().copied()).collect();
        let (x, w) = sss_bssrdf::quadrature::gauss_legendre(DISK_RING_POINTS);
        let ring = x
            .iter()
            .zip(w)
            .map(|(&x, &w)| ((0.5 * PI * (1.0 + x)).cos(), 0.5 * PI * w))
            .collect();
        let mfp_mm = (0..3)
            .map(|c| 1.0 / medium.sigma_t(c))
            .filter(|v| v.is_finite() && *v > 0.0)
            .fold(f64::INFINITY, f64::min);
        let mfp_mm = if mfp_mm.is_finite() { mfp_mm } else { 1.0 };
        let u = if units_per_mm.is_finite() && units_per_mm > 0.0 {
            units_per_mm
        } else {
            1.0
        };
        let r0 = 1e-3 * mfp_mm;
        let n = (7.0 * LAPLACIAN_PER_DECADE) as usize + 1;
        let per_ln = LAPLACIAN_PER_DECADE / std::f64::consts::LN_10;
        let mut laplacian = Vec::with_capacity(n);
        // Past the radius holding all but 10⁻⁵ of a channel's reflectance its R_d is negligible
        // and, for photon beam diffusion, a spline that wiggles about its clamp at 0: the
        // value there is frozen.
        let cut: Rgb = [0, 1, 2].map(|c| {
            let v = model.radius_for_energy(c, 1.0 - 1e-5);
            if v.is_finite() && v > 0.0 {
                v
            } else {
                f64::INFINITY
            }
        });
        let mut last = [0.0; 3];
        for k in 0..n {
            let r = r0 * (k as f64 / per_ln).exp();
            let h = 1e-3 * r;
            let (f0, fp, fm) = (model.rd_rgb(r), model.rd_rgb(r + h), model.rd_rgb(r - h));
            for c in 0..3 {
                let d2 = (fp[c] - 2.0 * f0[c] + fm[c]) / (h * h);
                let d1 = (fp[c] - fm[c]) / (2.0 * h);
                let l = (d2 + d1 / r) / f0[c];
                if r <= cut[c] && f0[c] > 1e-250 && fp[c] > 0.0 && fm[c] > 0.0 && l.is_finite() {
                    last[c] = l;
                }
            }
            laplacian.push(last);
        }
        DiskRule {
            inner,
            ring,
            panel_floor: 0.25 * mfp_mm * u,
            ln_r0: r0.ln(),
            per_ln,
            laplacian,
        }
    }

    /// ∇²R_d/R_d per channel at `r_mm` (1/mm²), interpolated in the table.
    #[inline]
    fn laplacian(&self, r_mm: f64) -> Rgb {
        let last = self.laplacian.len() - 1;
        let x = if r_mm > 0.0 {
            ((r_mm.ln() - self.ln_r0) * self.per_ln).clamp(0.0, last as f64)
        } else {
            0.0
        };
        let i = (x as usize).min(last - 1);
        let t = x - i as f64;
        let (lo, hi) = (self.laplacian[i], self.laplacian[i + 1]);
        [0, 1, 2].map(|c| lo[c] + t * (hi[c] - lo[c]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss_bssrdf::Medium;

    fn shading(model: ModelKind, medium: Medium, units_per_mm: f64) -> TranslucentShading {
        TranslucentShading::new(
            "test",
            &Translucent {
                model,
                medium,
                units_per_mm,
                texture: None,
                angular: Default::default(),
                sphere_radius: None,
                local_radius: false,
                drift: false,
                unscattered: false,
            },
        )
    }

    /// The cosine along the surface by hand: vectors in the tangent plane, out of it, and with
    /// no tangential part, at scene scales from 10⁻⁶ to 10⁶ (the guard is relative).
    #[test]
    fn along_surface_cos_projects_on_the_tangent_plane() {
        let n = DVec3::Z;
        for s in [1e-6, 1.0, 1e6] {
            let c = |a: DVec3, b: DVec3| along_surface_cos(a, b * s, n);
            assert!((c(DVec3::X, DVec3::X) - 1.0).abs() < 1e-12);
            assert!((c(DVec3::X, -DVec3::X) + 1.0).abs() < 1e-12);
            assert!(c(DVec3::X, DVec3::Y).abs() < 1e-12);
            // (1, 0, −5) and (1, 1, 3) along the surface: (1, 0) and (1, 1), 45° apart.
            let v = c(DVec3::new(1.0, 0.0, -5.0), DVec3::new(1.0, 1.0, 3.0));
            assert!((v - 0.5f64.sqrt()).abs() < 1e-12, "{v}");
            assert_eq!(c(DVec3::Z, DVec3::X), 0.0);
            assert_eq!(c(DVec3::X, DVec3::NEG_Z), 0.0);
            assert_eq!(c(DVec3::X, DVec3::ZERO), 0.0);
        }
    }

    /// A drifting material sends light arriving at 70° along +x to an exit point ahead of
    /// the entry (+x) more than to one behind, and the two, like any pair at opposite azimuths
    /// seen straight on, sum to twice the light without drift (the factor moves light); seen
    /// straight on from a point beside the light's path (±y), nothing changes; without drift
    /// every exit point gets the Fresnel-weighted irradiance.
    #[test]
    fn drift_moves_light_ahead_of_its_direction() {
        let medium = Medium::preset("skin1").unwrap();
        let plain = shading(ModelKind::McTable, medium.clone(), 1.0);
        let t = Translucent {
            model: ModelKind::McTable,
            medium,
            units_per_mm: 1.0,
            texture: None,
            angular: Default::default(),
            sphere_radius: None,
            local_radius: false,
            drift: true,
            unscattered: false,
        };
        let drifting = TranslucentShading::new("test", &t);
        assert!(drifting.drift.is_some() && plain.drift.is_none());
        let theta = 70f64.to_radians();
        // From the point towards the light: the light travels along +x, downwards.
        let packet = Incident {
            dir: DVec3::new(-theta.sin(), 0.0, theta.cos()),
            e_cos: [1.0, 2.0, 3.0],
        };
        let entry = (DVec3::ZERO, DVec3::Z);
        let at = |sh: &TranslucentShading, x: DVec3| {
            sh.entering_towards(&[packet], entry, (x, DVec3::Z, DVec3::Z))
        };
        let none = at(&plain, DVec3::X);
        let f = ft_dielectric(theta.cos(), plain.eta);
        for c in 0..3 {
            assert!((none[c] - f * packet.e_cos[c]).abs() < 1e-12, "{none:?}");
        }
        for d in [0.3, 1.0, 3.0] {
            let ahead = at(&drifting, DVec3::X * d);
            let behind = at(&drifting, -DVec3::X * d);
            let side = at(&drifting, DVec3::Y * d);
            for c in 0..3 {
                assert!(
                    ahead[c] > 1.1 * behind[c],
                    "{d} mm, channel {c}: {ahead:?} {behind:?}"
                );
                assert!((ahead[c] + behind[c] - 2.0 * none[c]).abs() < 1e-12 * none[c]);
                assert!((side[c] - none[c]).abs() < 1e-12 * none[c]);
            }
        }
        // The exit's term: seen at 60° from a point the view ray travels towards, the light
        // from behind the view ray's path along the surface is dimmed, from ahead brightened.
        let wo = DVec3::new(-60f64.to_radians().sin(), 0.0, 60f64.to_radians().cos());
        let normal_entry = Incident {
            dir: DVec3::Z,
            e_cos: [1.0; 3],
        };
        let seen =
            |xo: DVec3| drifting.entering_towards(&[normal_entry], entry, (xo, DVec3::Z, wo));
        // The view ray travels along +x at xo; the entry point is ahead of it when xo is at −x.
        let (ahead, behind) = (seen(-DVec3::X), seen(DVec3::X));
        for c in 0..3 {
            assert!(
                ahead[c] > 1.1 * behind[c],
                "exit, channel {c}: {ahead:?} {behind:?}"
            );
        }
    }

    /// The media of the tests: two measured ones (Jensen et al. 2001) and ketchup, whose green
    /// and blue channels absorb strongly (σ_tr > σ'_t: the steepest tails).
    fn media() -> Vec<(&'static str, Medium)> {
        ["skin1", "marble", "ketchup"]
            .into_iter()
            .map(|n| (n, Medium::preset(n).unwrap()))
            .collect()
    }

    const RADIAL: [ModelKind; 4] = [
        ModelKind::StandardDipole,
        ModelKind::BetterDipole,
        ModelKind::PhotonBeamDiffusion,
        ModelKind::Burley,
    ];

    /// Composite Gauss–Legendre of `f` on [lo, hi]: `panels` equal panels of 12 points, or, with
    /// `graded`, panels halving towards `lo` (down to 2⁻²⁷ of the interval) for integrands
    /// that peak there.
    fn composite(f: &dyn Fn(f64) -> Rgb, lo: f64, hi: f64, panels: usize, graded: bool) -> Rgb {
        let (x, w) = sss_bssrdf::quadrature::gauss_legendre(12);
        let mut edges = vec![lo];
        if graded {
            for k in (0..28).rev() {
                edges.push(lo + (hi - lo) * 0.5f64.powi(k));
            }
        } else {
            for k in 1..=panels {
                edges.push(lo + (hi - lo) * k as f64 / panels as f64);
            }
        }
        let mut sum = [0.0; 3];
        for e in edges.windows(2) {
            let (half, mid) = (0.5 * (e[1] - e[0]), 0.5 * (e[1] + e[0]));
            for (xi, wi) in x.iter().zip(w) {
                let v = f(mid + half * xi);
                for c in 0..3 {
                    sum[c] += wi * half * v[c];
                }
            }
        }
        sum
    }

    /// An independent brute force: the mean of R_d over the disk as a double integral over
    /// the angle θ around x_o (measured from the direction of the disk's centre) and the
    /// distance s along each ray, between the ray's entry and exit points of the disk
    /// s± = r cos θ ± √(a² − r² sin² θ), by fine composite Gauss–Legendre in both.
    fn brute_force(sh: &TranslucentShading, r: f64, a: f64) -> Rgb {
        brute_force_of(r, a, &|s| sh.rd_scene(s))
    }

    /// [`brute_force`] of any profile `rd(s)`.
    fn brute_force_of(r: f64, a: f64, rd: &dyn Fn(f64) -> Rgb) -> Rgb {
        let inner = |theta: f64| -> Rgb {
            let d = (a * a - r * r * theta.sin().powi(2)).max(0.0).sqrt();
            let (lo, hi) = if r < a {
                (0.0, r * theta.cos() + d)
            } else {
                (r * theta.cos() - d, r * theta.cos() + d)
            };
            if !(hi > lo) {
                return [0.0; 3];
            }
            let f = |s: f64| rd(s).map(|v| v * s);
            composite(&f, lo, hi, 8, lo == 0.0)
        };
        let sum = if r < a {
            // θ over [0, π] (twice, by symmetry); a panel edge at π/2 for the kink at r = a.
            composite(&inner, 0.0, PI, 12, false)
        } else {
            // θ up to the tangent θ_max = asin(a/r); θ = θ_max (1 − (1 − t)²) removes the
            // square root at the tangent.
            let tmax = (a / r).min(1.0).asin();
            let f = |t: f64| {
                inner(tmax * (1.0 - (1.0 - t) * (1.0 - t))).map(|v| v * 2.0 * tmax * (1.0 - t))
            };
            composite(&f, 0.0, 1.0, 12, false)
        };
        sum.map(|v| 2.0 * v / (PI * a * a))
    }

    /// Max over channels of the relative error, ignoring channels whose value is below 10⁻⁶
    /// of their disk average at r = 0 (no contribution; photon beam diffusion's spline is
    /// clamped at 0 where it overshoots there, so R_d is not smooth).
    fn rel_err_floor(got: Rgb, want: Rgb, peak: Rgb) -> f64 {
        (0..3)
            .filter(|&c| want[c] > 1e-6 * peak[c])
            .map(|c| (got[c] - want[c]).abs() / want[c])
            .fold(0.0, f64::max)
    }

    /// The disk average against the brute force, every radial model and medium, disk radii of
    /// 0.1 to 4 smallest reduced mean free paths and r/a ∈ {0, 0.5, 1, 2, 5, 20}.
    #[test]
    fn the_disk_average_derivatives_match_its_finite_differences() {
        // D′ and D″ against central differences of rd_sample_scene itself (h = 10⁻³ r, inside
        // one step of the far branch's correction table except by chance, and a fortieth of
        // the near branch's own step, so its O(h²) error shows), in the far branch and in the
        // near one (the quadrature, r < 3 disk radii), and no derivatives within 1.25 disk
        // radii (the average's derivatives are singular at the disk's edge). The closed-form
        // models only: the tabulated ones' splines have second derivatives that jump at their
        // knots, which a difference across one does not see (their R_d′ and R_d″ are checked
        // inside knot intervals in the bssrdf crate's tests).
        for model in [
            ModelKind::StandardDipole,
            ModelKind::BetterDipole,
            ModelKind::Burley,
        ] {
            for (name, medium) in media() {
                let u = 0.2;
                let sh = shading(model, medium.clone(), u);
                let mfp = (0..3)
                    .map(|c| 1.0 / medium.sigma_t_reduced(c))
                    .fold(f64::INFINITY, f64::min)
                    * u;
                let area = (0.5 * mfp).powi(2);
                let a = (area / PI).sqrt();
                assert!(sh.rd_sample_derivatives_scene(1.2 * a, area).is_none());
                for f in [1.3, 1.6, 2.2, 2.9, 3.5, 6.0, 15.0] {
                    let r = f * a;
                    let Some(d) = sh.rd_sample_derivatives_scene(r, area) else {
                        // The far branch may decline (a correction too large to trust); the
                        // near one always answers from 1.25 radii on.
                        assert!(f > DISK_FAR_RATIO, "{model} {name}: none at {f} a");
                        continue;
                    };
                    let h = 1e-3 * r;
                    let (m, p, q) = (
                        sh.rd_sample_scene(r, area),
                        sh.rd_sample_scene(r + h, area),
                        sh.rd_sample_scene(r - h, area),
                    );
                    for c in 0..3 {
                        if m[c] < 1e-200 {
                            continue;
                        }
                        let d1 = (p[c] - q[c]) / (2.0 * h);
                        let d2 = (p[c] - 2.0 * m[c] + q[c]) / (h * h);
                        let at = format!("{model} {name} ch{c} r = {f} a");
                        assert!((d[c][0] - m[c]).abs() <= 1e-6 * m[c], "{at}: value");
                        // Scales: the value over r and r²; the derivatives of the correction
                        // are a few per cent of the whole.
                        let (s1, s2) = (m[c] / r + d1.abs(), m[c] / (r * r) + d2.abs());
                        assert!(
                            (d[c][1] - d1).abs() <= 0.02 * s1,
                            "{at}: D′ {} vs {d1}",
                            d[c][1]
                        );
                        assert!(
                            (d[c][2] - d2).abs() <= 0.05 * s2,
                            "{at}: D″ {} vs {d2}",
                            d[c][2]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn disk_average_matches_brute_force() {
        let (mut worst, mut worst_large): (f64, f64) = (0.0, 0.0);
        for model in RADIAL {
            for (name, medium) in media() {
                let sh = shading(model, medium.clone(), 0.1);
                let l = (0..3)
                    .map(|c| medium.reduced_mean_free_path(c))
                    .fold(f64::INFINITY, f64::min)
                    * 0.1;
                for a_l in [0.1, 0.35, 1.0, 4.0] {
                    let a = a_l * l;
                    let peak = brute_force(&sh, 0.0, a);
                    for ratio in [0.0, 0.5, 1.0, 2.0, 5.0, 20.0] {
                        let r = ratio * a;
                        let got = sh.disk_average(r, a);
                        let want = brute_force(&sh, r, a);
                        let e = rel_err_floor(got, want, peak);
                        eprintln!("{model} {name} a/l {a_l} r/a {ratio}: {e:.2e}");
                        if a_l <= 1.0 {
                            worst = worst.max(e);
                        } else {
                            worst_large = worst_large.max(e);
                        }
                    }
                }
            }
        }
        eprintln!("worst {worst:.3e}, for a = 4 mean free paths {worst_large:.3e}");
        assert!(worst < 3e-3, "worst relative error {worst}");
        assert!(worst_large < 2e-2, "worst relative error {worst_large}");
    }

    /// Near the shading point, a sample's value under a pair's ball is the disk's average of
    /// the ball's profile, max(0, R_d + Δ) (0 beyond the diameter), against the brute force of
    /// that profile over the disk; not the disk's average of R_d with the difference at the
    /// centre's distance added, which near a peaked R_d is a point value beside an average
    /// (on a 450 mm marble head at the default spacing it took four fifths of a sample's own
    /// green term away; here it is 2.7 % off at the disk's centre and 5 % two radii away).
    /// Far, the reshaped point value with its correction, as without a ball.
    #[test]
    fn a_ball_reshapes_the_profile_before_the_disk_averages_it() {
        // skin1, whose walk resolves the difference at these distances (ketchup's green and
        // blue differences out there are the walk's noise beside a vanishing R_d, a kinked
        // profile no fixed quadrature averages to a few per cent).
        for (name, medium) in [("skin1", Medium::preset("skin1").unwrap())] {
            let sh = shading(ModelKind::McTable, medium.clone(), 1.0);
            let family = sss_bssrdf::BallFamily::new(&medium, 4.0, 64.0).unwrap();
            let l = (0..3)
                .map(|c| medium.reduced_mean_free_path(c))
                .fold(f64::INFINITY, f64::min);
            for radius in [8.0, 50.0] {
                let ball = |s: f64| family.reshape_rgb(s, radius, sh.rd_scene(s));
                for a_l in [0.35, 1.0, 3.0] {
                    let a = a_l * l;
                    let peak = brute_force_of(0.0, a, &ball);
                    for ratio in [0.0, 0.5, 1.0, 2.0, 5.0, 20.0] {
                        let r = ratio * a;
                        if r + a > radius {
                            continue;
                        }
                        let got = sh.rd_sample_ball(r, PI * a * a, &family, radius);
                        let want = brute_force_of(r, a, &ball);
                        // Relative, with a floor of 1 % of the channel's own peak.
                        let e = (0..3)
                            .map(|c| (got[c] - want[c]).abs() / (want[c] + 0.01 * peak[c]))
                            .fold(0.0, f64::max);
                        eprintln!("{name} R {radius} a/l {a_l} r/a {ratio}: {e:.2e}");
                        // The far branch adds the difference at the centre's distance to the
                        // corrected R_d: within 5 % where the difference bends over the disk.
                        let tolerance = if r < DISK_FAR_RATIO * a { 0.02 } else { 0.05 };
                        assert!(
                            e < tolerance,
                            "{name} R {radius} a/l {a_l} r/a {ratio}: {e}, {got:?} against {want:?}"
                        );
                    }
                }
            }
            // No radius: the half-space's value, bit for bit.
            for r in [0.0, 0.3, 3.0] {
                assert_eq!(
                    sh.rd_sample_ball(r, 0.5, &family, f64::NAN),
                    sh.rd_sample_scene(r, 0.5)
                );
            }
        }
    }

    /// The far branch's claim: wherever `rd_sample_scene` takes it (r ≥ DISK_FAR_RATIO·a and a
    /// small correction), it is within 1.5 % of the brute-force disk average; and it is taken at
    /// the default spacing (disks of ≈ 0.35 reduced mean free paths) from 3 radii on for the
    /// media that are not strongly absorbing, so `exact` pays for few quadratures.
    #[test]
    fn far_branch_is_within_its_tolerance() {
        let mut worst: f64 = 0.0;
        for model in RADIAL {
            for (name, medium) in media() {
                let sh = shading(model, medium.clone(), 1.0);
                let l = (0..3)
                    .map(|c| medium.reduced_mean_free_path(c))
                    .fold(f64::INFINITY, f64::min);
                for a_l in [0.05, 0.2, 0.35, 0.5, 1.0, 2.0] {
                    let a = a_l * l;
                    let peak = brute_force(&sh, 0.0, a);
                    let mut far_taken = 0;
                    for ratio in [DISK_FAR_RATIO, 4.0, 6.0, 8.0, 12.0, 20.0, 40.0] {
                        let r = ratio * a;
                        let got = sh.rd_sample_scene(r, PI * a * a);
                        if got != sh.disk_average(r, a) {
                            far_taken += 1;
                        }
                        let want = brute_force(&sh, r, a);
                        let e = rel_err_floor(got, want, peak);
                        eprintln!("far {model} {name} a/l {a_l} r/a {ratio}: {e:.2e}");
                        worst = worst.max(e);
                    }
                    eprintln!("far {model} {name} a/l {a_l}: far branch at {far_taken} of 7");
                    if a_l <= 0.35 && name != "ketchup" {
                        assert_eq!(far_taken, 7, "{model} {name} a/l {a_l}");
                    }
                }
            }
        }
        eprintln!("far worst {worst:.3e}");
        assert!(worst < 0.015, "worst relative error {worst}");
    }

    /// r = 0 has a closed form for normalized diffusion: the disk holds the fraction
    /// F(a/d) = 1 − ¼e^{−a/d} − ¾e^{−a/(3d)} of the total A (Christensen & Burley 2015, Eq. 11),
    /// so the mean is A F(a/d)/(πa²).
    #[test]
    fn burley_disk_at_the_centre_is_its_cdf() {
        for (name, medium) in media() {
            let model = sss_bssrdf::ChristensenBurley::new(medium.clone());
            let sh = shading(ModelKind::Burley, medium, 1.0);
            for a in [0.01, 0.1, 0.5, 2.0, 10.0] {
                let got = sh.rd_sample_scene(0.0, PI * a * a);
                for c in 0..3 {
                    let want = model.surface_albedo(c)
                        * sss_bssrdf::christensen_burley::cdf(a / model.d(c))
                        / (PI * a * a);
                    let e = (got[c] - want).abs() / want;
                    assert!(e < 1e-5, "{name} a {a} channel {c}: {} vs {want}", got[c]);
                }
            }
        }
    }

    /// Finite and non-negative at r = 0, for zero, tiny, huge and invalid areas and distances;
    /// a vanishing area gives the point value.
    #[test]
    fn finite_everywhere() {
        for model in RADIAL {
            let sh = shading(model, Medium::preset("skin1").unwrap(), 0.1);
            for r in [0.0, 1e-12, 1e-3, 0.1, 1.0, 1e3, 1e300, f64::INFINITY, -0.5] {
                for area in [
                    0.0,
                    1e-300,
                    1e-12,
                    1e-4,
                    1.0,
                    1e6,
                    1e300,
                    f64::INFINITY,
                    -1.0,
                    f64::NAN,
                ] {
                    let v = sh.rd_sample_scene(r, area);
                    assert!(
                        v.iter().all(|x| x.is_finite() && *x >= 0.0),
                        "{model} r {r} area {area}: {v:?}"
                    );
                }
                assert_eq!(sh.rd_sample_scene(r, 0.0), sh.rd_scene(r.abs()));
            }
            // A tiny disk averages to the point value away from a peak.
            let (p, d) = (sh.rd_scene(0.05), sh.rd_sample_scene(0.05, 1e-12));
            for c in 0..3 {
                assert!(
                    (p[c] - d[c]).abs() <= 1e-6 * p[c],
                    "{model}: {p:?} vs {d:?}"
                );
            }
        }
    }
}
