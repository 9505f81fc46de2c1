//! Units and geometry against closed forms: the flat slab at scene scales other than
//! 1 unit = 1 mm, the G-buffer's pixel footprint and the camera projection against a pinhole
//! model written here, a quad light's irradiance against the polygon (Lambert) formula and an
//! environment light's irradiance against π L and the tilted-sky view factor.
//!
//! Every expected value is computed in this file from first principles (ray–plane
//! intersections, Fresnel equations, Lambert's polygon formula); the code under test is only
//! called to produce the value being checked.

use super::common::{diffuse, scene_of};
use glam::DVec3;
use sss_bssrdf::{Medium, ModelKind, make_model};
use sss_render::gbuffer::{GBuffer, GSample};
use sss_render::geometry::SceneGeometry;
use sss_render::integrators::exact::Exact;
use sss_render::irradiance::IrradianceSettings;
use sss_render::lights::{Incident, Receiver, gather};
use sss_render::progress::NoProgress;
use sss_render::rng::{Stream, rng};
use sss_render::scene::{Camera, Light, Material, MaterialKind, Mesh, Scene, Translucent};
use sss_render::{RenderSettings, render};
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// Scene helpers
// ---------------------------------------------------------------------------------------------

/// A rectangle centred on `centre` spanning ±`half_u` along unit `u` and ±`half_v` along unit
/// `v`, split into n × n cells, facing u × v (winding and vertex normals).
fn rect(centre: DVec3, u: DVec3, v: DVec3, half_u: f64, half_v: f64, n: u32) -> Mesh {
    let normal = u.cross(v).normalize();
    let mut positions = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let a = -half_u + 2.0 * half_u * j as f64 / n as f64;
            let b = -half_v + 2.0 * half_v * i as f64 / n as f64;
            positions.push(centre + u * a + v * b);
        }
    }
    let normals = vec![normal; positions.len()];
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let a = i * (n + 1) + j;
            let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
            // (b − a) × (c − a) ∝ u × v: counter-clockwise seen from the front.
            triangles.push([a, b, c]);
            triangles.push([b, d, c]);
        }
    }
    Mesh {
        positions,
        normals,
        triangles,
    }
}

/// A camera at `position` looking at `target`.
fn camera(position: DVec3, target: DVec3, up: DVec3, vfov_deg: f64, w: u32, h: u32) -> Camera {
    Camera {
        position,
        target,
        up,
        vfov_deg,
        width: w,
        height: h,
        pixel_samples: 1,
    }
}

// ---------------------------------------------------------------------------------------------
// An independent pinhole camera
// ---------------------------------------------------------------------------------------------

/// The textbook pinhole: forward = normalise(target − eye), right = normalise(forward × up),
/// true up = right × forward (right-handed), an image plane at unit distance whose half-height
/// is tan(vfov/2) and half-width tan(vfov/2)·W/H, pixel (px, py) counted from the top-left
/// corner, pixel centres at half-integers.
struct Pinhole {
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    half_h: f64,
    half_w: f64,
    w: f64,
    h: f64,
}

impl Pinhole {
    fn new(c: &Camera) -> Self {
        let forward = (c.target - c.position).normalize();
        let right = forward.cross(c.up).normalize();
        let up = right.cross(forward);
        let half_h = (c.vfov_deg * PI / 360.0).tan();
        Pinhole {
            eye: c.position,
            forward,
            right,
            up,
            half_h,
            half_w: half_h * c.width as f64 / c.height as f64,
            w: c.width as f64,
            h: c.height as f64,
        }
    }

    /// Image-plane coordinates (at unit distance along forward) of image position (x, y).
    fn plane_coords(&self, x: f64, y: f64) -> (f64, f64) {
        let sx = (x / self.w * 2.0 - 1.0) * self.half_w;
        let sy = (1.0 - y / self.h * 2.0) * self.half_h;
        (sx, sy)
    }

    /// Unnormalised ray direction through image position (x, y): forward + sx·right + sy·up.
    fn ray(&self, x: f64, y: f64) -> DVec3 {
        let (sx, sy) = self.plane_coords(x, y);
        self.forward + self.right * sx + self.up * sy
    }

    /// Image position of world point p (in front of the camera).
    fn project(&self, p: DVec3) -> (f64, f64) {
        let d = p - self.eye;
        let z = d.dot(self.forward);
        let sx = d.dot(self.right) / z;
        let sy = d.dot(self.up) / z;
        (
            (sx / self.half_w + 1.0) * self.w / 2.0,
            (1.0 - sy / self.half_h) * self.h / 2.0,
        )
    }

    /// The angle-free pixel size on the image plane at unit distance: 2 tan(θ/2)/H.
    fn pixel_plane_size(&self) -> f64 {
        2.0 * self.half_h / self.h
    }
}

