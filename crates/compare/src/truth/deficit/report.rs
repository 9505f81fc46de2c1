//! `deficit.csv`, the report's tables (per sweep, and the apportioned deficit of each scaled
//! scene) and the plots.

use super::measure::ratio;
use super::*;
use crate::output::{Csv, csv_num, csv_text, md_num, md_table};
use sss_plot::{Series, SeriesStyle};
use std::path::Path;

/// One measured row.
#[derive(Clone, Debug)]
pub(crate) struct DeficitRow {
    pub setup: Setup,
    /// `volpath`, all light.
    pub truth: Mean,
    /// `volpath`, single scattering alone.
    pub single: Mean,
    /// `volpath --reentry no`: the truth without the light the object's parts trade; None on
    /// the convex set-ups, which trade none ([`Setup::trades_light`]).
    pub direct: Option<Mean>,
    /// The model under `pathtrace`.
    pub model: Mean,
    /// The model with `angular = "albedo"` under `pathtrace`.
    pub albedo: Mean,
    /// Pixels the means are over.
    pub pixels: usize,
}

impl DeficitRow {
    /// The model's image mean over the truth's, per channel, with its standard error.
    pub fn ratio(&self) -> [Option<(f64, f64)>; 3] {
        ratio(&self.model, &self.truth)
    }

    /// The model with the directional albedo's angular factors over the truth.
    pub fn albedo_ratio(&self) -> [Option<(f64, f64)>; 3] {
        ratio(&self.albedo, &self.truth)
    }

    /// Single scattering's share of the truth, per channel, with its standard error.
    pub fn single_share(&self) -> [Option<(f64, f64)>; 3] {
        ratio(&self.single, &self.truth)
    }

    /// The truth without the light the object's parts trade, over the truth, per channel
    /// (None where not measured: a convex set-up, where it is 1).
    pub fn direct_share(&self) -> [Option<(f64, f64)>; 3] {
        match &self.direct {
            Some(d) => ratio(d, &self.truth),
            None => [None; 3],
        }
    }

    /// The model's image mean over the truth's without the light the object's parts trade
    /// (over the truth itself on a convex set-up, where the two are the same).
    pub fn direct_ratio(&self) -> [Option<(f64, f64)>; 3] {
        ratio(&self.model, self.direct.as_ref().unwrap_or(&self.truth))
    }

    /// [`Self::direct_ratio`] for the model with `angular = "albedo"`.
    pub fn albedo_direct_ratio(&self) -> [Option<(f64, f64)>; 3] {
        ratio(&self.albedo, self.direct.as_ref().unwrap_or(&self.truth))
    }
}

/// The columns of `deficit.csv`.
pub const COLUMNS: [&str; 37] = [
    "group",
    "medium",
    "param",
    "value",
    "truth_r",
    "truth_g",
    "truth_b",
    "truth_se_r",
    "truth_se_g",
    "truth_se_b",
    "model",
    "model_r",
    "model_g",
    "model_b",
    "ratio_r",
    "ratio_g",
    "ratio_b",
    "ratio_se_r",
    "ratio_se_g",
    "ratio_se_b",
    "albedo_ratio_r",
    "albedo_ratio_g",
    "albedo_ratio_b",
    "albedo_ratio_se_r",
    "albedo_ratio_se_g",
    "albedo_ratio_se_b",
    "single_r",
    "single_g",
    "single_b",
    "direct_r",
    "direct_g",
    "direct_b",
    "truth_spp",
    "model_spp",
    "truth_seconds",
    "model_seconds",
    "pixels",
];

