//! The integration tests of `sss-bssrdf`, one module per file, linked into one test binary:
//! each binary links the whole dependency graph, so one per crate instead of one per file
//! saves most of the suite's link time. Run one file's tests with
//! `cargo test -p sss-bssrdf --test integration <module>::`.

mod christensen_burley;
mod extremes;
mod fresnel_literature;
mod mc_table;
mod mcml;
mod models;
mod monte_carlo_refractive;
mod pinned_accuracy;
mod rd_derivatives;
mod sampling_at_table_speed;