/// Parameter t of the intersection eye + t·dir with the plane through `q` with normal `n`.
fn ray_plane(eye: DVec3, dir: DVec3, q: DVec3, n: DVec3) -> f64 {
    n.dot(q - eye) / n.dot(dir)
}

fn gsample_of(gb: &GBuffer, pixel: usize) -> GSample {
    let s = gb.pixel(pixel);
    assert_eq!(s.len(), 1, "pixel {pixel} has {} hits", s.len());
    s[0]
}

// ---------------------------------------------------------------------------------------------
// 1. The flat slab at units_per_mm ≠ 1
// ---------------------------------------------------------------------------------------------

/// Unpolarised Fresnel reflectance, written from the s/p amplitude coefficients with indices
/// n1 = 1 (outside) and n2 = η (inside).
fn fresnel_r(cos_i: f64, eta: f64) -> f64 {
    let (n1, n2) = (1.0, eta);
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    0.5 * (rs * rs + rp * rp)
}

/// c = 1 − 2 ∫₀¹ F_r(μ; η) μ dμ by composite Simpson (η > 1: no critical angle, a smooth
/// integrand; 4096 intervals leave an error far below 1e-12).
fn normalization_c(eta: f64) -> f64 {
    let n = 4096;
    let h = 1.0 / n as f64;
    let f = |mu: f64| fresnel_r(mu, eta) * mu;
    let mut s = f(0.0) + f(1.0);
    for k in 1..n {
        let w = if k % 2 == 1 { 4.0 } else { 2.0 };
        s += w * f(k as f64 * h);
    }
    1.0 - 2.0 * s * h / 3.0
}

/// The flat slab of render.rs's `flat_slab_matches_closed_form` scaled to `units_per_mm`:
/// a 40 mm square (40·u scene units) under a distant light, seen straight down from 50 mm;
/// returns (exact, closed form) at the centre pixel per channel.
fn slab(units_per_mm: f64) -> ([f64; 3], [f64; 3]) {
    let u = units_per_mm;
    let material = Material {
        name: "marble".into(),
        kind: MaterialKind::Translucent(Translucent {
            model: ModelKind::BetterDipole,
            medium: Medium::preset("marble").unwrap(),
            units_per_mm: u,
            texture: None,
            angular: Default::default(),
            sphere_radius: None,
            local_radius: false,
            drift: false,
            unscattered: false,
        }),
    };
    let e0 = [2.0, 1.0, 0.5];
    // Facing +y: Z × X = Y.
    let mesh = rect(DVec3::ZERO, DVec3::Z, DVec3::X, 20.0 * u, 20.0 * u, 8);
    let scene = scene_of(
        vec![mesh],
        material,
        vec![Light::Directional {
            direction: DVec3::NEG_Y,
            irradiance: e0,
        }],
        camera(
            DVec3::new(0.0, 50.0 * u, 0.0),
            DVec3::ZERO,
            DVec3::Z,
            2.0,
            5,
            5,
        ),
    );
    // The spacing is in mean free paths, i.e. it scales with u like the slab: the same
    // sample pattern (in mm) at every u.
    let exact = Exact {
        irradiance: IrradianceSettings {
            spacing_mfp: 0.35,
            max_samples: 1_000_000,
            light_samples: 1,
            bounces: 0,
        },
    };
    let out = render(&scene, &exact, &RenderSettings::default(), &NoProgress).unwrap();
    let got = out.subsurface[2 * 5 + 2];
    let medium = Medium::preset("marble").unwrap();
    let eta = medium.eta();
    // R_d,total: the model's own ∫ 2πr R_d(r) dr over the half-space (in 1/mm² · mm² = 1),
    // not the per-point R_d the renderer sums.
    let model = make_model(ModelKind::BetterDipole, &medium);
    // Normal incidence and normal exit: F_t(η, 1) = 1 − ((η − 1)/(η + 1))².
    let ft1 = 1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2);
    let c = normalization_c(eta);
    let closed = std::array::from_fn(|ch| {
        ft1 / (c * PI) * ft1 * e0[ch] * model.total_diffuse_reflectance(ch)
    });
    (got, closed)
}

