//! The integration tests of `sss-manylight`, one module per file, linked into one test binary:
//! each binary links the whole dependency graph, so one per crate instead of one per file
//! saves most of the suite's link time. Run one file's tests with
//! `cargo test -p sss-manylight --test integration <module>::`.

mod baselines;
mod bounds;
mod common;
mod cone;
mod estimator;
mod refinement;
mod vpl;
