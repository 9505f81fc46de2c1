//! Plots for web pages: an SVG chart as text, each data point carrying a label that a browser
//! shows on hover (an SVG `<title>`), for the HTML report. Axes, tick labels and the
//! robustness rules (non-finite and non-positive-on-log points dropped) are the PNG plots'.

use crate::{MAX_LOG_DECADES, PALETTE, axis_range, tick_label};
use std::fmt::Write as _;

/// One series of a [`hover_svg`] chart: points, each with its hover label.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct LabelledSeries {
    /// Legend entry.
    pub name: String,
    /// (x, y, label) in drawing order.
    pub points: Vec<(f64, f64, String)>,
    /// RGB colour; `None` takes the palette's colour by series index.
    pub color: Option<[u8; 3]>,
}

/// Escapes text for SVG and HTML (`&`, `<`, `>`, `"`, `'`).
pub fn escape_xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Size of a chart's plot area and axes in SVG user units (the legend adds its width).
const SIZE: (f64, f64) = (640.0, 400.0);
/// Left, right (without the legend's text), top and bottom margins.
const MARGIN: (f64, f64, f64, f64) = (70.0, 150.0, 30.0, 50.0);
/// Width of a legend character at the 12-unit font, generously.
const CHAR_W: f64 = 7.0;

/// An axis: its range and where a value lands on it.
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
}

impl Axis {
    fn new(values: impl Iterator<Item = f64>, log: bool) -> Self {
        let (lo, hi) = axis_range(values, log);
        Axis { lo, hi, log }
    }

    /// Position of `v` in [0, 1] along the axis.
    fn at(&self, v: f64) -> f64 {
        let f = |x: f64| if self.log { x.log10() } else { x };
        let span = f(self.hi) - f(self.lo);
        if span > 0.0 {
            (f(v) - f(self.lo)) / span
        } else {
            0.5
        }
    }

    /// Tick values: each power of ten on a log axis (every other one beyond 8 decades; 2 and
    /// 5 times each too where fewer than three powers fall in the range), five even steps on
    /// a linear one.
    fn ticks(&self) -> Vec<f64> {
        if self.log {
            let (a, b) = (
                self.lo.log10().ceil() as i32,
                self.hi.log10().floor() as i32,
            );
            let step = if b - a > 8 { 2 } else { 1 };
            let decades: Vec<f64> = (a..=b).step_by(step).map(|e| 10f64.powi(e)).collect();
            if decades.len() >= 3 {
                return decades;
            }
            let e0 = self.lo.log10().floor() as i32;
            (e0..=b.max(e0) + 1)
                .flat_map(|e| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(e)))
                .filter(|v| *v >= self.lo && *v <= self.hi)
                .collect()
        } else {
            (0..=4)
                .map(|k| self.lo + (self.hi - self.lo) * k as f64 / 4.0)
                .collect()
        }
    }
}