/// The exact point sum at the centre of a large slab equals
/// F_t(η,1)/(cπ) · F_t(η,1) · E₀ · R_d,total whatever the scene scale: R_d in scene units is
/// R_d(r/u)/u² and the sample areas scale as u², so the sum is scale-free.
///
/// Margin 1 %: the sum covers a 40 mm square, not the half-space. In red (the longest
/// diffusion length, 1/σ_tr ≈ 8.5 mm for marble) the R_d mass beyond the square's 20 mm
/// half-width is ≈ 0.5 %, and the point sum's discretisation at 0.35 mean free paths adds
/// ~0.1 %; green and blue are 10× closer. A bug scaling R_d by 1/u instead of 1/u² multiplies
/// the result by u: ×0.1 (−90 %) at u = 0.1 and ×10 (+900 %) at u = 10, so it fails by two
/// orders of magnitude more than the margin.
#[test]
fn flat_slab_closed_form_at_other_scales() {
    for u in [0.1, 10.0] {
        let (got, closed) = slab(u);
        for ch in 0..3 {
            let rel = (got[ch] - closed[ch]) / closed[ch];
            eprintln!(
                "slab u = {u} channel {ch}: exact {:.6e}, closed form {:.6e}, rel {rel:+.2e}",
                got[ch], closed[ch]
            );
            assert!(
                rel.abs() < 0.01,
                "u = {u} channel {ch}: exact {} vs closed form {} ({rel:+.4})",
                got[ch],
                closed[ch]
            );
        }
    }
}

/// The Fresnel helpers of this file against values known independently: F_r = 0.04 at normal
/// incidence for η = 1.5, total reflection at grazing incidence, c = 1 without a boundary, and
/// c(1.3) against the Egan–Hilgeman fit of the internal diffuse reflectance (Jensen et al. 2001
/// Eq. 7, ≈ 1 % accurate) through the inside/outside relation 1 − F_dr(1/η) = (1 − F_dr(η))/η²,
/// i.e. c(η) = η² (1 − F_dr,fit(η)). Margin 1 %: the fit's accuracy.
#[test]
fn fresnel_helpers_match_known_values() {
    assert!((fresnel_r(1.0, 1.5) - 0.04).abs() < 1e-15);
    assert!((fresnel_r(0.0, 1.5) - 1.0).abs() < 1e-15);
    assert!((normalization_c(1.0) - 1.0).abs() < 1e-15);
    let eta: f64 = 1.3;
    let fdr_inside = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
    let want = eta * eta * (1.0 - fdr_inside);
    let c = normalization_c(eta);
    eprintln!("c(1.3) = {c:.6}, from the fit {want:.6}");
    assert!((c - want).abs() < 0.01 * want, "c(1.3) = {c} vs {want}");
}

// ---------------------------------------------------------------------------------------------
// 2. The G-buffer footprint
// ---------------------------------------------------------------------------------------------

/// Camera 5 units in front of the plane through `target`, looking down −z, 30° vertical field
/// of view, 41 × 31 pixels (odd: a pixel centre on the axis).
fn footprint_camera() -> Camera {
    let target = DVec3::new(0.3, -0.2, 0.0);
    camera(
        target + DVec3::new(0.0, 0.0, 5.0),
        target,
        DVec3::Y,
        30.0,
        41,
        31,
    )
}

