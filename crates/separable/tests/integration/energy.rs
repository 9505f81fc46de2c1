//! Every kernel conserves energy: its weights sum (in 2D) to the model's total diffuse
//! reflectance per channel, or to 1 with `Energy::Unit`.

use crate::common;

use sss_separable::gaussians;
use sss_separable::guided::{self, GuidedOptions};
use sss_separable::screen_space::{self, FilterOptions};
use sss_separable::{
    Energy, Kernel2d, Kernel2dSpec, SeparableKernel, TapPlacement, artist, preintegrated, svd,
};

fn all_kernels(k: &Kernel2d, model: &dyn sss_bssrdf::Bssrdf) -> Vec<(String, SeparableKernel)> {
    let mut out = Vec::new();
    for placement in [
        TapPlacement::Grid,
        TapPlacement::Uniform(7),
        TapPlacement::Importance(7),
        TapPlacement::Importance(4),
    ] {
        out.push((
            format!("pre-integrated {placement:?}"),
            preintegrated::kernel(k, placement).unwrap(),
        ));
    }
    let s = svd::decompose(k).unwrap();
    for rank in 1..=6 {
        out.push((
            format!("svd rank {rank}"),
            s.separable(rank, TapPlacement::Grid).unwrap(),
        ));
        out.push((
            format!("svd rank {rank} uniform 9"),
            s.separable(rank, TapPlacement::Uniform(9)).unwrap(),
        ));
    }
    for p in artist::PRESETS {
        out.push((
            format!("artist {}", p.name),
            artist::kernel(&p.params, k.total, TapPlacement::Importance(7)).unwrap(),
        ));
    }
    let fitted = artist::fit(&preintegrated::profile(k)).unwrap();
    out.push((
        "artist fitted".into(),
        artist::kernel(&fitted.params, k.total, TapPlacement::Grid).unwrap(),
    ));
    for fit in gaussians::fit_model(model, 6).unwrap() {
        out.push((
            format!("{} gaussians", fit.len()),
            fit.kernel(k.total, TapPlacement::Importance(7)).unwrap(),
        ));
    }
    for kk in [0.0, 2.0, 4.0] {
        let g = guided::optimize(
            k,
            &GuidedOptions {
                k: kk,
                ..Default::default()
            },
        )
        .unwrap();
        out.push((
            format!("guided k={kk}"),
            g.kernel(TapPlacement::Importance(7)).unwrap(),
        ));
    }
    out
}

#[test]
fn every_kernel_sums_to_the_total_diffuse_reflectance() {
    for preset in ["skin1", "ketchup"] {
        let m = common::model(preset);
        let k = common::kernel2d(m.as_ref(), 63);
        for (name, kernel) in all_kernels(&k, m.as_ref()) {
            assert!(kernel.is_finite(), "{preset} {name}");
            let t = kernel.total_weight();
            for c in 0..3 {
                let want = m.total_diffuse_reflectance(c);
                assert!(
                    ((t[c] - want) / want).abs() < 1e-12,
                    "{preset} {name} channel {c}: {} vs {want}",
                    t[c]
                );
            }
            let unit = kernel.with_energy([1.0; 3]).unwrap().total_weight();
            assert!(
                unit.iter().all(|u| (u - 1.0).abs() < 1e-12),
                "{name}: {unit:?}"
            );
        }
    }
}

#[test]
fn unit_energy_kernels_sum_to_one() {
    let m = common::model("marble");
    let k = Kernel2d::from_model(
        m.as_ref(),
        &Kernel2dSpec {
            cells: 31,
            energy: Energy::Unit,
            ..Default::default()
        },
    )
    .unwrap();
    for kernel in [
        preintegrated::kernel(&k, TapPlacement::Importance(7)).unwrap(),
        svd::decompose(&k)
            .unwrap()
            .separable(3, TapPlacement::Grid)
            .unwrap(),
    ] {
        assert!(
            kernel
                .total_weight()
                .iter()
                .all(|t| (t - 1.0).abs() < 1e-12)
        );
    }
}

#[test]
fn the_screen_space_pass_reproduces_a_constant_irradiance_times_the_reflectance() {
    // Energy conservation seen through the filter, for every kernel (signed SVD terms too),
    // with jitter on and clamp-to-edge borders.
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 31);
    let mut f = common::Frame::flat(40, 30, 0.4);
    f.set_irradiance(|_, _| 2.0);
    let opts = FilterOptions {
        jitter_radius: 1.0,
        ..Default::default()
    };
    for (name, kernel) in all_kernels(&k, m.as_ref()) {
        let out = screen_space::filter(&f.input(), &kernel, &opts).unwrap();
        let want = kernel.total_weight();
        for p in &out {
            for c in 0..3 {
                let e = 2.0 * want[c];
                assert!(
                    ((p[c] as f64 - e) / e).abs() < 2e-5,
                    "{name} channel {c}: {} vs {e}",
                    p[c]
                );
            }
        }
    }
}
