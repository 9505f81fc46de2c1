//! Helpers shared by the scene-loading tests: a minimal scene head, mesh invariants and
//! measures, and finding a line in a scene's text.

// Each test file is its own crate and uses only some of these.
#![allow(dead_code)]

use glam::DVec3;
use sss_scene::{LoadOptions, Mesh};

pub fn no_dirs() -> LoadOptions {
    LoadOptions::default()
}

/// A camera, a light and a diffuse material `m`; objects are appended.
pub const HEAD: &str = r#"[camera]
position = [0.0, 0.0, 10.0]
target = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [16, 12]

[[lights]]
type = "point"
position = [0.0, 5.0, 5.0]
intensity = 1.0

[materials.m]
type = "diffuse"
albedo = 0.5
"#;

/// The invariants every loaded mesh must satisfy.
pub fn check_mesh(m: &Mesh) {
    assert!(!m.triangles.is_empty());
    assert_eq!(m.positions.len(), m.normals.len());
    let mut used = vec![false; m.positions.len()];
    for t in &m.triangles {
        for &i in t {
            assert!((i as usize) < m.positions.len());
            used[i as usize] = true;
        }
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!(
            (b - a).cross(c - a).length() > 0.0,
            "degenerate triangle {t:?}"
        );
    }
    assert!(used.iter().all(|&u| u), "unused vertices");
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(p.is_finite());
        assert!((n.length() - 1.0).abs() < 1e-9, "normal {n} is not unit");
    }
}

pub fn area(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Enclosed volume by the divergence theorem: Σ a·(b × c) / 6.
pub fn volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

pub fn bbox(m: &Mesh) -> (DVec3, DVec3) {
    m.positions
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
}

/// The 1-based line of the first line of `text` containing `needle`; `needle#n` means the
/// n-th such line.
pub fn line_of(text: &str, needle: &str) -> usize {
    let (needle, nth) = match needle.rsplit_once('#') {
        Some((n, k)) if k.parse::<usize>().is_ok() => (n, k.parse::<usize>().unwrap()),
        _ => (needle, 1),
    };
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.contains(needle))
        .nth(nth - 1)
        .unwrap_or_else(|| panic!("`{needle}` #{nth} not in the text"))
        .0
        + 1
}
