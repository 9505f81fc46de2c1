//! # sss-hierarchy (placeholder, being written)
