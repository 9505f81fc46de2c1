//! # sss-workspace-hack: one feature set for the builds of one package alone
//!
//! Build-only; no code. Cargo unifies dependency features over the packages a command builds,
//! so a package built alone (`xtask` by `cargo xtask`, the Python bindings `crates/python`
//! by maturin) would get other feature sets than `cargo test --workspace` and rebuild the
//! crates they share in the one target directory. This crate's manifest asks for the union of
//! the feature sets; the workspace has it as a member and those two packages depend on it, so
//! every build resolves to the same set. Nothing else should depend on it.

#![forbid(unsafe_code)]
