//! The table of one η and g ([`McTable`]): the knot values of the four tables around them
//! blended (linear in η, then in g) into the toolkit's one profile-table type.

use super::*;
use crate::profile_table::ProfileTable;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// The knot values of every albedo row of table `e` ([`row_nodes`]). Row-major [`N_RHO`] ×
/// knots.
fn node_values(data: &McTableData, e: usize) -> Vec<f64> {
    let knots = data.knots();
    let n = knots.len() + 1;
    let rows = data.rho_samples().len();
    let mut out = vec![0.0; rows * n];
    let Ok(system) = Histopolation::new(knots) else {
        return out;
    };
    for i in 0..rows {
        let v = row_nodes(&system, knots, data.mass(e, i), data.mass_se(e, i));
        out[i * n..(i + 1) * n].copy_from_slice(&v);
    }
    out
}

/// Per table of the embedded data (g-major over [`GS`] × [`ETAS`]), its knot values, each
/// computed on first use (a medium with g = 0 never solves the tables of g ≠ 0).
fn embedded_nodes(t: usize) -> Option<&'static [f64]> {
    const TABLES: usize = GS.len() * ETAS.len();
    static NODES: [OnceLock<Option<Vec<f64>>>; TABLES] = [const { OnceLock::new() }; TABLES];
    NODES
        .get(t)?
        .get_or_init(|| Some(node_values(McTableData::embedded().ok()?, t)))
        .as_deref()
}

/// `(1 − t) a + t b` per value, exactly `a` at t = 0 and `b` at t = 1 (empty unless both have
/// `len` values).
fn blend_nodes(a: &[f64], b: &[f64], t: f64, len: usize) -> Vec<f64> {
    if a.len() != len || b.len() != len {
        return Vec::new();
    }
    a.iter()
        .zip(b)
        .map(|(a, b)| {
            if t == 0.0 {
                *a
            } else if t == 1.0 {
                *b
            } else {
                (1.0 - t) * a + t * b
            }
        })
        .collect()
}

/// The knot values at (`eta`, `g`), both already clamped: the four tables around them blended
/// bilinearly (linear in η, then in g), through `nodes(t)` for table t.
fn blended_nodes<'a>(eta: f64, g: f64, nodes: impl Fn(usize) -> Option<&'a [f64]>) -> Vec<f64> {
    let len = N_RHO * (radius_knots().len() + 1);
    let (e0, e1, te) = eta_bracket(eta);
    let (g0, g1, tg) = g_bracket(g);
    let at = |gi: usize| {
        let (a, b) = (nodes(gi * ETAS.len() + e0), nodes(gi * ETAS.len() + e1));
        blend_nodes(a.unwrap_or(&[]), b.unwrap_or(&[]), te, len)
    };
    if tg == 0.0 {
        at(g0)
    } else {
        blend_nodes(&at(g0), &at(g1), tg, len)
    }
}

/// The tabulated Monte Carlo profile for one η and g (the counterpart of
/// [`crate::photon_beam_diffusion::PbdTable`]): [`N_RHO`] albedo rows × [`radius_knots`] of
/// T(ρ', x') = 2πx' R_d¹(x') (reduced albedo and radius in reduced mean free paths; for g = 0
/// these are ρ and σ_t r), their running integrals and totals.
/// The table itself is the toolkit's one [`ProfileTable`], which this dereferences to.
#[derive(Clone, Debug)]
pub struct McTable(ProfileTable);

impl std::ops::Deref for McTable {
    type Target = ProfileTable;

    fn deref(&self) -> &ProfileTable {
        &self.0
    }
}

impl McTable {
    /// The isotropic (g = 0) table for `eta`: [`McTable::anisotropic`] at g = 0.
    pub fn new(eta: f64) -> McTable {
        McTable::anisotropic(eta, 0.0)
    }

    /// The table for `eta` and `g` from the embedded data: η clamped to [1.0, 1.5] and g to
    /// [0, 0.9] ([`GS`]), then the knot values of the four neighbouring tables blended
    /// bilinearly (linear in η, then in g). If the embedded data could not be read (see
    /// [`McTableData::embedded`]) the table is all zeros.
    pub fn anisotropic(eta: f64, g: f64) -> McTable {
        let (eta, g) = (clamp_eta(eta), clamp_g(g));
        McTable::from_nodes(eta, g, &blended_nodes(eta, g, embedded_nodes))
    }

    /// The isotropic table from `data` without any cache: the spline knot values of the two η
    /// tables are solved from the tallies here (what the first model of a process pays).
    pub fn from_data(data: &McTableData, eta: f64) -> McTable {
        McTable::from_data_anisotropic(data, eta, 0.0)
    }