/// `deficit.csv`: one row per set-up.
pub(crate) fn deficit_csv(rows: &[DeficitRow]) -> Csv {
    let mut csv = Csv::new(COLUMNS);
    for r in rows {
        let q = r.ratio();
        let s = r.single_share();
        let mut f = vec![
            csv_text(r.setup.group),
            csv_text(r.setup.medium.name),
            csv_text(r.setup.param),
            csv_num(Some(r.setup.value)),
        ];
        f.extend(r.truth.mean.iter().map(|&v| csv_num(Some(v))));
        f.extend(r.truth.se.iter().map(|&v| csv_num(Some(v))));
        f.push(csv_text(MODEL.name()));
        f.extend(r.model.mean.iter().map(|&v| csv_num(Some(v))));
        f.extend(q.iter().map(|v| csv_num(v.map(|x| x.0))));
        f.extend(q.iter().map(|v| csv_num(v.map(|x| x.1))));
        let a = r.albedo_ratio();
        f.extend(a.iter().map(|v| csv_num(v.map(|x| x.0))));
        f.extend(a.iter().map(|v| csv_num(v.map(|x| x.1))));
        f.extend(s.iter().map(|v| csv_num(v.map(|x| x.0))));
        f.extend(r.direct_share().iter().map(|v| csv_num(v.map(|x| x.0))));
        f.push(r.truth.spp.to_string());
        f.push(r.model.spp.to_string());
        f.push(csv_num(Some(r.truth.seconds)));
        f.push(csv_num(Some(r.model.seconds)));
        f.push(r.pixels.to_string());
        csv.row(f);
    }
    csv
}

/// `x ± s` with three decimals, or `–`.
fn pm(v: Option<(f64, f64)>) -> String {
    match v {
        Some((x, s)) => format!("{x:.3} ± {s:.3}"),
        None => "–".to_string(),
    }
}

/// Three channels as `r / g / b`.
fn rgb3(v: [Option<(f64, f64)>; 3], plus_minus: bool) -> String {
    v.iter()
        .map(|x| {
            if plus_minus {
                pm(*x)
            } else {
                md_num(x.map(|x| x.0), 3)
            }
        })
        .collect::<Vec<_>>()
        .join(" / ")
}

/// A scaled scene's deficit as four factors per channel, whose product is its model/truth
/// at scale 1: interreflection (at scale 1, the truth without the light the object's parts
/// trade over the truth) and, against that truth without it, size (scale 1 over the flat
/// limit), angles (the flat limit over the half-space head-on) and profile (the half-space
/// head-on).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Apportioned {
    pub group: &'static str,
    pub medium: &'static str,
    /// The two largest scales measured.
    pub scales: (f64, f64),
    /// Model / truth at scale 1; model over the truth without traded light at the largest
    /// scale and in the flat limit.
    pub total: Rgb,
    pub largest: Rgb,
    pub flat: Rgb,
    pub size: Rgb,
    pub angles: Rgb,
    pub profile: Rgb,
    /// The truth without the light the object's parts trade over the truth, at scale 1 (1
    /// where it was not measured).
    pub interreflection: Rgb,
    /// With `angular = "albedo"`: model / truth at scale 1, and over the truth without
    /// traded light in the flat limit.
    pub albedo_total: Rgb,
    pub albedo_flat: Rgb,
}

/// The flat limit of a ratio measured at scales `s1 < s2`, assuming what is left of the size
/// effect falls as 1/scale (first order in curvature × diffusion length, as the spheres'
/// sweep shows): D∞ = D₂ + (D₂ − D₁)/(s₂/s₁ − 1) (Richardson extrapolation).
pub(crate) fn flat_limit((s1, d1): (f64, f64), (s2, d2): (f64, f64)) -> f64 {
    if s2 > s1 && s1 > 0.0 {
        d2 + (d2 - d1) / (s2 / s1 - 1.0)
    } else {
        d2
    }
}

/// The value of `group`'s row in `medium` at `value`.
fn row_at<'a>(
    rows: &'a [DeficitRow],
    group: &str,
    medium: &str,
    value: f64,
) -> Option<&'a DeficitRow> {
    rows.iter()
        .find(|r| r.setup.group == group && r.setup.medium.name == medium && r.setup.value == value)
}

