//! The methods the experiment compares: [`ProfileMethod`] and the `sss_bssrdf` models that
//! implement it.

use super::*;

/// A method that produces a radial profile R_d(r) for a medium.
pub trait ProfileMethod: Sync {
    /// Name in the report and CSV.
    fn name(&self) -> String;
    /// The evaluator for `medium` (may use process-wide caches).
    fn build(&self, medium: &Medium) -> Box<dyn Bssrdf>;
    /// Seconds a build takes from scratch, without process-wide caches (best of three).
    fn cold_build_seconds(&self, medium: &Medium) -> f64;
    /// The part of the Monte Carlo transport the method models, and is measured against.
    fn reference_part(&self) -> WalkPart;
}

/// One of the `sss_bssrdf` models.
pub struct ModelMethod(pub ModelKind);

impl ProfileMethod for ModelMethod {
    fn name(&self) -> String {
        self.0.name().to_string()
    }

    fn build(&self, medium: &Medium) -> Box<dyn Bssrdf> {
        make_model(self.0, medium)
    }

    /// Photon beam diffusion models single and multiple scattering, normalized diffusion
    /// (Christensen & Burley 2015) is fitted to Monte Carlo profiles of all scattering orders,
    /// and `mc-table` is the Monte Carlo transport itself, tabulated.
    /// The directional dipole (Frisvad et al. 2014) puts a source of strength 1, not α′, at
    /// the ray's first scattering event, so it stands for all scattered light and is measured
    /// against the full tally too. The standard and better dipoles model multiple scattering
    /// only.
    fn reference_part(&self) -> WalkPart {
        match self.0 {
            ModelKind::PhotonBeamDiffusion
            | ModelKind::Burley
            | ModelKind::DirectionalDipole
            | ModelKind::McTable => WalkPart::All,
            ModelKind::StandardDipole | ModelKind::BetterDipole => WalkPart::Multiple,
        }
    }

    fn cold_build_seconds(&self, medium: &Medium) -> f64 {
        // Warm the shared caches, then time a build that redoes the cached part explicitly:
        // photon beam diffusion shares its table per (g, η); that table is its real cost.
        // Normalized diffusion takes its surface albedo from the table of (0, η). `mc-table`
        // reads its embedded tallies and solves their splines once per process; a cold build
        // redoes that for the two η tables it blends.
        black_box(self.build(medium));
        (0..3)
            .map(|_| {
                let t0 = Instant::now();
                match self.0 {
                    ModelKind::PhotonBeamDiffusion => {
                        black_box(PbdTable::new(medium.g(), medium.eta()));
                    }
                    ModelKind::Burley => {
                        black_box(PbdTable::new(0.0, medium.eta()));
                    }
                    ModelKind::McTable => {
                        black_box(McTable::from_embedded_uncached(medium.eta()));
                    }
                    _ => {}
                }
                black_box(self.build(medium));
                t0.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// Every method the experiment compares, in report order.
pub fn methods() -> Vec<Box<dyn ProfileMethod>> {
    ModelKind::ALL
        .into_iter()
        .map(|k| Box::new(ModelMethod(k)) as Box<dyn ProfileMethod>)
        .collect()
}
