//! The integration tests of `sss-render`, one module per file, linked into one test binary:
//! each binary links the whole dependency graph, so one per crate instead of one per file
//! saves most of the suite's link time. Run one file's tests with
//! `cargo test -p sss-render --test integration <module>::`.

mod angular_albedo;
mod bounded_resources;
mod closed_forms;
mod common;
mod disk_average;
mod dual_tree_fmm;
mod entry_drift;
mod exr_budget;
mod flip_evaluator;
mod fuzz_regressions;
mod integrator_contract;
mod interreflection;
mod local_radius;
mod manylight;
mod metrics_by_hand;
mod pathological_geometry;
mod pathtrace_bias;
mod ray_casting;
mod render;
mod scene_framing;
mod separable_fast_path;
mod sparse_manylight;
mod sphere_profile;
mod subset_reference;
mod trees;
mod unscattered;
mod volpath;
mod volpath_mcml;
mod volpath_mitsuba;