/// The apportioned deficit of each scaled scene and medium that has its scale-1 row, two
/// larger ones and the half-space head-on row (`incidence` at 0°) of its medium.
pub(crate) fn apportion(rows: &[DeficitRow]) -> Vec<Apportioned> {
    // Rows that are not scaled have scale 0: a group without a scale-1 row is skipped.
    let scale_of = |r: &DeficitRow| match r.setup.kind {
        Kind::Scaled { scale, .. } => scale,
        _ => 0.0,
    };
    let ratio_of = |r: &DeficitRow| values(r.ratio());
    let direct_of = |r: &DeficitRow| values(r.direct_ratio());
    let albedo_of = |r: &DeficitRow| values(r.albedo_direct_ratio());
    let traded_of = |r: &DeficitRow| values(r.direct_share()).unwrap_or([1.0; 3]);
    let mut out = Vec::new();
    for (g, m) in groups_of(rows) {
        let Some(head_on) = row_at(rows, "incidence", m, 0.0) else {
            continue;
        };
        let mut of: Vec<&DeficitRow> = rows
            .iter()
            .filter(|r| r.setup.group == g && r.setup.medium.name == m)
            .collect();
        of.sort_by(|a, b| scale_of(a).total_cmp(&scale_of(b)));
        let Some(unit) = of.iter().find(|r| scale_of(r) == 1.0) else {
            continue;
        };
        let larger: Vec<&&DeficitRow> = of.iter().filter(|r| scale_of(r) > 1.0).collect();
        let [.., r1, r2] = larger.as_slice() else {
            continue;
        };
        let (Some(t), Some(u), Some(d1), Some(d2), Some(n)) = (
            ratio_of(unit),
            direct_of(unit),
            direct_of(r1),
            direct_of(r2),
            ratio_of(head_on),
        ) else {
            continue;
        };
        let (Some(at), Some(a1), Some(a2)) =
            (values(unit.albedo_ratio()), albedo_of(r1), albedo_of(r2))
        else {
            continue;
        };
        let (s1, s2) = (scale_of(r1), scale_of(r2));
        let flat: Rgb = std::array::from_fn(|c| flat_limit((s1, d1[c]), (s2, d2[c])));
        let albedo_flat: Rgb = std::array::from_fn(|c| flat_limit((s1, a1[c]), (s2, a2[c])));
        let div = |a: Rgb, b: Rgb| -> Rgb {
            std::array::from_fn(|c| if b[c] != 0.0 { a[c] / b[c] } else { 0.0 })
        };
        out.push(Apportioned {
            group: g,
            medium: m,
            scales: (s1, s2),
            total: t,
            largest: d2,
            flat,
            size: div(u, flat),
            angles: div(flat, n),
            profile: n,
            interreflection: traded_of(unit),
            albedo_total: at,
            albedo_flat,
        });
    }
    out
}

/// Each factor's share of the deficit, per channel, in the order size, angles, profile,
/// interreflection: ln(factor)/ln(total) (the logarithms add up), None where the total is
/// within 0.5 % of 1.
pub(crate) fn shares(a: &Apportioned) -> [[Option<f64>; 3]; 4] {
    let share = |f: Rgb| -> [Option<f64>; 3] {
        std::array::from_fn(|c| {
            let t = a.total[c];
            ((t - 1.0).abs() > 0.005 && t > 0.0 && f[c] > 0.0).then(|| f[c].ln() / t.ln())
        })
    };
    [
        share(a.size),
        share(a.angles),
        share(a.profile),
        share(a.interreflection),
    ]
}

/// The model's exitant flux over the truth's, per channel, from an exit-angle sweep: the
/// radiances at the measured exit angles θ (plus `head_on` at 0° if the sweep lacks it)
/// integrated as ∫ L cos θ sin θ dθ by the trapezoid rule, the integrand 0 at 90°. On the
/// half-space every pixel sees the same radiance, so this is the hemispherical reflectance's
/// ratio for that lighting (a quadrature over 15–30° steps: about 1 % of its own error).
/// None with fewer than two angles or a zero truth.
pub(crate) fn flux_ratio(sweep: &[&DeficitRow], head_on: Option<&DeficitRow>) -> Option<Rgb> {
    let mut pts: Vec<(f64, Rgb, Rgb)> = sweep
        .iter()
        .map(|r| (r.setup.value, r.truth.mean, r.model.mean))
        .collect();
    if let Some(h) = head_on
        && !pts.iter().any(|p| p.0 == 0.0)
    {
        pts.push((0.0, h.truth.mean, h.model.mean));
    }
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    if pts.len() < 2 {
        return None;
    }
    // ∫ L cos θ sin θ dθ of one channel's radiances by the trapezoid rule, the integrand 0
    // at 90°.
    let integral = |value: &dyn Fn(&(f64, Rgb, Rgb)) -> f64| -> f64 {
        let mut nodes: Vec<(f64, f64)> = pts
            .iter()
            .map(|p| {
                let t = p.0.to_radians();
                (t, value(p) * t.cos() * t.sin())
            })
            .collect();
        nodes.push((std::f64::consts::FRAC_PI_2, 0.0));
        nodes
            .windows(2)
            .map(|w| 0.5 * (w[1].0 - w[0].0) * (w[0].1 + w[1].1))
            .sum()
    };
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let t = integral(&|p| p.1[c]);
        if !(t > 0.0) {
            return None;
        }
        *o = integral(&|p| p.2[c]) / t;
    }
    Some(out)
}

