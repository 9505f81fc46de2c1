//! # sss-plot: line plots and error maps for the toolkit's reports
//!
//! Line and scatter plots to PNG or SVG, for radial profiles and error reports, SVG charts for
//! web pages whose points name themselves on hover ([`hover_svg`]), and false-colour per-pixel
//! error maps ([`write_error_map`]). Use it when you want the pictures
//! `sss` and `cargo xtask compare` draw; the renderer itself does not depend on it.
//!
//! The API is plain data: build [`Series`] (a name, points, a colour, an optional symmetric
//! error per point), group them in [`Panel`]s and call [`line_plot`] (one panel) or
//! [`panel_plot`] (a grid of panels). The format follows the file extension (`.png` or
//! `.svg`). Text uses the Ubuntu-Light font embedded by `epaint_default_fonts`, so no system
//! font library is needed and the output does not depend on which fonts are installed.
//!
//! Robustness rules:
//! - Points with a non-finite coordinate are dropped, and so are points with x ≤ 0 on a log x
//!   axis or y ≤ 0 on a log y axis. A log y axis spans at most [`MAX_LOG_DECADES`] decades
//!   below the largest value; points below that are dropped too.
//! - The image is drawn to a temporary file in the same directory and renamed into place, so
//!   a reader never sees a half-written plot. Every error names the file.
//!
//! ```
//! use sss_plot::{Series, SeriesStyle, line_plot};
//!
//! let dir = std::env::temp_dir().join(format!("sss-plot-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let points = (1..50).map(|i| (i as f64 * 0.1, (-(i as f64) * 0.1).exp())).collect();
//! let series = Series::line("R_d", points);
//! line_plot(&dir.join("rd.svg"), "profile", "r (mm)", "R_d", &[series], false, true).unwrap();
//! assert!(std::fs::read_to_string(dir.join("rd.svg")).unwrap().contains("<svg"));
//! # std::fs::remove_dir_all(&dir).unwrap();
//! ```
//!
//! ## Papers
//! None. The colour maps are matplotlib's inferno, magma and viridis (van der Walt, Smith &
//! Firing) and ColorBrewer's red-blue (Brewer), from the tables of the `colorous` crate.

#![forbid(unsafe_code)]

use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

mod error_map;
mod hover;
pub use error_map::{
    ColourMap, MapScale, OVER_RANGE, diverging_colour, false_colour, write_error_map,
    write_error_map_with, write_flip_map, write_signed_map,
};
pub use hover::{LabelledSeries, escape_xml, hover_svg};

/// A log y axis spans at most this many decades below its largest value.
pub const MAX_LOG_DECADES: f64 = 10.0;

/// The default colour cycle, used for series without an explicit colour.
pub const PALETTE: [[u8; 3]; 8] = [
    [0, 0, 0],
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
];

/// Pure red, green and blue for plotting the three colour channels.
pub const CHANNEL_COLORS: [[u8; 3]; 3] = [[200, 30, 30], [30, 150, 30], [30, 60, 200]];

/// How a series' points are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SeriesStyle {
    /// A solid polyline through the points.
    #[default]
    Line,
    /// A dashed polyline.
    Dashed,
    /// A filled circle at each point, no line.
    Markers,
    /// A polyline with a circle at each point.
    LineMarkers,
}

/// How a series' per-point errors are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ErrorStyle {
    /// A translucent band between y − e and y + e.
    #[default]
    Band,
    /// A vertical bar from y − e to y + e at every point.
    Bars,
}

/// One named series of a plot.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// (x, y) points in drawing order.
    pub points: Vec<(f64, f64)>,
    /// RGB colour; `None` takes the next colour of [`PALETTE`] by series index.
    pub color: Option<[u8; 3]>,
    /// How the points are drawn.
    pub style: SeriesStyle,
    /// Optional symmetric error of each y value (same length as `points`; extra or missing
    /// entries are ignored, non-finite ones count as 0).
    pub y_err: Option<Vec<f64>>,
    /// How `y_err` is drawn.
    pub err_style: ErrorStyle,
}

