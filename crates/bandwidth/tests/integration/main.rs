//! The integration tests of `sss-bandwidth`, one module per file, linked into one test binary:
//! each binary links the whole dependency graph, so one per crate instead of one per file
//! saves most of the suite's link time. Run one file's tests with
//! `cargo test -p sss-bandwidth --test integration <module>::`.

mod curvature;
mod models;
mod spectrum;
mod transport;