/// The distinct items of `items`, in order of first appearance.
fn unique<T: PartialEq>(items: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut out = Vec::new();
    for x in items {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

/// The (group, medium) pairs of `rows`, in order of first appearance.
fn groups_of(rows: &[DeficitRow]) -> Vec<(&'static str, &'static str)> {
    unique(rows.iter().map(|r| (r.setup.group, r.setup.medium.name)))
}

/// The three channels' values of a ratio, None if one is missing.
fn values(q: [Option<(f64, f64)>; 3]) -> Option<Rgb> {
    Some([q[0]?.0, q[1]?.0, q[2]?.0])
}

/// The report's section.
pub(crate) fn section(rows: &[DeficitRow], skipped: &[String], plan: &DeficitPlan) -> Section {
    let mut body = String::new();
    body.push_str(&format!(
        "Where `{}`'s error against real transport comes from: its image mean under \
         `pathtrace` (the model's integral) over `volpath`'s (the truth), per channel \
         (R / G / B) with standard errors, on controlled set-ups; each mean rendered to about \
         {:.1} % relative standard error in each channel. \"single\" is single scattering's \
         share of the truth (`volpath --scattering single`); \"without traded light\" is the \
         truth without the light the object's parts trade (`volpath --reentry no`) over the \
         truth, on the meshes (the other set-ups are convex: 1). Reduced mean free paths (R / G / \
         B): skin1 1.30 / 0.95 / 0.67 mm, marble 0.46 / 0.38 / 0.33 mm, ketchup 4.15 / 0.96 / 0.68 \
         mm.\n\n",
        MODEL.name(),
        100.0 * plan.target
    ));
    for (g, m) in groups_of(rows) {
        let of: Vec<&DeficitRow> = rows
            .iter()
            .filter(|r| r.setup.group == g && r.setup.medium.name == m)
            .collect();
        body.push_str(&format!("**{g}, {m}**\n\n"));
        let param = of.first().map_or("", |r| r.setup.param);
        let table: Vec<Vec<String>> = of
            .iter()
            .map(|r| {
                vec![
                    md_num(Some(r.setup.value), 4),
                    rgb3(r.ratio(), true),
                    rgb3(r.albedo_ratio(), false),
                    rgb3(r.single_share(), false),
                    rgb3(r.direct_share(), false),
                    format!(
                        "{} / {}",
                        md_num(Some(r.truth.seconds), 2),
                        md_num(Some(r.model.seconds), 2)
                    ),
                ]
            })
            .collect();
        body.push_str(&md_table(
            &[
                param,
                "model / truth (R / G / B)",
                "with angular = albedo",
                "single (R / G / B)",
                "without traded light",
                "s: volpath / pathtrace",
            ],
            &table,
        ));
        body.push('\n');
    }
    let mut flux = Vec::new();
    for (g, m) in groups_of(rows) {
        if !g.starts_with("exit-") {
            continue;
        }
        let sweep: Vec<&DeficitRow> = rows
            .iter()
            .filter(|r| r.setup.group == g && r.setup.medium.name == m)
            .collect();
        let head_on = (g == "exit-sun")
            .then(|| row_at(rows, "incidence", m, 0.0))
            .flatten();
        if let Some(f) = flux_ratio(&sweep, head_on) {
            let light = if g == "exit-sun" {
                "the sun at normal incidence"
            } else {
                "the uniform environment"
            };
            flux.push(format!(
                "- {m} under {light}: {}",
                f.map(|x| format!("{x:.3}")).join(" / ")
            ));
        }
    }
    if !flux.is_empty() {
        body.push_str(
            "The half-space's exitant flux, model over truth (R / G / B; the exit sweeps' \
             radiances integrated over the hemisphere by the trapezoid rule, 0 at 90°): the \
             boundary terms and the normalisation conserve what the table holds where the flux \
             is the table's own (normal incidence); under other lighting the difference is the \
             albedo's dependence on the incidence angle, which the model does not have.\n\n",
        );
        body.push_str(&flux.join("\n"));
        body.push_str("\n\n");
    }
    let parts = apportion(rows);
    let mut summary = String::new();
    if !parts.is_empty() {
        let f3 = |v: Rgb| {
            v.iter()
                .map(|x| format!("{x:.3}"))
                .collect::<Vec<_>>()
                .join(" / ")
        };
        let s3 = |v: [Option<f64>; 3]| {
            v.iter()
                .map(|x| x.map_or("–".to_string(), |x| format!("{:.0} %", 100.0 * x)))
                .collect::<Vec<_>>()
                .join(" / ")
        };
        let table: Vec<Vec<String>> = parts
            .iter()
            .map(|a| {
                let sh = shares(a);
                vec![
                    format!("{}, {}", a.group, a.medium),
                    f3(a.total),
                    format!("{} at {}; {}", f3(a.largest), a.scales.1, f3(a.flat)),
                    format!("{} ({})", f3(a.size), s3(sh[0])),
                    format!("{} ({})", f3(a.angles), s3(sh[1])),
                    format!("{} ({})", f3(a.profile), s3(sh[2])),
                    format!("{} ({})", f3(a.interreflection), s3(sh[3])),
                    format!("{}; {}", f3(a.albedo_total), f3(a.albedo_flat)),
                ]
            })
            .collect();
        summary.push_str(&format!(
            "`{}`'s image mean over real transport's (`volpath`), apportioned: model / truth \
             at scale 1 = size × angles × profile × interreflection, per channel R / G / B, \
             each factor's share of the deficit in brackets (ln factor / ln total). \
             Interreflection: the truth without the light the object's parts trade \
             (`volpath --reentry no`) over the truth, at scale 1: what a BSSRDF under direct \
             light cannot carry. The other factors are taken against that truth without it. \
             Size: scale 1 over the flat limit (the two largest scales extrapolated as \
             1/scale); angles: the flat limit over the half-space lit and seen head-on (the \
             scene's incidence and exit directions); profile: the half-space head-on (the \
             table's own set-up: what is left is the profile and the boundary terms).\n\n",
            MODEL.name()
        ));
        summary.push_str(&md_table(
            &[
                "scene, medium",
                "model / truth",
                "largest scale; flat limit",
                "size (curvature, thin parts)",
                "angles (incidence, exit)",
                "profile and boundary",
                "interreflection",
                "with angular = albedo: scale 1; flat limit",
            ],
            &table,
        ));
    }
    for s in skipped {
        body.push_str(&format!("\nSkipped: {s}\n"));
    }
    Section {
        title: "Where the models' error comes from".into(),
        summary,
        body,
    }
}

/// `deficit_<group>.png` and `.svg`: the ratio against the swept quantity, per channel, for
/// each group with more than one row.
pub(crate) fn write_plots(out: &Path, rows: &[DeficitRow]) -> Result<(), Error> {
    let colours = [[200, 30, 30], [30, 150, 30], [30, 60, 210]];
    let groups = unique(rows.iter().map(|r| r.setup.group));
    for g in groups {
        let of: Vec<&DeficitRow> = rows.iter().filter(|r| r.setup.group == g).collect();
        if of.len() < 2 {
            continue;
        }
        let param = of[0].setup.param;
        let log_x = matches!(param, "radius_mm" | "scale" | "thickness_mm");
        let mut series = Vec::new();
        let media = unique(of.iter().map(|r| r.setup.medium.name));
        for (k, m) in media.into_iter().enumerate() {
            for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
                let points: Vec<(f64, f64)> = of
                    .iter()
                    .filter(|r| r.setup.medium.name == m)
                    .filter_map(|r| r.ratio()[c].map(|(x, _)| (r.setup.value, x)))
                    .filter(|p| !log_x || p.0 > 0.0)
                    .collect();
                if points.len() < 2 {
                    continue;
                }
                let style = [
                    SeriesStyle::LineMarkers,
                    SeriesStyle::Dashed,
                    SeriesStyle::Line,
                ];
                series.push(
                    Series::line(format!("{m} {name}"), points)
                        .with_style(style[k % style.len()])
                        .with_color(colours[c]),
                );
            }
        }
        if series.is_empty() {
            continue;
        }
        crate::output::plot_with_hover(
            &out.join(format!("deficit_{g}.png")),
            &format!("{g}: {} over volpath's truth", MODEL.name()),
            (param, "model / truth (image mean)"),
            &series,
            (log_x, false),
        )?;
    }
    Ok(())
}
