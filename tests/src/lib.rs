//! # sss-tests: cross-crate integration tests
//!
//! The tests in `tests/tests/` exercise the crates together, the way the tools use them: the
//! models of `sss-bssrdf` through its profile rows (`sss_bssrdf::profile_rows`, what `sss
//! profile` prints) and the CLI's plot of them, and the Monte Carlo reference through both. The `sss` binary's own end-to-end tests live next to
//! it in `crates/cli/tests/integration/cli.rs` (Cargo only builds a binary for tests of its package).
//!
//! ```text
//! cargo test -p sss-tests --release
//! ```
//!
//! ## Papers
//! None of its own; see `sss-bssrdf` for the models under test.