impl Series {
    /// A solid line series with the palette colour.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
            ..Series::default()
        }
    }

    /// The same series with colour `rgb`.
    pub fn with_color(mut self, rgb: [u8; 3]) -> Self {
        self.color = Some(rgb);
        self
    }

    /// The same series drawn with `style`.
    pub fn with_style(mut self, style: SeriesStyle) -> Self {
        self.style = style;
        self
    }

    /// The same series with a symmetric error per point drawn as `style`.
    pub fn with_errors(mut self, y_err: Vec<f64>, style: ErrorStyle) -> Self {
        self.y_err = Some(y_err);
        self.err_style = style;
        self
    }
}

/// One chart of a [`panel_plot`]: its axes and series.
#[derive(Clone, Copy, Debug)]
pub struct Panel<'a> {
    /// Caption above the chart (may be empty).
    pub title: &'a str,
    /// Description of the x axis.
    pub x_label: &'a str,
    /// Description of the y axis.
    pub y_label: &'a str,
    /// The series drawn in this chart.
    pub series: &'a [Series],
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
}

/// Why a plot could not be written.
#[derive(Debug)]
pub enum PlotError {
    /// The file extension is neither `.png` nor `.svg`.
    UnsupportedFormat(PathBuf),
    /// The embedded font could not be registered.
    Font,
    /// Drawing or writing failed.
    Draw {
        /// The requested output file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlotError::UnsupportedFormat(p) => write!(
                f,
                "cannot plot to '{}': the file name must end in .png or .svg",
                p.display()
            ),
            PlotError::Font => f.write_str("cannot register the embedded plot font"),
            PlotError::Draw { path, message } => {
                write!(f, "cannot write plot '{}': {message}", path.display())
            }
        }
    }
}

impl std::error::Error for PlotError {}

/// The output format chosen by a file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotFormat {
    /// A PNG bitmap.
    Png,
    /// An SVG vector image.
    Svg,
}

impl PlotFormat {
    /// The format of `path` by its (case-insensitive) extension.
    pub fn from_path(path: &Path) -> Result<Self, PlotError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => Ok(PlotFormat::Png),
            Some("svg") => Ok(PlotFormat::Svg),
            _ => Err(PlotError::UnsupportedFormat(path.to_path_buf())),
        }
    }
}

/// Size in pixels of one panel.
const PANEL_SIZE: (u32, u32) = (800, 560);

/// Draws one chart of `series` to `path` (`.png` or `.svg`).
///
/// ```no_run
/// use sss_plot::{line_plot, Series};
/// let s = Series::line("exp", (1..100).map(|i| (i as f64, (-(i as f64) / 10.0).exp())).collect());
/// line_plot("out.svg".as_ref(), "decay", "r (mm)", "Rd (1/mm²)", &[s], false, true)?;
/// # Ok::<(), sss_plot::PlotError>(())
/// ```
pub fn line_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_x: bool,
    log_y: bool,
) -> Result<(), PlotError> {
    let panel = Panel {
        title: "",
        x_label,
        y_label,
        series,
        log_x,
        log_y,
    };
    panel_plot(path, title, &[panel], 1)
}

/// Draws `panels` in a grid with `columns` columns (at least 1) under a common `title`.
pub fn panel_plot(
    path: &Path,
    title: &str,
    panels: &[Panel<'_>],
    columns: usize,
) -> Result<(), PlotError> {
    let format = PlotFormat::from_path(path)?;
    register_font()?;
    let columns = columns.clamp(1, panels.len().max(1));
    let rows = panels.len().div_ceil(columns).max(1);
    let title_h = if title.is_empty() { 0 } else { 40 };
    let size = (
        PANEL_SIZE.0 * columns as u32,
        PANEL_SIZE.1 * rows as u32 + title_h,
    );
    let draw_err = |message: String| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    };
    sss_util::write_atomic_with(
        path,
        |tmp| {
            // Creating the file first gives a plain I/O message for a bad directory.
            std::fs::File::create(tmp).map_err(|e| draw_err(e.to_string()))?;
            match format {
                PlotFormat::Png => {
                    let root = BitMapBackend::new(tmp, size).into_drawing_area();
                    draw_all(&root, title, panels, rows, columns).and_then(|()| {
                        root.present()
                            .map_err(|e| format!("encoding the image failed: {e}"))
                    })
                }
                PlotFormat::Svg => {
                    let mut svg = String::new();
                    let drawn = {
                        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                        draw_all(&root, title, panels, rows, columns)
                            .and_then(|()| root.present().map_err(|e| e.to_string()))
                    };
                    drawn.and_then(|()| std::fs::write(tmp, &svg).map_err(|e| e.to_string()))
                }
            }
            .map_err(draw_err)
        },
        |e| draw_err(e.to_string()),
    )
}

