//! The TOML scene format (serde structures). Being written.
