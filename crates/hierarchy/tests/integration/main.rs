//! The integration tests of `sss-hierarchy`, one module per file, linked into one test binary:
//! each binary links the whole dependency graph, so one per crate instead of one per file
//! saves most of the suite's link time. Run one file's tests with
//! `cargo test -p sss-hierarchy --test integration <module>::`.

mod blue_noise;
mod bvh;
mod common;
mod point_trees;
