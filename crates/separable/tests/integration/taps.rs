//! Importance-sampled taps (Jimenez et al. 2015, §6 and Figure 11): 7 taps from the dominant
//! channel's CDF are closer to a 513-tap uniform reference than 7 uniform taps.

use crate::common;

use sss_separable::screen_space::{self, FilterOptions};
use sss_separable::{Kernel1d, SeparableKernel, preintegrated, taps};

#[test]
fn seven_importance_sampled_taps_beat_seven_uniform_taps() {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 127);
    let profile = preintegrated::profile(&k);
    // A textured, pore-like irradiance at 0.1 mm per pixel (the kernel spans ±140 pixels).
    let mut f = common::Frame::flat(256, 256, 0.1);
    f.set_irradiance(|x, y| {
        let pores = if common::hash01(x, y) < 0.1 { 0.0 } else { 1.0 };
        let checker = if (x / 32 + y / 32) % 2 == 0 { 1.0 } else { 0.3 };
        pores * checker
    });
    let opts = FilterOptions {
        jitter_radius: 0.0,
        ..Default::default()
    };
    let run = |t: Kernel1d| {
        let kernel = SeparableKernel::symmetric(&t, k.total, k.half_width_mm()).unwrap();
        screen_space::filter(&f.input(), &kernel, &opts).unwrap()
    };
    let reference = run(taps::uniform(&profile, 513).unwrap());
    let error = |out: &[[f32; 3]]| -> [f64; 3] {
        std::array::from_fn(|c| {
            let (mut e, mut n) = (0.0, 0.0);
            for (a, b) in out.iter().zip(&reference) {
                e += (a[c] as f64 - b[c] as f64).powi(2);
                n += (b[c] as f64).powi(2);
            }
            (e / n).sqrt()
        })
    };
    let is7 = error(&run(taps::importance(&profile, 7, None).unwrap()));
    let u7 = error(&run(taps::uniform(&profile, 7).unwrap()));
    for c in 0..3 {
        assert!(
            is7[c] < u7[c],
            "channel {c}: importance {is7:?} uniform {u7:?}"
        );
    }
}

#[test]
fn taps_are_placed_from_the_widest_channel() {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 63);
    let p = preintegrated::profile(&k);
    // Red scatters farthest in skin.
    assert_eq!(taps::dominant_channel(&p), 0);
    let t = taps::importance(&p, 7, None).unwrap();
    let red = p.total()[0];
    for tap in &t.taps {
        assert!((tap.weight[0] - red / 7.0).abs() < 1e-12 * red);
    }
}