    /// [`McTable::anisotropic`] from `data` (which must hold the tables of [`GS`] × [`ETAS`];
    /// all zeros otherwise), without any cache.
    pub fn from_data_anisotropic(data: &McTableData, eta: f64, g: f64) -> McTable {
        let (eta, g) = (clamp_eta(eta), clamp_g(g));
        let full = data.gs().len() == GS.len() && data.etas().len() == ETAS.len();
        let ((e0, e1, _), (g0, g1, _)) = (eta_bracket(eta), g_bracket(g));
        let needed = |t: usize| {
            let (gi, e) = (t / ETAS.len(), t % ETAS.len());
            (gi == g0 || gi == g1) && (e == e0 || e == e1)
        };
        let solved: Vec<Option<Vec<f64>>> = (0..GS.len() * ETAS.len())
            .map(|t| (full && needed(t)).then(|| node_values(data, t)))
            .collect();
        McTable::from_nodes(
            eta,
            g,
            &blended_nodes(eta, g, |t| solved.get(t)?.as_deref()),
        )
    }

    /// [`McTable::from_data`] of the embedded file, parsed again (a cold start: what the first
    /// `mc-table` model of a process costs, for timing); all zeros if it cannot be read.
    pub fn from_embedded_uncached(eta: f64) -> McTable {
        match McTableData::from_bytes(EMBEDDED) {
            Ok(data) => McTable::from_data(&data, eta),
            Err(_) => McTable::from_nodes(clamp_eta(eta), 0.0, &[]),
        }
    }

    /// The table through the knot values `nodes` (all zeros when it is not a full table).
    fn from_nodes(eta: f64, g: f64, nodes: &[f64]) -> McTable {
        let rho_samples = rho_samples();
        let radius_samples = spline_knots(&radius_knots());
        let mut profile = vec![0.0; N_RHO * radius_samples.len()];
        if nodes.len() == profile.len() {
            profile.copy_from_slice(nodes);
        }
        McTable(
            ProfileTable::new(g, eta, rho_samples, radius_samples, profile)
                .expect("the radius knots are increasing and the table full"),
        )
    }

    /// The table for `eta` and `g` from a process-wide cache keyed by the clamped values'
    /// bits, built on first use. Every call with the same η and g returns the same `Arc`.
    pub fn shared(eta: f64, g: f64) -> Arc<McTable> {
        type Cache = Mutex<HashMap<(u64, u64), Arc<McTable>>>;
        static CACHE: OnceLock<Cache> = OnceLock::new();
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        let key = (clamp_eta(eta).to_bits(), clamp_g(g).to_bits());
        if let Some(t) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return Arc::clone(t);
        }
        let table = Arc::new(McTable::anisotropic(eta, g));
        let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
        Arc::clone(map.entry(key).or_insert(table))
    }
}

/// The two entries of the increasing `grid` (≥ 2 values) around `v` (already clamped to it)
/// and the weight of the upper one.
fn bracket(grid: &[f64], v: f64) -> (usize, usize, f64) {
    let hi = grid.partition_point(|&x| x <= v).clamp(1, grid.len() - 1);
    let (a, b) = (grid[hi - 1], grid[hi]);
    (hi - 1, hi, ((v - a) / (b - a)).clamp(0.0, 1.0))
}

/// `v` clamped to the range of the increasing `grid`, NaN to `nan`.
fn clamp_to(grid: &[f64], v: f64, nan: f64) -> f64 {
    if v.is_nan() {
        nan
    } else {
        v.clamp(grid[0], grid[grid.len() - 1])
    }
}

/// The two tables of [`ETAS`] around `eta` (already clamped) and the weight of the upper one.
fn eta_bracket(eta: f64) -> (usize, usize, f64) {
    bracket(&ETAS, eta)
}

/// η clamped to the range of [`ETAS`] (NaN to [`MAIN_ETA`]).
fn clamp_eta(eta: f64) -> f64 {
    clamp_to(&ETAS, eta, MAIN_ETA)
}

/// True when `eta` lies in the range of [`ETAS`], where the tables are interpolated rather
/// than clamped.
pub fn eta_in_range(eta: f64) -> bool {
    (ETAS[0]..=ETAS[ETAS.len() - 1]).contains(&eta)
}

/// The two tables of [`GS`] around `g` (already clamped) and the weight of the upper one.
fn g_bracket(g: f64) -> (usize, usize, f64) {
    bracket(&GS, g)
}

/// g clamped to the range of [`GS`] (NaN to 0).
fn clamp_g(g: f64) -> f64 {
    clamp_to(&GS, g, 0.0)
}

/// True when `g` lies in the range of [`GS`], where the tables are interpolated; a medium
/// outside it (g < 0, or g > 0.9) reads the nearest end table at its reduced albedo and radius
/// (the similarity relation: an approximation near the entry point, see the module
/// documentation).
pub fn g_in_range(g: f64) -> bool {
    (GS[0]..=GS[GS.len() - 1]).contains(&g)
}
