//! The separable-kernel experiment (Jimenez et al. 2015): for each material and each kernel
//! method, with importance-sampled and uniform taps, the number of 1D passes and taps per
//! pixel, the time to filter a 1920×1080 frame with all threads and with one, and the error
//! against the exact 2D screen-space convolution with the full kernel at the same footprint
//! (on a 256×256 test image holding a diagonal shadow edge and a small bright spot).
//!
//! Writes `kernels.csv`, `singular_values.png`, `kernel_error_vs_time.png`, and under
//! `kernels/` the shadow-edge test (input, exact 2D, pre-integrated, their error) and the
//! point-light response with and without rotation jitter. Against the world-space `exact`
//! reference: every kernel (7 taps, importance and uniform) on the `sphere` (skin1) and `slab`
//! (marble) scenes, reusing the scenes experiment's cached references; the tap-count sweep is
//! the `separable` method of the scenes experiment.

mod frames;
mod images;
mod report;
mod runs;
mod world;

use super::output::{Csv, csv_num, csv_text, md_num, md_table};
use super::{Context, Error, Experiment, Section};
use frames::*;
use images::*;
use report::*;
use runs::*;
use sss_bssrdf::{Bssrdf, Medium, ModelKind, Rgb, make_model};
use sss_plot::{PALETTE, Series, SeriesStyle, line_plot, write_error_map};
use sss_render::image::{auto_exposure, write_png};
use sss_render::kernel_choice::{KernelMethod, MaterialKernel, SeparableSettings, build_kernel};
use sss_separable::{
    FilterOptions, Kernel2d, Kernel2dSpec, NO_OBJECT, ScreenInput, SeparableKernel, TapPlacement,
    artist, convolve2d, screen_space, svd,
};
use std::path::Path;
use std::time::Instant;
use world::*;

/// The separable-kernel experiment.
pub struct KernelComparison;

/// What a full or `--quick` run covers.
struct Plan {
    materials: &'static [&'static str],
    /// The timed frame's size.
    frame: (usize, usize),
    /// Cells per side of the full 2D kernel the exact convolution uses: the brute-force 2D
    /// convolution costs cells² per pixel, and took 18 s a material on 2 cores at 127; the
    /// quick run's 63 (cells twice as wide, the same 99 % energy radius) is a quarter of it.
    cells: usize,
}

/// The plan of a full or `--quick` run.
fn plan(quick: bool) -> Plan {
    if quick {
        Plan {
            materials: &["skin1", "marble"],
            frame: (480, 270),
            cells: 63,
        }
    } else {
        Plan {
            materials: &["skin1", "marble", "ketchup", "skimmilk"],
            frame: (1920, 1080),
            cells: Kernel2dSpec::default().cells,
        }
    }
}

impl Experiment for KernelComparison {
    fn name(&self) -> &'static str {
        "kernels"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let cfg = ctx.config;
        let Plan {
            materials,
            frame,
            cells,
        } = plan(cfg.quick);
        let spec = Kernel2dSpec {
            cells,
            ..Kernel2dSpec::default()
        };
        let big = Frame::edge(frame.0, frame.1);
        let test = Frame::edge(TEST_SIDE, TEST_SIDE);
        let all_threads = rayon::current_num_threads();
        let dir = cfg.out.join("kernels");
        std::fs::create_dir_all(&dir)
            .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
        let mut rows: Vec<Row> = Vec::new();
        let mut spectra = Vec::new();
        let mut curves = Vec::new();
        for (mi, &name) in materials.iter().enumerate() {
            (ctx.log)(&format!("kernels: {name}"));
            let medium = Medium::preset(name).map_err(|e| Error(e.to_string()))?;
            let model = make_model(ModelKind::BetterDipole, &medium);
            let runs = material_runs(name, model.as_ref(), &spec, &test, &big, all_threads, &dir)?;
            spectra.push(spectrum_series(name, &runs.spectrum, mi));
            curves.push(curve_series(name, runs.points, mi));
            rows.extend(runs.rows);
            // Point-light response with and without jitter (skin1 only shows the cross best).
            if mi == 0 {
                point_response(name, model.as_ref(), &dir)?;
            }
        }
        rows.extend(production_runs(&big, all_threads)?);
        let world = world_space(ctx)?;
        plots(&cfg.out, &spectra, &curves, frame, all_threads)?;
        csv(&rows, frame).write(&cfg.out.join("kernels.csv"))?;
        Ok(section(&rows, &world, frame, cells))
    }
}