/// Checks that a plot can be written to `path` (a supported extension, a writable
/// directory) without drawing it: creates and removes the temporary file. Call it before a
/// long computation whose result is to be plotted.
pub fn check_writable(path: &Path) -> Result<(), PlotError> {
    PlotFormat::from_path(path)?;
    // Registered, so an interrupt between the create and the remove deletes it too.
    let tmp = sss_util::Temporary::register(sss_util::temp_path(path));
    std::fs::File::create(tmp.path()).map_err(|e| PlotError::Draw {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let _ = std::fs::remove_file(tmp.path());
    Ok(())
}

/// Registers the embedded font with plotters (once); other drawing code calls this before
/// drawing text.
pub fn ensure_font() -> Result<(), PlotError> {
    register_font()
}

fn register_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

fn draw_all<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    panels: &[Panel<'_>],
    rows: usize,
    columns: usize,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let body = if title.is_empty() {
        root.clone()
    } else {
        root.titled(title, ("sans-serif", 26))
            .map_err(|e| e.to_string())?
    };
    let areas = body.split_evenly((rows, columns));
    for (panel, area) in panels.iter().zip(areas.iter()) {
        draw_panel(area, panel)?;
    }
    Ok(())
}

/// A series after filtering: its points split into runs of drawable points.
struct Prepared {
    name: String,
    color: RGBColor,
    style: SeriesStyle,
    err_style: ErrorStyle,
    /// (x, y, error) of every kept point.
    points: Vec<(f64, f64, f64)>,
}

fn prepare(panel: &Panel<'_>) -> Vec<Prepared> {
    panel
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let [r, g, b] = s.color.unwrap_or(PALETTE[i % PALETTE.len()]);
            let points = s
                .points
                .iter()
                .enumerate()
                .filter_map(|(k, &(x, y))| {
                    let ok = x.is_finite()
                        && y.is_finite()
                        && (!panel.log_x || x > 0.0)
                        && (!panel.log_y || y > 0.0);
                    let e = s
                        .y_err
                        .as_ref()
                        .and_then(|e| e.get(k).copied())
                        .filter(|e| e.is_finite())
                        .map_or(0.0, f64::abs);
                    ok.then_some((x, y, e))
                })
                .collect();
            Prepared {
                name: s.name.clone(),
                color: RGBColor(r, g, b),
                style: s.style,
                err_style: s.err_style,
                points,
            }
        })
        .collect()
}

/// The axis range covering `values`, padded; log ranges are limited to
/// [`MAX_LOG_DECADES`] below the maximum.
fn axis_range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        lo = lo.max(hi * 10f64.powf(-MAX_LOG_DECADES));
        // Exponents within ±300 keep both ends (and their padding) normal, finite numbers: a
        // subnormal end rounded to 0 made plotters' log ticks loop forever.
        let (l, h) = (
            lo.log10().clamp(-300.0, 300.0),
            hi.log10().clamp(-300.0, 300.0),
        );
        if h - l < 1.0 {
            // Less than a decade: show the enclosing decades so that labelled ticks exist.
            let (fl, ch) = (l.floor(), h.ceil());
            let ch = if ch > fl { ch } else { fl + 1.0 };
            return (10f64.powf(fl), 10f64.powf(ch));
        }
        let pad = ((h - l) * 0.03).max(0.05);
        (10f64.powf(l - pad), 10f64.powf(h + pad))
    } else {
        let span = hi - lo;
        let pad = if span > 0.0 {
            span * 0.03
        } else {
            lo.abs().max(1.0) * 0.1
        };
        (lo - pad, hi + pad)
    }
}

