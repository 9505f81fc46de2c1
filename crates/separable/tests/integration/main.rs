//! The integration tests of `sss-separable`, one module per file, linked into one test binary:
//! each binary links the whole dependency graph, so one per crate instead of one per file
//! saves most of the suite's link time. Run one file's tests with
//! `cargo test -p sss-separable --test integration <module>::`.

mod common;
mod energy;
mod fits;
mod guided;
mod mm_response;
mod preintegrated;
mod properties;
mod screen_space;
mod screen_space_random;
mod screen_space_rows;
mod shader_export;
mod svd;
mod taps;