/// The centre pixel of a plane seen head-on and tilted: distance 5 along the axis, footprint
/// 2·D·tan(θ/2)/H perpendicular to the ray, and (tilted) the on-surface size
/// footprint/|n·wo| against the exact distance between the hits of the rays through the
/// pixel's edges.
///
/// Margins 1e-9 relative: every quantity is a ray–plane intersection in f64 at distance 5;
/// rounding is ~1e-15 relative.
#[test]
fn footprint_of_the_centre_pixel_head_on_and_tilted() {
    let cam = footprint_camera();
    let pin = Pinhole::new(&cam);
    let target = cam.target;
    let d = 5.0;
    let a = pin.pixel_plane_size();
    let centre_pixel = (15 * 41 + 20) as usize;
    for tilt_deg in [0.0f64, 30.0, 60.0] {
        let phi = tilt_deg.to_radians();
        // Tilted about the x axis: the pixel stretches vertically on the surface.
        let n = DVec3::new(0.0, phi.sin(), phi.cos());
        let v_axis = DVec3::new(0.0, phi.cos(), -phi.sin());
        let mesh = rect(target, DVec3::X, v_axis, 8.0, 8.0, 4);
        let scene = scene_of(
            vec![mesh],
            diffuse(),
            vec![Light::Environment { radiance: [1.0; 3] }],
            cam.clone(),
        );
        let gb = GBuffer::new(&scene, &SceneGeometry::new(&scene), 1);
        let g = gsample_of(&gb, centre_pixel);
        let want_fp = d * 2.0 * (cam.vfov_deg.to_radians() / 2.0).tan() / cam.height as f64;
        eprintln!(
            "tilt {tilt_deg}°: distance {:.15}, footprint {:.15e} (pinhole {want_fp:.15e})",
            g.distance, g.footprint
        );
        assert!((g.distance - d).abs() < 1e-9 * d, "distance {}", g.distance);
        assert!(
            (g.footprint - want_fp).abs() < 1e-9 * want_fp,
            "tilt {tilt_deg}: footprint {} vs {want_fp}",
            g.footprint
        );
        assert!((g.p - target).length() < 1e-9 * d, "hit {}", g.p);
        assert!((g.n - n).length() < 1e-12 && (g.ng - n).length() < 1e-12);
        assert!((g.wo - DVec3::Z).length() < 1e-12, "wo {}", g.wo);
        // On the surface: the rays through the top and bottom edges of the centre pixel
        // (image rows 15 and 16) hit the tilted plane s_top − s_bottom apart. With T = tan φ,
        // exactly D·a(1 + T²)·cos φ / (1 − (aT/2)²) = (D·a/cos φ) / (1 − (aT/2)²): the
        // linearised size footprint/|n·wo| times a second-order correction, written here.
        let hit = |x: f64, y: f64| {
            let dir = pin.ray(x, y);
            pin.eye + dir * ray_plane(pin.eye, dir, target, n)
        };
        let along_v = (hit(20.5, 15.0) - hit(20.5, 16.0)).length();
        let along_u = (hit(21.0, 15.5) - hit(20.0, 15.5)).length();
        let t = phi.tan();
        let corr = 1.0 - (a * t / 2.0).powi(2);
        let linear = g.footprint / g.n.dot(g.wo).abs();
        eprintln!(
            "  on-surface pixel: vertical {along_v:.15e} vs footprint/|n·wo| {linear:.15e} \
             / {corr:.15}; horizontal {along_u:.15e}"
        );
        assert!(
            (along_v * corr - linear).abs() < 1e-9 * linear,
            "vertical on-surface size {along_v} vs {linear}/{corr}"
        );
        // Along the tilt axis the plane is not foreshortened: exactly the footprint.
        assert!(
            (along_u - g.footprint).abs() < 1e-9 * g.footprint,
            "horizontal on-surface size {along_u} vs {}",
            g.footprint
        );
    }
}