/// A short tick label: `1e-4` style on log axes, at most 4 significant digits on linear ones.
fn tick_label(v: f64, log: bool) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10();
    if log || !(-3.0..5.0).contains(&mag) {
        let rounded = format!("{v:.1e}");
        // 1.0e-4 -> 1e-4
        rounded.replace(".0e", "e")
    } else {
        let decimals = (3.0 - mag.floor()).clamp(0.0, 6.0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel<'_>,
) -> Result<(), String> {
    let prepared = prepare(panel);
    let xs = prepared.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let (x0, x1) = axis_range(xs, panel.log_x);
    let ys = prepared.iter().flat_map(|s| {
        s.points
            .iter()
            .flat_map(|&(_, y, e)| [y, y + e, if e < y { y - e } else { y }])
    });
    let (y0, y1) = axis_range(ys, panel.log_y);
    match (panel.log_x, panel.log_y) {
        (false, false) => draw_chart(area, panel, &prepared, x0..x1, y0..y1),
        (true, false) => draw_chart(area, panel, &prepared, (x0..x1).log_scale(), y0..y1),
        (false, true) => draw_chart(area, panel, &prepared, x0..x1, (y0..y1).log_scale()),
        (true, true) => draw_chart(
            area,
            panel,
            &prepared,
            (x0..x1).log_scale(),
            (y0..y1).log_scale(),
        ),
    }
}

fn draw_chart<DB, XR, YR>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel<'_>,
    prepared: &[Prepared],
    x_range: XR,
    y_range: YR,
) -> Result<(), String>
where
    DB: DrawingBackend,
    XR: AsRangedCoord<Value = f64>,
    YR: AsRangedCoord<Value = f64>,
    XR::CoordDescType: ValueFormatter<f64>,
    YR::CoordDescType: ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75);
    if !panel.title.is_empty() {
        builder.caption(panel.title, ("sans-serif", 20));
    }
    let mut chart = builder.build_cartesian_2d(x_range, y_range).map_err(e)?;
    let x_desc = chart.x_range();
    let y_desc = chart.y_range();
    let (y_lo, y_hi) = (y_desc.start, y_desc.end);
    let in_y = |y: f64| y >= y_lo && y <= y_hi;
    let in_x = |x: f64| x >= x_desc.start && x <= x_desc.end;
    let x_fmt = |v: &f64| tick_label(*v, panel.log_x);
    let y_fmt = |v: &f64| tick_label(*v, panel.log_y);
    chart
        .configure_mesh()
        .x_desc(panel.x_label)
        .y_desc(panel.y_label)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;

    let mut any_legend = false;
    for s in prepared {
        let color = s.color;
        // Errors first, so the lines stay on top.
        if s.points.iter().any(|p| p.2 > 0.0) {
            match s.err_style {
                ErrorStyle::Band => {
                    let kept: Vec<_> = s.points.iter().filter(|p| in_x(p.0)).collect();
                    let mut poly: Vec<(f64, f64)> = kept
                        .iter()
                        .map(|&&(x, y, err)| (x, (y + err).clamp(y_lo, y_hi)))
                        .collect();
                    poly.extend(
                        kept.iter()
                            .rev()
                            .map(|&&(x, y, err)| (x, (y - err).clamp(y_lo, y_hi))),
                    );
                    if poly.len() >= 3 {
                        chart
                            .draw_series(std::iter::once(Polygon::new(
                                poly,
                                color.mix(0.22).filled(),
                            )))
                            .map_err(e)?;
                    }
                }
                ErrorStyle::Bars => {
                    chart
                        .draw_series(s.points.iter().filter(|p| in_x(p.0) && p.2 > 0.0).map(
                            |&(x, y, err)| {
                                PathElement::new(
                                    vec![
                                        (x, (y - err).clamp(y_lo, y_hi)),
                                        (x, (y + err).clamp(y_lo, y_hi)),
                                    ],
                                    color.mix(0.7).stroke_width(1),
                                )
                            },
                        ))
                        .map_err(e)?;
                }
            }
        }
        // Runs of points inside the y range (points below the log floor break the line).
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for &(x, y, _) in &s.points {
            if in_y(y) && in_x(x) {
                runs.last_mut().expect("non-empty").push((x, y));
            } else if !runs.last().expect("non-empty").is_empty() {
                runs.push(Vec::new());
            }
        }
        runs.retain(|r| !r.is_empty());
        let line_style = color.stroke_width(2);
        let draw_line = matches!(
            s.style,
            SeriesStyle::Line | SeriesStyle::LineMarkers | SeriesStyle::Dashed
        );
        let draw_markers = matches!(s.style, SeriesStyle::Markers | SeriesStyle::LineMarkers);
        let mut legend_drawn = false;
        for run in &runs {
            let anno = if draw_line {
                if s.style == SeriesStyle::Dashed {
                    Some(
                        chart
                            .draw_series(DashedLineSeries::new(
                                run.iter().copied(),
                                8,
                                5,
                                line_style,
                            ))
                            .map_err(e)?,
                    )
                } else {
                    Some(
                        chart
                            .draw_series(LineSeries::new(run.iter().copied(), line_style))
                            .map_err(e)?,
                    )
                }
            } else {
                None
            };
            let anno = if draw_markers {
                Some(
                    chart
                        .draw_series(run.iter().map(|&p| Circle::new(p, 3, color.filled())))
                        .map_err(e)?,
                )
            } else {
                anno
            };
            if let Some(anno) = anno.filter(|_| !legend_drawn && !s.name.is_empty()) {
                let dashed = s.style == SeriesStyle::Dashed;
                anno.label(s.name.clone()).legend(move |(x, y)| {
                    if dashed {
                        PathElement::new(vec![(x, y), (x + 8, y)], color.stroke_width(2))
                    } else {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    }
                });
                legend_drawn = true;
                any_legend = true;
            }
        }
    }
    if any_legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font(("sans-serif", 14))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(e)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_by_extension() {
        assert_eq!(
            PlotFormat::from_path(Path::new("a/b.PNG")).unwrap(),
            PlotFormat::Png
        );
        assert_eq!(
            PlotFormat::from_path(Path::new("b.svg")).unwrap(),
            PlotFormat::Svg
        );
        assert!(PlotFormat::from_path(Path::new("b.pdf")).is_err());
        assert!(PlotFormat::from_path(Path::new("b")).is_err());
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(9.999999999e-5, true), "1e-4");
        assert_eq!(tick_label(0.001, true), "1e-3");
        assert_eq!(tick_label(2.5, false), "2.5");
        assert_eq!(tick_label(0.0, false), "0");
        assert_eq!(tick_label(1.0e7, false), "1e7");
        assert_eq!(tick_label(0.30000000000000004, false), "0.3");
    }

    #[test]
    fn log_range_is_limited_and_padded() {
        let (lo, hi) = axis_range([1e-30, 1e-3, 1.0, -1.0, f64::NAN].into_iter(), true);
        assert!(
            lo > 1e-11 && lo < 1e-10 && hi > 1.0 && hi < 2.5,
            "{lo} {hi}"
        );
        let (lo, hi) = axis_range([40.0, 150.0].into_iter(), true);
        assert!(
            (lo - 10.0).abs() < 1e-9 && (hi - 1000.0).abs() < 1e-9,
            "{lo} {hi}"
        );
        let (lo, hi) = axis_range([100.0].into_iter(), true);
        assert!(
            (lo - 100.0).abs() < 1e-9 && (hi - 1000.0).abs() < 1e-9,
            "{lo} {hi}"
        );
        let (lo, hi) = axis_range(std::iter::empty(), true);
        assert!(lo > 0.0 && hi > lo);
        let (lo, hi) = axis_range([2.0, 2.0].into_iter(), false);
        assert!(lo < 2.0 && hi > 2.0);
    }

    #[test]
    fn svg_plot_with_everything() {
        let dir = std::env::temp_dir().join(format!("sss-plot-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.svg");
        let pts: Vec<(f64, f64)> = (0..50)
            .map(|i| (i as f64 * 0.1, (-(i as f64) * 0.2).exp()))
            .collect();
        let n = pts.len();
        let series = [
            Series::line("band", pts.clone()).with_errors(vec![0.01; n], ErrorStyle::Band),
            Series::line("bars", pts.clone())
                .with_errors(vec![0.01; n], ErrorStyle::Bars)
                .with_style(SeriesStyle::Markers),
            Series::line("dashed", vec![(0.0, f64::NAN), (1.0, 0.5), (2.0, 0.1)])
                .with_style(SeriesStyle::Dashed),
        ];
        line_plot(&path, "t", "x", "y", &series, false, true).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("<svg") && text.contains("bars"));
        // No temporary file left behind.
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
