//! The integration tests of `sss-cli`, one module per file, linked into one test binary:
//! each binary links the whole dependency graph, so one per crate instead of one per file
//! saves most of the suite's link time. Run one file's tests with
//! `cargo test -p sss-cli --test integration <module>::`.
//!
//! Kept apart: `filter_gpu.rs`, which the GPU step of CI builds with the `gpu` feature and
//! runs by its name.

mod cli;
#[path = "../common/mod.rs"]
mod common;
mod fuzz_regressions;
mod interrupt;
