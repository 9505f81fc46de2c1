//! # sss-py: the toolkit from Python (module `sss`)
//!
//! Python bindings (PyO3, numpy) for researchers who work in Python: the BSSRDF models and
//! their Monte Carlo reference, the measured presets, the separable kernels and their shader
//! exports, the screen-space filter on arrays a user already has (e.g. AOVs of another
//! renderer), scene renders with any registered method, and the image metrics of `sss diff`.
//! Every function calls the library functions the `sss` command-line tool calls (in
//! `sss-bssrdf`, `sss-separable`, `sss-scene` and `sss-render`; nothing here depends on the
//! binary crate), so a value from Python is the value `sss` prints or writes.
//!
//! Built with maturin as one abi3 wheel for CPython ≥ 3.10:
//!
//! ```text
//! python3 -m venv .venv && .venv/bin/pip install maturin numpy
//! .venv/bin/maturin build --release -m crates/python/Cargo.toml -o target/wheels && .venv/bin/pip install target/wheels/sss_py-*.whl
//! ```
//!
//! ```python
//! import numpy as np, sss
//!
//! skin = sss.Model("better-dipole", preset="skin1")
//! r = np.linspace(0.01, 5.0, 200)
//! rd = skin.rd(r)                                  # float64 (200, 3), 1/mm²
//! r_mc, rd_mc, se = sss.monte_carlo(preset="skin1", r_max=5.0, bins=50, photons=100_000)
//! glsl = sss.kernel(skin, "preintegrated", taps=9).export("glsl")
//! out = sss.render("sphere", method="pathtrace", spp=4,
//!                  progress=lambda done, total: None)
//! img = out["total"]                               # float32 (H, W, 3)
//! print(sss.diff(out["subsurface"], sss.render("sphere")["subsurface"]))
//! ```
//!
//! Conventions: profiles are float64, images float32 `(H, W, 3)` row-major from the top-left;
//! lengths in mm. Arrays of another dtype or shape are refused (`TypeError` for the type or
//! dtype, `ValueError` for the shape) with a message naming the argument; strided arrays are
//! copied. Errors of the Rust side keep the one-line message `sss` prints, in Python's terms
//! (the keyword `max_samples` where `sss` names `--max-samples`): `ValueError` for bad
//! input, `OSError` for files (a subclass such as `FileNotFoundError` where the cause is known),
//! `RuntimeError` for a non-finite model value; a panic is caught and raised as
//! `RuntimeError`, never as PyO3's `PanicException`.
//! `render` and `monte_carlo` release the GIL, call an optional `progress(done, total)` on the
//! calling thread every 0.1 s, and stop on Ctrl-C (`KeyboardInterrupt`) or when `progress`
//! raises (see [`progress`] for how the work is stopped); `filter`, `kernel` and `read_exr`
//! release the GIL too.
//!
//! ## In the workspace, tested from Python
//! A member of the root workspace (not a default member), so `cargo fmt --all` and `cargo
//! clippy --workspace` check it and the wheel's build reuses the workspace's artifacts. It is
//! an extension module (`PYO3_BUILD_EXTENSION_MODULE`, set in `.cargo/config.toml` as maturin
//! sets it): Python's symbols come from the interpreter that imports it, so no Rust test
//! binary can link it (`test = false`). `ci.sh` beside this manifest builds the wheel with
//! maturin and runs the pytest suite in a fresh virtual environment.

pub mod arrays;
pub mod errors;
pub mod files;
pub mod kernel;
pub mod model;
pub mod progress;
pub mod render;
pub mod scene;

/// Subsurface scattering on numpy arrays: BSSRDF models (`Model`), their Monte Carlo reference
/// (`monte_carlo`), the measured `presets`, separable kernels and their shader text (`kernel`),
/// the screen-space filter on your own AOVs (`filter`), scenes as objects (`load_dict`,
/// `load_file`, `Scene`), scene renders (`render`), EXR layers
/// (`read_exr`, `write_exr`), PNG pictures (`write_png`) and the image metrics of `sss diff`
/// (`diff`). Profiles are float64, images
/// float32 (H, W, 3); lengths in mm.
#[pyo3::pymodule(name = "sss")]
pub mod sss_module {
    #[pymodule_export]
    use crate::files::{write_exr, write_png};
    #[pymodule_export]
    use crate::kernel::{Kernel, filter, kernel};
    #[pymodule_export]
    use crate::model::{Model, monte_carlo, presets};
    #[pymodule_export]
    use crate::render::{diff, read_exr_layers, render};
    #[pymodule_export]
    use crate::scene::{Scene, load_dict, load_file};

    use pyo3::prelude::*;

    /// Module attributes: the version and the names of the models, kernels, methods and
    /// built-in scenes.
    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        m.add("__version__", env!("CARGO_PKG_VERSION"))?;
        let models: Vec<&str> = sss_bssrdf::ModelKind::ALL
            .iter()
            .map(|k| k.name())
            .collect();
        m.add("MODELS", models)?;
        m.add(
            "KERNELS",
            sss_render::kernel_choice::KernelMethod::NAMES.to_vec(),
        )?;
        let methods: Vec<&str> = sss_render::integrators::METHODS
            .iter()
            .map(|m| m.name)
            .collect();
        m.add("METHODS", methods)?;
        let scenes: Vec<&str> = sss_render::scene::BUILTIN_SCENES
            .iter()
            .map(|(n, _)| *n)
            .collect();
        m.add("BUILTIN_SCENES", scenes)?;
        Ok(())
    }
}
