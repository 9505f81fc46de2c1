//! The integration tests of `sss-scene`, one module per file, linked into one test binary:
//! each binary links the whole dependency graph, so one per crate instead of one per file
//! saves most of the suite's link time. Run one file's tests with
//! `cargo test -p sss-scene --test integration <module>::`.
//!
//! Kept apart: `mesh_dirs_env.rs`, which sets `SSS_MESH_DIR` for its process (a variable the
//! other tests' scene loads would read).

mod builtin_scenes;
mod common;
mod obj_meshes;
mod shapes;
mod textures;
mod validation;
