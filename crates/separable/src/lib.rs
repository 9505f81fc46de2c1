//! # sss-separable (placeholder, being written)
