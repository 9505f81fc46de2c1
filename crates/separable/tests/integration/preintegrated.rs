//! The pre-integrated kernel (Jimenez et al. 2015, §4, Eq. 4–5) is exact for additively
//! separable irradiance, E(x, y) = E₁(x) + E₂(y).

use crate::common;

use sss_separable::screen_space::{self, FilterOptions};
use sss_separable::{Rgb, TapPlacement, convolve2d, preintegrated};

fn max_relative_difference(a: &[Rgb], b: &[Rgb]) -> f64 {
    let peak = a
        .iter()
        .flat_map(|p| p.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0f64, f64::max);
    worst / peak
}

#[test]
fn pre_integrated_equals_the_2d_convolution_for_additively_separable_irradiance() {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 63);
    let pre = preintegrated::kernel(&k, TapPlacement::Grid).unwrap();
    let (w, h) = (150, 110);
    type Image = Box<dyn Fn(usize, usize) -> f64>;
    let images: [(&str, Image); 3] = [
        (
            "vertical edge",
            Box::new(|x, _| if x < 70 { 1.0 } else { 0.0 }),
        ),
        (
            "horizontal edge",
            Box::new(|_, y| if y < 40 { 1.0 } else { 0.0 }),
        ),
        (
            "E1(x) + E2(y)",
            Box::new(|x, y| {
                (if x % 23 < 9 { 1.0 } else { 0.2 }) + 0.5 * (y as f64 * 0.3).sin().abs()
            }),
        ),
    ];
    for (name, f) in images {
        let img: Vec<Rgb> = (0..w * h)
            .map(|i| {
                let v = f(i % w, i / w);
                [v, 0.5 * v, 2.0 * v]
            })
            .collect();
        let exact = convolve2d::grid_full(&img, w, h, &k).unwrap();
        let sep = convolve2d::grid_separable(&img, w, h, &pre, k.cell_mm).unwrap();
        let d = max_relative_difference(&exact, &sep);
        assert!(d < 1e-6, "{name}: relative difference {d:e}");
    }
    // Negative control: a diagonal edge is not additively separable, and there the rank-1
    // kernel differs from the radial one (it is not exact "for arbitrary orientation").
    let img: Vec<Rgb> = (0..w * h)
        .map(|i| [if i % w + i / w < 130 { 1.0 } else { 0.0 }; 3])
        .collect();
    let exact = convolve2d::grid_full(&img, w, h, &k).unwrap();
    let sep = convolve2d::grid_separable(&img, w, h, &pre, k.cell_mm).unwrap();
    assert!(max_relative_difference(&exact, &sep) > 1e-3);
}

#[test]
fn screen_space_pre_integrated_pass_matches_the_exact_screen_space_convolution_on_an_edge() {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 41);
    let pre = preintegrated::kernel(&k, TapPlacement::Grid).unwrap();
    // One pixel per kernel cell: every tap lands on a pixel centre.
    let mut f = common::Frame::flat(90, 60, k.cell_mm as f32);
    f.set_irradiance(|x, _| if x < 45 { 1.0 } else { 0.0 });
    let opts = FilterOptions {
        jitter_radius: 0.0,
        ..Default::default()
    };
    let fast = screen_space::filter(&f.input(), &pre, &opts).unwrap();
    let exact = convolve2d::exact(&f.input(), &k, &opts).unwrap();
    let to64 = |v: &[[f32; 3]]| -> Vec<Rgb> { v.iter().map(|p| p.map(f64::from)).collect() };
    let d = max_relative_difference(&to64(&exact), &to64(&fast));
    // f32 buffers and accumulation: a few ulps of the 41-tap sums.
    assert!(d < 1e-5, "relative difference {d:e}");
}
