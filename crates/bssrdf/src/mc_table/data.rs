//! The Monte Carlo tallies behind the tables ([`McTableData`]): their generation, the file
//! format (versions 1 and 2, FNV-1a checksummed) and the embedded data.

use super::*;
use crate::BssrdfError;
use crate::monte_carlo::MAX_SCATTERING_EVENTS;
use crate::monte_carlo::condensed::{CondensedConfig, simulate_albedos};
use std::ops::Range;
use std::sync::OnceLock;

/// The table file embedded in the crate.
pub(super) const EMBEDDED: &[u8] =
    include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/mc_table.bin"));

/// File magic of the table data (version 2: tables over g and η).
const MAGIC: &[u8; 8] = b"SSSMCT\x02\x00";

/// File magic of version 1 (g = 0 only), read by [`McTableData::from_bytes_v1`].
const MAGIC_V1: &[u8; 8] = b"SSSMCT\x01\x00";

/// FNV-1a 64 (Fowler, Noll, Vo) of `bytes`: the checksum of the table file.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The Monte Carlo tallies behind the table: for every table (g of [`GS`], η of [`ETAS`]) and
/// albedo row, the escaped weight per photon in each bin of [`tally_edges`] (∫ 2πx R_d¹ dx
/// over the bin; unit extinction for g = 0, unit reduced extinction otherwise) with its
/// standard error, and the row's total reflectance.
///
/// The tables are numbered g-major: table `t = g_index × etas().len() + eta_index`
/// ([`McTableData::table_index`]), so for g = 0 the table index is the η index.
#[derive(Clone, Debug, PartialEq)]
pub struct McTableData {
    pub(super) seed: u64,
    pub(super) gs: Vec<f64>,
    pub(super) etas: Vec<f64>,
    pub(super) rho: Vec<f64>,
    pub(super) knots: Vec<f64>,
    pub(super) edges: Vec<f64>,
    /// Per table, the walks.
    pub(super) walks: Vec<Vec<Walks>>,
    /// Per (table, row, bin), row-major.
    pub(super) mass: Vec<f64>,
    pub(super) mass_se: Vec<f64>,
    /// Per (table, row).
    pub(super) total: Vec<f64>,
    pub(super) total_se: Vec<f64>,
    pub(super) capped_weight: Vec<f64>,
}

impl McTableData {
    /// Runs every walk of [`plan`] (photons × `scale`), calling `progress` with a line after
    /// each. Takes ≈ 700 CPU-seconds at `scale` = 1 for the tables of g = 0 (measured on a
    /// shared 2-core machine) and about 4.5 times that for the others (see `docs/mc-table.md`).
    /// Bit-identical for any number of rayon threads.
    pub fn generate(scale: f64, progress: &dyn Fn(&str)) -> Result<McTableData, BssrdfError> {
        McTableData::generate_reusing(scale, None, progress)
    }