/// Off-centre pixels: `distance` is measured along the ray (|hit − eye|), and the footprint is
/// that distance times the centre pixel's angle 2 tan(θ/2)/H (camera.rs: `pixel_angle`). Both
/// are computed here from the pinhole and a ray–plane intersection. Margin 1e-9 relative (f64
/// intersections at distances ≈ 5).
///
/// Note: off the axis this is the centre-pixel approximation, not the exact size of the pixel
/// perpendicular to its ray, which is t·a·cos γ across and t·a·cos² γ along the radial
/// direction (γ the angle off the axis); the test prints both ratios at the corner.
#[test]
fn footprint_off_centre_is_distance_along_the_ray_times_the_pixel_angle() {
    let cam = footprint_camera();
    let pin = Pinhole::new(&cam);
    let a = pin.pixel_plane_size();
    for tilt_deg in [0.0f64, 40.0] {
        let phi = tilt_deg.to_radians();
        let n = DVec3::new(0.0, phi.sin(), phi.cos());
        let v_axis = DVec3::new(0.0, phi.cos(), -phi.sin());
        let scene = scene_of(
            vec![rect(cam.target, DVec3::X, v_axis, 8.0, 8.0, 4)],
            diffuse(),
            vec![Light::Environment { radiance: [1.0; 3] }],
            cam.clone(),
        );
        let gb = GBuffer::new(&scene, &SceneGeometry::new(&scene), 1);
        assert_eq!(gb.samples.len(), 41 * 31, "the plane fills the image");
        let mut worst = 0.0f64;
        for py in 0..31u32 {
            for px in 0..41u32 {
                let g = gsample_of(&gb, (py * 41 + px) as usize);
                let dir = pin.ray(px as f64 + 0.5, py as f64 + 0.5);
                let hit = pin.eye + dir * ray_plane(pin.eye, dir, cam.target, n);
                let dist = (hit - pin.eye).length();
                assert!(
                    (g.distance - dist).abs() < 1e-9 * dist,
                    "({px},{py}): distance {} vs {dist}",
                    g.distance
                );
                assert!((g.p - hit).length() < 1e-9 * dist);
                let want = dist * a;
                let rel = (g.footprint - want).abs() / want;
                worst = worst.max(rel);
                assert!(
                    rel < 1e-9,
                    "({px},{py}) tilt {tilt_deg}: footprint {} vs {want}",
                    g.footprint
                );
            }
        }
        // The corner pixel: how far the centre-pixel approximation is from the exact
        // perpendicular size (reported, not asserted).
        let dir = pin.ray(0.5, 0.5).normalize();
        let cos_g = dir.dot(pin.forward);
        eprintln!(
            "tilt {tilt_deg}°: worst footprint rel. error {worst:.2e}; at the corner pixel the \
             footprint is 1/cos γ = {:.4} × the exact across-size and 1/cos² γ = {:.4} × the \
             exact radial size",
            1.0 / cos_g,
            1.0 / (cos_g * cos_g)
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 3. The camera projection
// ---------------------------------------------------------------------------------------------

/// Every pixel of a general camera (off-axis eye, non-orthogonal up hint, 64 × 48, 40°) sees
/// the point of a tilted plane that an independent pinhole predicts. Margin 1e-9 of the
/// distance (f64 intersections).
#[test]
fn every_pixel_sees_the_point_the_pinhole_predicts() {
    let cam = camera(
        DVec3::new(1.0, 2.0, 6.0),
        DVec3::new(0.5, 0.8, 0.0),
        DVec3::new(0.1, 1.0, 0.2),
        40.0,
        64,
        48,
    );
    let pin = Pinhole::new(&cam);
    let n = DVec3::new(0.2, 0.3, 1.0).normalize();
    let u = DVec3::X.cross(n).normalize().cross(n).normalize();
    let v = n.cross(u);
    let scene = scene_of(
        vec![rect(cam.target, u, v, 20.0, 20.0, 4)],
        diffuse(),
        vec![Light::Environment { radiance: [1.0; 3] }],
        cam.clone(),
    );
    let gb = GBuffer::new(&scene, &SceneGeometry::new(&scene), 9);
    assert_eq!(gb.samples.len(), 64 * 48);
    for py in 0..48u32 {
        for px in 0..64u32 {
            let g = gsample_of(&gb, (py * 64 + px) as usize);
            let dir = pin.ray(px as f64 + 0.5, py as f64 + 0.5);
            let want = pin.eye + dir * ray_plane(pin.eye, dir, cam.target, n);
            let dist = (want - pin.eye).length();
            assert!(
                (g.p - want).length() < 1e-9 * dist,
                "pixel ({px},{py}): hit {} vs pinhole {want}",
                g.p
            );
            assert!((g.wo + dir.normalize()).length() < 1e-12);
            // And back: the pinhole projects the hit into the same pixel's centre.
            let (x, y) = pin.project(g.p);
            assert!(
                (x - px as f64 - 0.5).abs() < 1e-6 && (y - py as f64 - 0.5).abs() < 1e-6,
                "pixel ({px},{py}) projects back to ({x}, {y})"
            );
        }
    }
}

/// A tiny square (a fifth of a pixel wide) placed where the pinhole puts the centre of pixel
/// (px, py) is seen by that pixel and no other; up is up (a point above the target lands in a
/// row above the centre) and right is right (+x lands right of centre for a camera looking down
/// −z with up +y).
#[test]
fn known_points_land_on_known_pixels() {
    let cam = camera(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::ZERO,
        DVec3::Y,
        30.0,
        40,
        30,
    );
    let pin = Pinhole::new(&cam);
    // The expected pixels of a few world points, from the pinhole by hand: z = 0 is at depth 5,
    // half-height 5 tan 15° ≈ 1.3397, so y = 0.6 is 0.6/1.3397 · 15 ≈ 6.72 pixels above the
    // centre line (row 15 − 6.72 = 8.28 → row 8), x = 0.9 is 0.9/(1.3397·40/30) · 20 ≈ 10.08
    // pixels right (column 30).
    let half = 5.0 * (15f64).to_radians().tan();
    // World points; each one's expected pixel is derived inline below.
    let cases = [
        DVec3::new(0.0, 0.6, 0.0),
        DVec3::new(0.9, 0.0, 0.0),
        DVec3::new(-0.7, -0.45, 0.0),
        DVec3::new(0.5, 0.5, -1.0),
    ];
    for p in cases {
        let depth = 5.0 - p.z;
        let hh = depth * (15f64).to_radians().tan();
        let col = ((p.x / (hh * 40.0 / 30.0) + 1.0) * 20.0).floor() as u32;
        let row = ((1.0 - p.y / hh) * 15.0).floor() as u32;
        // Snap the object onto that pixel's centre ray (at the point's depth) so the only
        // pixel whose centre ray hits it is (col, row).
        let dir = pin.ray(col as f64 + 0.5, row as f64 + 0.5);
        let on_ray = pin.eye + dir * ((p.z - pin.eye.z) / dir.z);
        assert!(
            (on_ray - p).length() < 1.5 * depth * pin.pixel_plane_size(),
            "the pixel centre ray passes within a pixel of {p}"
        );
        let s = 0.1 * depth * pin.pixel_plane_size();
        let scene = scene_of(
            vec![rect(on_ray, DVec3::X, DVec3::Y, s, s, 1)],
            diffuse(),
            vec![Light::Environment { radiance: [1.0; 3] }],
            cam.clone(),
        );
        let gb = GBuffer::new(&scene, &SceneGeometry::new(&scene), 3);
        let hits: Vec<u32> = gb.samples.iter().map(|g| g.pixel).collect();
        assert_eq!(
            hits,
            vec![row * 40 + col],
            "{p}: expected only pixel ({col},{row})"
        );
        let (hx, hy) = (hits[0] % 40, hits[0] / 40);
        eprintln!("{p} → pixel ({hx}, {hy})");
        // Orientation straight from the G-buffer: above the target → smaller row index than
        // the centre rows (14, 15); right of it → larger column than the centre (19, 20).
        if p.y > 0.1 * half {
            assert!(hy < 14, "{p} is above the target but lands in row {hy}");
        }
        if p.y < -0.1 * half {
            assert!(hy > 15, "{p} is below the target but lands in row {hy}");
        }
        if p.x > 0.1 * half {
            assert!(
                hx > 20,
                "{p} is right of the target but lands in column {hx}"
            );
        }
        if p.x < -0.1 * half {
            assert!(
                hx < 19,
                "{p} is left of the target but lands in column {hx}"
            );
        }
    }
    // The hand numbers in the comment above, from the same formulas.
    assert_eq!(
        (
            ((1.0 - 0.6 / half) * 15.0).floor(),
            ((0.9 / (half * 4.0 / 3.0) + 1.0) * 20.0).floor()
        ),
        (8.0, 30.0)
    );
}

// ---------------------------------------------------------------------------------------------
// 4. Quad light irradiance
// ---------------------------------------------------------------------------------------------

/// Irradiance at `p` (normal `n`) from a uniform Lambertian polygon of radiance `l`, wholly
/// above the receiver's horizon: Lambert's formula E = (L/2) |Σᵢ βᵢ n·γᵢ|, βᵢ the angle
/// between the unit vectors to vertices i and i+1, γᵢ the unit normal of the plane they span.
fn polygon_irradiance(p: DVec3, n: DVec3, vertices: &[DVec3], l: f64) -> f64 {
    let k = vertices.len();
    let mut sum = 0.0;
    for i in 0..k {
        let a = (vertices[i] - p).normalize();
        let b = (vertices[(i + 1) % k] - p).normalize();
        let beta = a.dot(b).clamp(-1.0, 1.0).acos();
        let gamma = a.cross(b).normalize();
        sum += beta * n.dot(gamma);
    }
    0.5 * l * sum.abs()
}

/// The polygon formula against the textbook view factor of a rectangle parallel to a
/// differential area at one of its corners (e.g. Howell's catalogue, C-11):
/// F = 1/(2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))], E = π L F.
#[test]
fn test_polygon_formula_matches_the_corner_view_factor() {
    let (a, b, h, l): (f64, f64, f64, f64) = (1.3, 0.7, 0.9, 2.0);
    let (x, y) = (a / h, b / h);
    let f = 1.0 / (2.0 * PI)
        * (x / (1.0 + x * x).sqrt() * (y / (1.0 + x * x).sqrt()).atan()
            + y / (1.0 + y * y).sqrt() * (x / (1.0 + y * y).sqrt()).atan());
    let quad = [
        DVec3::new(0.0, 0.0, h),
        DVec3::new(a, 0.0, h),
        DVec3::new(a, b, h),
        DVec3::new(0.0, b, h),
    ];
    let e = polygon_irradiance(DVec3::ZERO, DVec3::Z, &quad, l);
    assert!((e - PI * l * f).abs() < 1e-12, "{e} vs {}", PI * l * f);
}

/// A receiver plane (a large square at z = 0 facing +z) for the gather tests.
fn receiver_scene(lights: Vec<Light>) -> Scene {
    scene_of(
        vec![rect(DVec3::ZERO, DVec3::X, DVec3::Y, 10.0, 10.0, 2)],
        diffuse(),
        lights,
        camera(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, 30.0, 4, 4),
    )
}

/// Mean and standard error of the mean of `calls` seeded estimates of channel `ch`.
fn gather_stats(
    scene: &Scene,
    at: Receiver,
    m: u32,
    calls: u64,
    seed: u64,
    ch: usize,
) -> (f64, f64, Vec<Vec<Incident>>) {
    let geom = SceneGeometry::new(scene);
    let mut all = Vec::with_capacity(calls as usize);
    let (mut s1, mut s2) = (0.0, 0.0);
    for i in 0..calls {
        let mut r = rng(seed, Stream::Irradiance, i);
        let mut packets = Vec::new();
        gather(&geom, &scene.lights, at, m, &mut r, &mut packets);
        let e: f64 = packets.iter().map(|p| p.e_cos[ch]).sum();
        s1 += e;
        s2 += e * e;
        all.push(packets);
    }
    let n = calls as f64;
    let mean = s1 / n;
    let var = (s2 / n - mean * mean).max(0.0) * n / (n - 1.0);
    (mean, (var / n).sqrt(), all)
}

/// The mean of 4000 seeded `gather` estimates (16 samples each) of a rectangle's irradiance
/// equals Lambert's polygon formula within 4 standard errors of the mean (a 4σ band: a correct
/// estimator fails it with probability ≈ 6e-5), on the axis, off the axis and for a receiver
/// tilted towards the light; the relative difference is printed.
#[test]
fn quad_light_irradiance_matches_the_polygon_formula() {
    let (w, hgt, h) = (1.6, 1.0, 0.8);
    let radiance = [3.0, 1.5, 0.25];
    // Corner and edges with edge_u × edge_v = −z: the emitting side faces the receiver.
    let corner = DVec3::new(-w / 2.0, -hgt / 2.0, h);
    let (edge_u, edge_v) = (DVec3::new(0.0, hgt, 0.0), DVec3::new(w, 0.0, 0.0));
    assert!(edge_u.cross(edge_v).z < 0.0);
    let vertices = [
        corner,
        corner + edge_u,
        corner + edge_u + edge_v,
        corner + edge_v,
    ];
    let scene = receiver_scene(vec![Light::Quad {
        corner,
        edge_u,
        edge_v,
        radiance,
    }]);
    let tilt = DVec3::new(0.3, -0.2, 1.0).normalize();
    let cases = [
        ("on the axis", DVec3::ZERO, DVec3::Z),
        ("off the axis", DVec3::new(0.5, -0.3, 0.0), DVec3::Z),
        ("tilted shading normal", DVec3::new(-0.2, 0.1, 0.0), tilt),
    ];
    for (seed, (name, p, n)) in cases.into_iter().enumerate() {
        // The tilted normal must keep the whole quad above its horizon for the formula.
        assert!(vertices.iter().all(|v| n.dot(*v - p) > 0.0));
        let at = Receiver { p, n, ng: DVec3::Z };
        for ch in [0, 2] {
            let want = polygon_irradiance(p, n, &vertices, radiance[ch]);
            let (mean, se, _) = gather_stats(&scene, at, 16, 4000, 11 + seed as u64, ch);
            let rel = (mean - want) / want;
            eprintln!(
                "quad {name} ch {ch}: mean {mean:.6e} ± {se:.2e}, polygon formula {want:.6e}, \
                 rel {rel:+.2e}, {:.2} SE",
                (mean - want) / se
            );
            assert!(
                (mean - want).abs() <= 4.0 * se,
                "{name} ch {ch}: {mean} ± {se} vs {want}"
            );
            // The estimator is not degenerate: its standard error is a small but non-zero
            // fraction of the value (so the 4σ band is meaningful).
            assert!(se > 0.0 && se < 0.01 * want, "{name}: se {se}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 5. Environment light
// ---------------------------------------------------------------------------------------------

/// With the shading normal equal to the geometric one, cosine-weighted sampling makes every
/// packet π L/m and none falls below the horizon: each estimate is π L to rounding. Margin
/// 1e-12 relative (16 additions of equal doubles).
#[test]
fn environment_irradiance_is_pi_l_per_estimate() {
    let radiance = [0.7, 1.0, 2.5];
    let scene = receiver_scene(vec![Light::Environment { radiance }]);
    let geom = SceneGeometry::new(&scene);
    for m in [1u32, 16, 64] {
        for seed in 0..50u64 {
            let mut r = rng(seed, Stream::Irradiance, seed * 7 + 1);
            let mut packets = Vec::new();
            let p = DVec3::new(0.1 * seed as f64 - 2.0, 0.3, 0.0);
            gather(
                &geom,
                &scene.lights,
                Receiver {
                    p,
                    n: DVec3::Z,
                    ng: DVec3::Z,
                },
                m,
                &mut r,
                &mut packets,
            );
            assert_eq!(packets.len(), m as usize, "m = {m} seed {seed}");
            for ch in 0..3 {
                let e: f64 = packets.iter().map(|p| p.e_cos[ch]).sum();
                let want = PI * radiance[ch];
                assert!(
                    (e - want).abs() < 1e-12 * want,
                    "m = {m} seed {seed} ch {ch}: {e} vs π L = {want}"
                );
            }
            assert!(
                packets
                    .iter()
                    .all(|p| p.dir.z > 0.0 && p.dir.is_normalized())
            );
        }
    }
}

/// A shading normal tilted by α from the geometric one: packets are cosine-distributed about
/// the shading normal and those below the geometric horizon are dropped, so the mean is the
/// isotropic-sky irradiance of a tilted plane, ∫_{n·ω>0, ng·ω>0} L n·ω dω = π L (1 + cos α)/2
/// (the sky view factor (1 + cos α)/2), and every estimate is a multiple of π L/m. Mean within
/// 4 standard errors (4000 calls × 16 samples; ≈ 6e-5 false-failure probability).
#[test]
fn environment_irradiance_with_a_tilted_shading_normal() {
    let radiance = [1.0, 2.0, 0.5];
    let scene = receiver_scene(vec![Light::Environment { radiance }]);
    for (k, alpha_deg) in [25.0f64, 60.0].into_iter().enumerate() {
        let alpha = alpha_deg.to_radians();
        let n = DVec3::new(alpha.sin() * 0.6, alpha.sin() * 0.8, alpha.cos());
        let at = Receiver {
            p: DVec3::new(0.2, -0.1, 0.0),
            n,
            ng: DVec3::Z,
        };
        let m = 16;
        let (mean, se, all) = gather_stats(&scene, at, m, 4000, 100 + k as u64, 1);
        let want = PI * radiance[1] * (1.0 + alpha.cos()) / 2.0;
        let rel = (mean - want) / want;
        eprintln!(
            "environment tilt {alpha_deg}°: mean {mean:.6e} ± {se:.2e}, closed form {want:.6e}, \
             rel {rel:+.2e}, {:.2} SE",
            (mean - want) / se
        );
        assert!(
            (mean - want).abs() <= 4.0 * se,
            "tilt {alpha_deg}: {mean} ± {se} vs {want}"
        );
        let quantum = PI * radiance[1] / m as f64;
        for packets in &all {
            let e: f64 = packets.iter().map(|p| p.e_cos[1]).sum();
            assert!((e / quantum - packets.len() as f64).abs() < 1e-9);
            assert!(packets.iter().all(|p| p.dir.z > 0.0));
        }
        // Some packets were dropped, or the test would not exercise the horizon.
        assert!(all.iter().any(|p| p.len() < m as usize));
    }
}

/// A sun (a disc of angular radius α and radiance L = E/(π sin²α)) against closed forms:
/// unoccluded, the irradiance on a surface is E cos θ (∫ L cos dω over the disc is L π sin²α
/// times the cosine towards its centre, while the whole disc is above the horizon), for a
/// receiver facing it and one tilted 40°; with an opaque half-plane whose edge passes right
/// under the disc's centre (a receiver facing the sun, so the cosine is symmetric about the
/// edge) exactly half; deep in the shadow 0 and clear of it E. Means of 400 seeded estimates
/// of 16 samples, within 4 standard errors.
#[test]
fn sun_irradiance_and_penumbra_match_closed_forms() {
    let alpha = 5f64.to_radians();
    let e = 2.0;
    let sun = Light::Sun {
        direction: DVec3::new(0.0, -1.0, 0.0),
        irradiance: [e, 2.0 * e, 0.5 * e],
        half_angle: alpha,
    };
    // An opaque half-plane at height 1: x < 0 (a 40 × 40 square centred at x = -20).
    let mut blocker = super::common::square(40.0, 4);
    for p in &mut blocker.positions {
        *p += DVec3::new(-20.0, 1.0, 0.0);
    }
    let scene = scene_of(
        vec![blocker],
        diffuse(),
        vec![sun],
        camera(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, 30.0, 4, 4),
    );
    let up = DVec3::Y;
    let tilt = DVec3::new(0.0, 40f64.to_radians().cos(), 40f64.to_radians().sin());
    // (position, normal, expected fraction of E)
    let cases = [
        (DVec3::new(5.0, 0.0, 0.0), up, 1.0),
        (DVec3::new(5.0, 0.0, 0.0), tilt, 40f64.to_radians().cos()),
        (DVec3::new(0.0, 0.0, 0.0), up, 0.5),
        (DVec3::new(-1.0, 0.0, 0.0), up, 0.0),
    ];
    for (p, n, fraction) in cases {
        for ch in 0..3 {
            let (mean, se, _) = gather_stats(&scene, Receiver { p, n, ng: n }, 16, 400, 7, ch);
            let want = fraction * [e, 2.0 * e, 0.5 * e][ch];
            println!("sun at {p} n {n}: {mean} (want {want}, se {se})");
            assert!(
                (mean - want).abs() <= 4.0 * se + 1e-9 * want,
                "at {p}, n {n}, channel {ch}: {mean} ± {se}, want {want}"
            );
            if fraction == 1.0 || fraction == 0.0 {
                // Unoccluded facing the sun every sample is near E; in the umbra none lands.
                assert!(se <= 1e-3 * want.max(1.0), "se {se}");
            }
        }
    }
}