/// An SVG chart (as text, to inline in HTML or write to a file) of `series`, every point a
/// circle whose `<title>` is its label. Points with a non-finite coordinate, or ≤ 0 on a log
/// axis, or more than [`MAX_LOG_DECADES`] below the largest y on a log y axis, are dropped.
pub fn hover_svg(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[LabelledSeries],
    log_x: bool,
    log_y: bool,
) -> String {
    let keep = |x: f64, y: f64| {
        x.is_finite() && y.is_finite() && (!log_x || x > 0.0) && (!log_y || y > 0.0)
    };
    let y_max = series
        .iter()
        .flat_map(|s| &s.points)
        .filter(|p| keep(p.0, p.1))
        .map(|p| p.1)
        .fold(f64::NEG_INFINITY, f64::max);
    let floor = if log_y {
        y_max * 10f64.powf(-MAX_LOG_DECADES)
    } else {
        f64::NEG_INFINITY
    };
    let kept: Vec<Vec<&(f64, f64, String)>> = series
        .iter()
        .map(|s| {
            s.points
                .iter()
                .filter(|p| keep(p.0, p.1) && p.1 >= floor)
                .collect()
        })
        .collect();
    let all = || kept.iter().flatten();
    let xa = Axis::new(all().map(|p| p.0), log_x);
    let ya = Axis::new(all().map(|p| p.1), log_y);
    let (ml, mr, mt, mb) = MARGIN;
    let legend = series
        .iter()
        .map(|s| s.name.chars().count())
        .max()
        .unwrap_or(0) as f64
        * CHAR_W;
    let (pw, ph) = (SIZE.0 - ml - mr, SIZE.1 - mt - mb);
    let (w, h) = (SIZE.0 + (legend - (mr - 40.0)).max(0.0), SIZE.1);
    let px = |x: f64| ml + xa.at(x) * pw;
    let py = |y: f64| mt + (1.0 - ya.at(y)) * ph;
    let mut s = String::new();
    let _ = write!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {w} {h}\" width=\"{w}\" \
         height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\" role=\"img\">\
         <title>{}</title><rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>",
        escape_xml(title)
    );
    let _ = write!(
        s,
        "<text x=\"{}\" y=\"18\" text-anchor=\"middle\" font-size=\"15\">{}</text>",
        ml + pw / 2.0,
        escape_xml(title)
    );
    // Grid, ticks and their labels.
    for t in xa.ticks() {
        let x = px(t);
        let _ = write!(
            s,
            "<line x1=\"{x:.1}\" y1=\"{mt}\" x2=\"{x:.1}\" y2=\"{:.1}\" stroke=\"#e6e6e6\"/>\
             <text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
            mt + ph,
            mt + ph + 16.0,
            escape_xml(&tick_label(t, log_x))
        );
    }
    for t in ya.ticks() {
        let y = py(t);
        let _ = write!(
            s,
            "<line x1=\"{ml}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"#e6e6e6\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            ml + pw,
            ml - 6.0,
            y + 4.0,
            escape_xml(&tick_label(t, log_y))
        );
    }
    let _ = write!(
        s,
        "<rect x=\"{ml}\" y=\"{mt}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" \
         stroke=\"#444\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>\
         <text transform=\"translate(16 {:.1}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
        ml + pw / 2.0,
        h - 10.0,
        escape_xml(x_label),
        mt + ph / 2.0,
        escape_xml(y_label)
    );
    for (i, (ser, pts)) in series.iter().zip(&kept).enumerate() {
        let [r, g, b] = ser.color.unwrap_or(PALETTE[i % PALETTE.len()]);
        let colour = format!("rgb({r},{g},{b})");
        if pts.len() > 1 {
            let path: Vec<String> = pts
                .iter()
                .map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1)))
                .collect();
            let _ = write!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.5\"/>",
                path.join(" ")
            );
        }
        for p in pts {
            let _ = write!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"4\" fill=\"{colour}\"><title>{}</title>\
                 </circle>",
                px(p.0),
                py(p.1),
                escape_xml(&p.2)
            );
        }
        // Legend, right of the plot.
        let ly = mt + 10.0 + 18.0 * i as f64;
        let _ = write!(
            s,
            "<line x1=\"{:.1}\" y1=\"{ly:.1}\" x2=\"{:.1}\" y2=\"{ly:.1}\" stroke=\"{colour}\" \
             stroke-width=\"3\"/><text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            ml + pw + 10.0,
            ml + pw + 30.0,
            ml + pw + 36.0,
            ly + 4.0,
            escape_xml(&ser.name)
        );
    }
    s.push_str("</svg>");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kept_point_has_its_label_and_bad_points_are_dropped() {
        let series = [
            LabelledSeries {
                name: "a <b>".into(),
                points: vec![
                    (1.0, 0.1, "first & one".into()),
                    (10.0, 0.01, "second".into()),
                    (f64::NAN, 1.0, "nan".into()),
                    (0.0, 1.0, "zero x".into()),
                ],
                color: None,
            },
            LabelledSeries {
                name: "c".into(),
                points: vec![(100.0, 1e-30, "far below".into())],
                color: Some([1, 2, 3]),
            },
        ];
        let svg = hover_svg("t", "x", "y", &series, true, true);
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
        assert_eq!(svg.matches("<circle").count(), 2, "{svg}");
        assert!(svg.contains("<title>first &amp; one</title>"));
        assert!(svg.contains("<title>second</title>"));
        assert!(!svg.contains("nan") && !svg.contains("zero x") && !svg.contains("far below"));
        assert!(svg.contains("a &lt;b&gt;"));
        // The points sit inside the plot area: 0.1 above 0.01, 1 left of 10.
        let circles: Vec<(f64, f64)> = svg
            .match_indices("<circle cx=\"")
            .map(|(i, _)| {
                let rest = &svg[i + 12..];
                let cx: f64 = rest[..rest.find('"').unwrap()].parse().unwrap();
                let rest = &rest[rest.find("cy=\"").unwrap() + 4..];
                let cy: f64 = rest[..rest.find('"').unwrap()].parse().unwrap();
                (cx, cy)
            })
            .collect();
        let (ml, mr, mt, mb) = MARGIN;
        for &(x, y) in &circles {
            assert!(x >= ml && x <= SIZE.0 - mr && y >= mt && y <= SIZE.1 - mb);
        }
        // Room for the legend's longest name.
        let long = LabelledSeries {
            name: "x".repeat(60),
            points: vec![(1.0, 1.0, "p".into())],
            color: None,
        };
        let wide = hover_svg("t", "x", "y", &[long], false, false);
        let want = format!("viewBox=\"0 0 {} 400\"", SIZE.0 + 60.0 * CHAR_W - 110.0);
        assert!(wide.contains(&want), "{wide}");
        assert!(circles[0].0 < circles[1].0 && circles[0].1 < circles[1].1);
        // Decade ticks on a log axis; 2 and 5 times them where fewer than three decades show.
        assert!(svg.contains(">1e-2<") && svg.contains(">1e1<"), "{svg}");
        let narrow = LabelledSeries {
            name: "n".into(),
            points: vec![(1.0, 0.3, "a".into()), (2.0, 4.0, "b".into())],
            color: None,
        };
        let svg = hover_svg("t", "x", "y", &[narrow], false, true);
        for t in [">5e-1<", ">1e0<", ">2e0<"] {
            assert!(svg.contains(t), "{t}: {svg}");
        }
    }

    #[test]
    fn escaping_covers_markup() {
        assert_eq!(
            escape_xml("<a href=\"x\">'&'</a>"),
            "&lt;a href=&quot;x&quot;&gt;&#39;&amp;&#39;&lt;/a&gt;"
        );
    }

    #[test]
    fn an_empty_chart_is_still_a_chart() {
        let svg = hover_svg("none", "x", "y", &[], true, false);
        assert!(svg.contains("</svg>") && !svg.contains("<circle"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }
}