    /// [`McTableData::generate`], taking each table whose g, η, seed and walks `reuse` holds
    /// unchanged from it instead of running its walks again (every walk is seeded, so the
    /// result is the same as a full run; `cargo xtask tables --reuse`).
    pub fn generate_reusing(
        scale: f64,
        reuse: Option<&McTableData>,
        progress: &dyn Fn(&str),
    ) -> Result<McTableData, BssrdfError> {
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(BssrdfError::InvalidArgument(format!(
                "mc-table: photon scale {scale} must be finite and > 0"
            )));
        }
        let rho = rho_samples();
        let knots = radius_knots();
        let edges = tally_edges(&knots);
        let bins = edges.len() - 1;
        let tables = GS.len() * ETAS.len();
        let cells = tables * N_RHO * bins;
        let mut data = McTableData {
            seed: SEED,
            gs: GS.to_vec(),
            etas: ETAS.to_vec(),
            rho: rho.clone(),
            knots,
            edges: edges.clone(),
            walks: Vec::new(),
            mass: vec![0.0; cells],
            mass_se: vec![0.0; cells],
            total: vec![0.0; tables * N_RHO],
            total_se: vec![0.0; tables * N_RHO],
            capped_weight: vec![0.0; tables * N_RHO],
        };
        for (gi, &g) in GS.iter().enumerate() {
            for (e, &eta) in ETAS.iter().enumerate() {
                let t = gi * ETAS.len() + e;
                let walks = plan(gi, e, scale);
                let old = reuse.and_then(|r| r.find_table(g, eta, SEED, &walks));
                if let Some((r, rt)) = old {
                    let (cell, row) = (t * N_RHO * bins, t * N_RHO);
                    let (rcell, rrow) = (rt * N_RHO * bins, rt * N_RHO);
                    let n = N_RHO * bins;
                    data.mass[cell..cell + n].copy_from_slice(&r.mass[rcell..rcell + n]);
                    data.mass_se[cell..cell + n].copy_from_slice(&r.mass_se[rcell..rcell + n]);
                    for (dst, src) in [
                        (&mut data.total, &r.total),
                        (&mut data.total_se, &r.total_se),
                        (&mut data.capped_weight, &r.capped_weight),
                    ] {
                        dst[row..row + N_RHO].copy_from_slice(&src[rrow..rrow + N_RHO]);
                    }
                    progress(&format!("g {g}, eta {eta}: reused"));
                } else {
                    data.simulate_table(t, g, eta, &walks, progress)?;
                }
                data.walks.push(walks);
            }
        }
        Ok(data)
    }

    /// Runs the walks of table `t` (anisotropy `g`, index `eta`) into its cells.
    fn simulate_table(
        &mut self,
        t: usize,
        g: f64,
        eta: f64,
        walks: &[Walks],
        progress: &dyn Fn(&str),
    ) -> Result<(), BssrdfError> {
        let bins = self.edges.len() - 1;
        // Strata of one band add up: sums of masses and totals, variances in quadrature.
        let mut var = vec![0.0; N_RHO * bins];
        let mut total_var = vec![0.0; N_RHO];
        for walk in walks {
            let start = std::time::Instant::now();
            let reduced = &self.rho[walk.rows.clone()];
            // The rows are reduced albedos; the walk runs at their single-scattering albedos
            // in a medium of unit extinction and bins row i at σ'_t r, σ'_t = 1 − ρ_i g.
            let albedos: Vec<f64> = reduced
                .iter()
                .map(|&r| single_scattering_albedo(r, g))
                .collect();
            let radius_scales = if g == 0.0 {
                Vec::new()
            } else {
                albedos.iter().map(|&a| 1.0 - a * g).collect()
            };
            let profile = simulate_albedos(&CondensedConfig {
                photons: walk.photons,
                seed: self.seed,
                stream: walk.stream,
                albedos,
                g,
                eta,
                edges: self.edges.clone(),
                min_events: walk.min_events,
                max_events: walk.max_events,
                radius_scales,
            })?;
            for (k, i) in walk.rows.clone().enumerate() {
                let (cell, row) = ((t * N_RHO + i) * bins, t * N_RHO + i);
                for b in 0..bins {
                    self.mass[cell + b] += profile.row_mass(k)[b];
                    var[i * bins + b] += profile.row_mass_se(k)[b].powi(2);
                }
                self.total[row] += profile.total[k];
                total_var[i] += profile.total_se[k].powi(2);
                if walk.max_events == MAX_SCATTERING_EVENTS {
                    self.capped_weight[row] = profile.capped_weight[k];
                }
            }
            let stopped = if walk.max_events == MAX_SCATTERING_EVENTS {
                format!("{} stopped by the collision cap", profile.capped)
            } else {
                format!("{} walk on past the stratum", profile.capped)
            };
            progress(&format!(
                "g {g}, eta {eta}: albedo rows {}..{} (rho' {:.6}..{:.6}), collisions {}..={}, \
                 {} photons, {:.1} s, {stopped}",
                walk.rows.start,
                walk.rows.end,
                self.rho[walk.rows.start],
                self.rho[walk.rows.end - 1],
                walk.min_events,
                walk.max_events,
                walk.photons,
                start.elapsed().as_secs_f64(),
            ));
        }
        // Stored as f32 (see the module documentation).
        let (cells, rows) = (t * N_RHO * bins, t * N_RHO);
        for (k, v) in var.iter().enumerate() {
            let m = &mut self.mass[cells + k];
            *m = *m as f32 as f64;
            self.mass_se[cells + k] = v.sqrt() as f32 as f64;
        }
        for (i, v) in total_var.iter().enumerate() {
            self.total_se[rows + i] = v.sqrt();
        }
        Ok(())
    }

    /// The table of anisotropy `g` and index `eta`, if this data holds it with the same seed
    /// and walks: (self, its table index).
    fn find_table(&self, g: f64, eta: f64, seed: u64, walks: &[Walks]) -> Option<(&Self, usize)> {
        // The rows and knots are this version's: `parse` and `generate` make no others.
        if self.seed != seed {
            return None;
        }
        let gi = self.gs.iter().position(|&x| x.to_bits() == g.to_bits())?;
        let e = self
            .etas
            .iter()
            .position(|&x| x.to_bits() == eta.to_bits())?;
        let t = gi * self.etas.len() + e;
        (self.walks.get(t)?.as_slice() == walks).then_some((self, t))
    }

    /// The binary file (little-endian): magic, seed, sizes (g, η, ρ, knots, walks per table),
    /// the grids (g, η, ρ, knots, edges), per table the walks (rows, stream, collision range,
    /// photons), per (table, row) the total, its standard error and the capped weight as f64,
    /// per (table, row, bin) the masses and then their standard errors as f32, and the FNV-1a
    /// 64 of everything before it.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&self.seed.to_le_bytes());
        let n_walks = self.walks.first().map_or(0, Vec::len);
        for n in [
            self.gs.len(),
            self.etas.len(),
            self.rho.len(),
            self.knots.len(),
            n_walks,
        ] {
            out.extend_from_slice(&(n as u32).to_le_bytes());
        }
        for v in self
            .gs
            .iter()
            .chain(&self.etas)
            .chain(&self.rho)
            .chain(&self.knots)
            .chain(&self.edges)
        {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for walks in &self.walks {
            for w in walks {
                for v in [w.rows.start, w.rows.end, w.stream] {
                    out.extend_from_slice(&(v as u32).to_le_bytes());
                }
                for v in [w.min_events, w.max_events, w.photons] {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        for k in 0..self.total.len() {
            for v in [self.total[k], self.total_se[k], self.capped_weight[k]] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        for v in self.mass.iter().chain(&self.mass_se) {
            out.extend_from_slice(&(*v as f32).to_le_bytes());
        }
        let sum = fnv1a(&out);
        out.extend_from_slice(&sum.to_le_bytes());
        out
    }

    /// Reads [`McTableData::to_bytes`]'s format. Errors (never panics) on a wrong magic or
    /// checksum, a truncated file, grids other than this version's ([`GS`], [`ETAS`],
    /// [`rho_samples`], [`radius_knots`]) or values that are not finite and ≥ 0.
    pub fn from_bytes(bytes: &[u8]) -> Result<McTableData, BssrdfError> {
        let data = McTableData::parse(bytes, MAGIC)?;
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        if bits(&data.gs) != bits(&GS) || bits(&data.etas) != bits(&ETAS) {
            return Err(BssrdfError::InvalidArgument(
                "mc-table data: grids differ from this version's (regenerate with `cargo xtask \
                 tables`)"
                    .into(),
            ));
        }
        Ok(data)
    }

    /// Reads a version-1 file (the tables of g = 0 only, before the tables had g), as data
    /// with `gs() == [0.0]`: something to [`McTableData::generate_reusing`] from, not a table
    /// the model reads.
    pub fn from_bytes_v1(bytes: &[u8]) -> Result<McTableData, BssrdfError> {
        McTableData::parse(bytes, MAGIC_V1)
    }

    /// The common reader of both versions (version 1 has no g grid: it is g = 0).
    fn parse(bytes: &[u8], magic: &[u8; 8]) -> Result<McTableData, BssrdfError> {
        let bad = |what: &str| {
            Err(BssrdfError::InvalidArgument(format!(
                "mc-table data: {what}"
            )))
        };
        if bytes.len() < magic.len() + 8 || &bytes[..magic.len()] != magic {
            return bad("not a table file of this version (magic)");
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        if fnv1a(body).to_le_bytes() != sum {
            return bad("checksum mismatch (corrupt or truncated)");
        }
        let mut r = Reader {
            bytes: body,
            at: magic.len(),
        };
        let v1 = magic == MAGIC_V1;
        let seed = r.u64()?;
        let n_g = if v1 { 1 } else { r.u32()? as usize };
        let sizes = [r.u32()?, r.u32()?, r.u32()?, r.u32()?].map(|v| v as usize);
        let [n_eta, n_rho, n_knots, n_walks] = sizes;
        let gs = if v1 { vec![0.0] } else { r.f64s(n_g)? };
        let etas = r.f64s(n_eta)?;
        let rho = r.f64s(n_rho)?;
        let knots = r.f64s(n_knots)?;
        let edges = r.f64s(n_knots.saturating_add(1))?;
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        let want_knots = radius_knots();
        if bits(&rho) != bits(&rho_samples())
            || bits(&knots) != bits(&want_knots)
            || bits(&edges) != bits(&tally_edges(&want_knots))
            || n_g == 0
            || n_eta == 0
        {
            return bad("grids differ from this version's (regenerate with `cargo xtask tables`)");
        }
        let tables = n_g.saturating_mul(n_eta);
        let mut walks = Vec::with_capacity(tables.min(64));
        for _ in 0..tables {
            let mut row = Vec::with_capacity(n_walks.min(64));
            for _ in 0..n_walks {
                let (start, end, stream) = (r.u32()? as usize, r.u32()? as usize, r.u32()?);
                let (min_events, max_events, photons) = (r.u64()?, r.u64()?, r.u64()?);
                if !(start < end && end <= n_rho && photons > 0 && min_events <= max_events) {
                    return bad("invalid walk");
                }
                row.push(Walks {
                    rows: start..end,
                    min_events,
                    max_events,
                    photons,
                    stream: stream as usize,
                });
            }
            walks.push(row);
        }
        let rows = tables.saturating_mul(n_rho);
        let (mut total, mut total_se, mut capped_weight) = (
            Vec::with_capacity(rows.min(1 << 16)),
            Vec::with_capacity(rows.min(1 << 16)),
            Vec::with_capacity(rows.min(1 << 16)),
        );
        for _ in 0..rows {
            total.push(r.f64()?);
            total_se.push(r.f64()?);
            capped_weight.push(r.f64()?);
        }
        let cells = rows.saturating_mul(n_knots);
        let mass = r.f32s(cells)?;
        let mass_se = r.f32s(cells)?;
        if r.at != body.len() {
            return bad("trailing bytes");
        }
        let valid = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x >= 0.0);
        if !(valid(&mass)
            && valid(&mass_se)
            && valid(&total)
            && valid(&total_se)
            && valid(&capped_weight)
            && gs.iter().all(|g| g.abs() < 1.0))
        {
            return bad("a tallied value is negative or not finite");
        }
        Ok(McTableData {
            seed,
            gs,
            etas,
            rho,
            knots,
            edges,
            walks,
            mass,
            mass_se,
            total,
            total_se,
            capped_weight,
        })
    }

    /// The table embedded in the crate (`data/mc_table.bin`), parsed on first use.
    pub fn embedded() -> Result<&'static McTableData, BssrdfError> {
        static DATA: OnceLock<Result<McTableData, BssrdfError>> = OnceLock::new();
        DATA.get_or_init(|| McTableData::from_bytes(EMBEDDED))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The master seed of the walks.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The anisotropy of each table ([`GS`]).
    pub fn gs(&self) -> &[f64] {
        &self.gs
    }

    /// The η of each table ([`ETAS`]).
    pub fn etas(&self) -> &[f64] {
        &self.etas
    }

    /// The index of the table of `gs()[g_index]` and `etas()[eta_index]`, the `t` of the
    /// accessors below.
    pub fn table_index(&self, g_index: usize, eta_index: usize) -> usize {
        g_index * self.etas.len() + eta_index
    }

    /// The albedo rows ([`rho_samples`]): single-scattering albedos for g = 0, reduced
    /// albedos otherwise.
    pub fn rho_samples(&self) -> &[f64] {
        &self.rho
    }

    /// The radius knots ([`radius_knots`]).
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The tally bin edges ([`tally_edges`]).
    pub fn edges(&self) -> &[f64] {
        &self.edges
    }

    /// The walks of table `t`.
    pub fn walks(&self, t: usize) -> &[Walks] {
        &self.walks[t]
    }

    fn cell(&self, t: usize, i: usize) -> Range<usize> {
        let bins = self.knots.len();
        let start = (t * self.rho.len() + i) * bins;
        start..start + bins
    }

    /// The tallied bin masses ∫ 2πx R_d¹ dx of table `t`, albedo row `i`.
    pub fn mass(&self, t: usize, i: usize) -> &[f64] {
        &self.mass[self.cell(t, i)]
    }

    /// Standard errors of [`McTableData::mass`].
    pub fn mass_se(&self, t: usize, i: usize) -> &[f64] {
        &self.mass_se[self.cell(t, i)]
    }

    /// The tallied total reflectance (all radii) of table `t`, albedo row `i`, and its
    /// standard error.
    pub fn total(&self, t: usize, i: usize) -> (f64, f64) {
        let k = t * self.rho.len() + i;
        (self.total[k], self.total_se[k])
    }

    /// The weight per photon lost to the event cap of the walk (table `t`, row `i`).
    pub fn capped_weight(&self, t: usize, i: usize) -> f64 {
        self.capped_weight[t * self.rho.len() + i]
    }
}

/// A little-endian reader over a byte slice that reports truncation as an error.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], BssrdfError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(BssrdfError::InvalidArgument(
                "mc-table data: truncated".into(),
            ));
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u32(&mut self) -> Result<u32, BssrdfError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self) -> Result<u64, BssrdfError> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }

    fn f64(&mut self) -> Result<f64, BssrdfError> {
        Ok(f64::from_bits(self.u64()?))
    }

    fn f64s(&mut self, n: usize) -> Result<Vec<f64>, BssrdfError> {
        let b = self.take(n.saturating_mul(8))?;
        Ok(b.chunks_exact(8)
            .map(|c| {
                let mut a = [0u8; 8];
                a.copy_from_slice(c);
                f64::from_le_bytes(a)
            })
            .collect())
    }

    fn f32s(&mut self, n: usize) -> Result<Vec<f64>, BssrdfError> {
        let b = self.take(n.saturating_mul(4))?;
        Ok(b.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
            .collect())
    }
}
