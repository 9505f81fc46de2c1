//! Solid textures evaluated directly: checker and stripes boundaries, and the noise's bounds,
//! determinism, smoothness and variation.

use glam::DVec3;
use sss_scene::Texture;

#[test]
fn checker_and_stripes() {
    let (a, b) = ([0.9, 0.1, 0.2], [0.2, 0.3, 0.8]);
    let t = Texture::Checker { scale: 0.5, a, b };
    let e = 1e-9;
    assert_eq!(t.eval(DVec3::new(0.25, 0.25, 0.25)), a);
    assert_eq!(t.eval(DVec3::new(0.5 - e, 0.1, 0.1)), a);
    assert_eq!(
        t.eval(DVec3::new(0.5 + e, 0.1, 0.1)),
        b,
        "alternates across x = s"
    );
    assert_eq!(t.eval(DVec3::new(0.1, 0.5 + e, 0.1)), b, "and across y = s");
    assert_eq!(t.eval(DVec3::new(0.1, 0.1, -e)), b, "and across z = 0");
    assert_eq!(
        t.eval(DVec3::new(0.5 + e, 0.5 + e, 0.1)),
        a,
        "two steps: back to a"
    );
    assert_eq!(t.eval(DVec3::new(-0.25, -0.25, 0.25)), a);
    for i in 0..1000 {
        let p = DVec3::new(
            i as f64 * 0.137 - 50.0,
            i as f64 * 0.071,
            -(i as f64) * 0.093,
        );
        let v = t.eval(p);
        assert!(v == a || v == b);
    }
    let t = Texture::Stripes {
        axis: DVec3::X,
        period: 2.0,
        a,
        b,
    };
    assert_eq!(t.eval(DVec3::new(0.5, 7.0, -3.0)), a);
    assert_eq!(t.eval(DVec3::new(1.5, 7.0, -3.0)), b);
    assert_eq!(t.eval(DVec3::new(-0.5, 0.0, 0.0)), b);
    assert_eq!(t.eval(DVec3::new(2.5, 0.0, 0.0)), a);
}

#[test]
fn noise_is_smooth_bounded_and_deterministic() {
    let (a, b) = ([0.9, 0.1, 0.5], [0.2, 0.6, 0.5]);
    let t = Texture::Noise {
        scale: 0.3,
        seed: 42,
        a,
        b,
    };
    let other = Texture::Noise {
        scale: 0.3,
        seed: 43,
        a,
        b,
    };
    let mut values = Vec::new();
    let mut differs = 0;
    for i in 0..20_000 {
        let k = i as f64;
        let p = DVec3::new(
            (k * 0.618).sin() * 37.0,
            (k * 0.377).cos() * 1e4,
            k * 0.0131 - 100.0,
        );
        let v = t.eval(p);
        assert_eq!(v, t.eval(p), "deterministic");
        for ch in 0..3 {
            assert!(
                v[ch] >= a[ch].min(b[ch]) && v[ch] <= a[ch].max(b[ch]),
                "{v:?}"
            );
        }
        assert_eq!(v[2], 0.5, "a = b gives a constant channel");
        if other.eval(p) != v {
            differs += 1;
        }
        values.push(v[0]);
    }
    assert!(differs > 19_000, "the seed changes the noise ({differs})");
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    assert!(
        lo < 0.35 && hi > 0.75,
        "varies over its range: [{lo}, {hi}]"
    );
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    assert!((mean - 0.55).abs() < 0.05, "mean {mean}");
    // Smooth: a step of 1e-4 feature sizes changes the value by little (Lipschitz), and
    // values along a line change continuously.
    let mut max_jump: f64 = 0.0;
    let step = 1e-4 * 0.3;
    for i in 0..10_000 {
        let p = DVec3::new(i as f64 * step, 0.37, -1.21);
        let q = p + DVec3::new(step, 0.0, 0.0);
        max_jump = max_jump.max((t.eval(p)[0] - t.eval(q)[0]).abs());
    }
    assert!(max_jump < 0.7 * 3.0 * 1e-4, "max jump {max_jump}");
    // Varies with position on the scale of the feature size.
    let far = (0..100)
        .filter(|&i| {
            let p = DVec3::splat(i as f64 * 0.77);
            (t.eval(p)[0] - t.eval(p + DVec3::splat(0.3))[0]).abs() > 1e-3
        })
        .count();
    assert!(far > 80, "{far}");
}
