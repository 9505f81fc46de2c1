//! BSSRDF-aware against Max-Extent cluster selection (the paper's Table 3 question) on a
//! synthetic scene in the paper's regime: a finely tessellated bumpy plate, a short profile,
//! 16 shading points per pixel inside a small footprint, and an area light sampled into VPLs.
//!
//! `cargo run --release -p sss-manylight --example selection -- [grid] [vpls] [pixels] [eps]
//! [ref_eps]` (defaults 64, 1024, 32, 0.02, ε/20). Prints triplets, splits and time per pixel
//! for both selections, and the fraction of pixels within ε of a reference rendered with the
//! same method at `ref_eps` (the paper's estimation accuracy).
//!
//! Measured on the project machine (2 shared cores, other builds running, so times are noisy),
//! `… --example selection -- 64 1024 200 EPS 0.001` (8192 triangles, 1024 VPLs, 200 pixels):
//!
//! | ε | BSSRDF-aware triplets / ms / within ε | Max-Extent triplets / ms / within ε |
//! |---|---|---|
//! | 10 % | 80 / 1.5 / 89.0 % | 540 / 5.3 / 92.5 % |
//! | 5 % | 190 / 1.5 / 93.5 % | 1214 / 9.1 / 92.5 % |
//! | 2 % | 709 / 5.1 / 96.0 % | 3542 / 8.1 / 93.5 % |
//! | 1 % | 1855 / 8.4 / 95.0 % | 8462 / 25.2 / 94.5 % |
//!
//! Max-Extent needs 4.6–6.8× the triplets (the paper's Table 3: 1.8–7.7×); with 200 pixels
//! the accuracy's binomial standard error is about 1.5 points.

use std::time::Instant;

use glam::DVec3;
use sss_manylight::*;

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |k: usize, d: f64| args.get(k).and_then(|s| s.parse().ok()).unwrap_or(d);
    let grid = arg(0, 64.0) as u32;
    let n_vpls = arg(1, 1024.0) as usize;
    let pixels = arg(2, 32.0) as u64;
    let eps = arg(3, 0.02);
    let ref_eps = arg(4, eps / 20.0);

    // A 1 × 1 plate with a gentle bump, (grid × grid × 2) triangles, normal +z.
    let h = |x: f64, y: f64| 0.05 * (6.0 * x).sin() * (4.0 * y).cos();
    let mut pos = Vec::new();
    for j in 0..=grid {
        for i in 0..=grid {
            let (x, y) = (
                f64::from(i) / f64::from(grid),
                f64::from(j) / f64::from(grid),
            );
            pos.push(DVec3::new(x, y, h(x, y)));
        }
    }
    let w = grid + 1;
    let mut tris = Vec::new();
    for j in 0..grid {
        for i in 0..grid {
            let a = j * w + i;
            tris.push([a, a + 1, a + w + 1]);
            tris.push([a, a + w + 1, a + w]);
        }
    }
    let surface = TriangleClusterTree::new(&pos, &tris)?;

    // A 0.4 × 0.4 area light at height 0.6, facing down, stratified into VPLs of equal power.
    let side = (n_vpls as f64).sqrt().ceil() as usize;
    let mut vpls = Vec::new();
    for j in 0..side {
        for i in 0..side {
            let (x, y) = (
                0.3 + 0.4 * (i as f64 + 0.5) / side as f64,
                0.3 + 0.4 * (j as f64 + 0.5) / side as f64,
            );
            vpls.push(Vpl::oriented(
                DVec3::new(x, y, 0.6),
                DVec3::NEG_Z,
                [1.0 / (side * side) as f64; 3],
            ));
        }
    }
    let lights = LightTree::new(vpls)?;

    // A dipole-like profile with mean free paths of a few hundredths of the plate.
    let profile = RadialProfile::new(
        |r| {
            [(30.0, 0.02), (60.0, 0.01), (120.0, 0.005)].map(|(s, z): (f64, f64)| {
                let d = (r * r + z * z).sqrt();
                z * (1.0 + s * d) * (-s * d).exp() / (d * d * d)
            })
        },
        2.0,
    )?;
    let ft = Transmittance::new(|c| 1.0 - 0.04 * (1.0 - c).powi(5))?;
    let t = StudentT::new(0.95)?;
    let vis = |_: DVec3, _: DVec3| true;

    // Pixels: 16 shading points in a 1/256-wide footprint at scattered places.
    let foot = 1.0 / 256.0;
    let pixel = |k: u64| -> Result<ShadingTree, Error> {
        let (cx, cy) = (
            0.1 + 0.8 * frac(k as f64 * 0.618_034),
            0.1 + 0.8 * frac(k as f64 * 0.414_214),
        );
        let pts = (0..16)
            .map(|s| {
                let (x, y) = (
                    cx + foot * ((s % 4) as f64 + 0.5) / 4.0,
                    cy + foot * ((s / 4) as f64 + 0.5) / 4.0,
                );
                ShadingPoint {
                    position: DVec3::new(x, y, h(x, y)),
                    normal: DVec3::Z,
                    weight: 1.0 / 16.0,
                }
            })
            .collect();
        ShadingTree::new(pts)
    };

    let mut reference = Vec::new();
    {
        let mut st = Settings::new(Settings::g_max_for_scene(0.75));
        st.epsilon = ref_eps;
        st.max_triplets = 2_000_000;
        st.max_splits = 1 << 20;
        let est = Estimator::new(&lights, &surface, &profile, &ft, &t, st)?;
        let t0 = Instant::now();
        for k in 0..pixels {
            let px = est.estimate(&pixel(k)?, &vis, pixel_seed(1000, k));
            reference.push(px.value);
        }
        println!(
            "reference (ε = {ref_eps}): {:.2} s for {pixels} pixels",
            t0.elapsed().as_secs_f64()
        );
    }
    println!(
        "grid {grid} ({} triangles), {} VPLs, {pixels} pixels, ε = {eps}, α = 0.95",
        tris.len(),
        lights.vpls().len()
    );
    println!("selection      triplets/px  splits/px  ms/px  within-ε  statuses");
    for sel in [Selection::BssrdfAware, Selection::MaxExtent] {
        let mut st = Settings::new(Settings::g_max_for_scene(0.75));
        st.epsilon = eps;
        st.selection = sel;
        st.max_triplets = 2_000_000;
        st.max_splits = 1 << 20;
        let est = Estimator::new(&lights, &surface, &profile, &ft, &t, st)?;
        let (mut trip, mut splits, mut ok) = (0usize, 0usize, 0usize);
        let mut statuses = std::collections::BTreeMap::new();
        let t0 = Instant::now();
        for k in 0..pixels {
            let px = est.estimate(&pixel(k)?, &vis, pixel_seed(7, k));
            trip += px.triplets;
            splits += px.splits;
            if (px.value - reference[k as usize]).abs() < eps * reference[k as usize] {
                ok += 1;
            }
            *statuses.entry(format!("{:?}", px.status)).or_insert(0) += 1;
        }
        let ms = t0.elapsed().as_secs_f64() * 1e3 / pixels as f64;
        println!(
            "{:<14} {:>11.0} {:>10.0} {:>6.2} {:>8.1}%  {statuses:?}",
            format!("{sel:?}"),
            trip as f64 / pixels as f64,
            splits as f64 / pixels as f64,
            ms,
            100.0 * ok as f64 / pixels as f64
        );
    }
    Ok(())
}

fn frac(x: f64) -> f64 {
    x - x.floor()
}
