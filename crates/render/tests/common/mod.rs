//! Helpers shared by the render crate's integration tests.

pub mod rasterizer;
