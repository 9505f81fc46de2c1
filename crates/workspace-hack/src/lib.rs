//! # sss-workspace-hack: one feature set for two workspaces
//!
//! Build-only; no code. The Python bindings (`crates/python`) are a Cargo workspace of their
//! own (see their crate doc), and Cargo unifies dependency features per workspace, so the
//! crates both workspaces build would come out with different features and be built twice in
//! the shared target directory. This crate's manifest asks for the union of the two feature
//! sets; the root workspace has it as a member and the bindings depend on it, so both resolve
//! to the same set; `xtask`, which `cargo xtask` builds alone, depends on it for the same
//! reason. Nothing else should depend on it.

#![forbid(unsafe_code)]
