//! False-colour error maps: per-pixel values drawn with a colour bar and a title, as PNG.

use crate::PlotError;
use plotters::prelude::*;
use std::path::Path;

/// A perceptually uniform colour map of matplotlib (van der Walt, Smith & Firing), from
/// `colorous`'s 256-entry tables (d3-scale-chromatic's, exact to 8 bits).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ColourMap {
    /// Black through purple and orange to pale yellow: the toolkit's error maps.
    #[default]
    Inferno,
    /// Black through purple to pale pink: FLIP's maps, as NVIDIA draws them.
    Magma,
    /// Dark blue through green to yellow.
    Viridis,
}

impl ColourMap {
    /// The colour at t ∈ [0, 1] (clamped; a non-finite t is 0).
    pub fn colour(self, t: f64) -> [u8; 3] {
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let c = match self {
            ColourMap::Inferno => colorous::INFERNO,
            ColourMap::Magma => colorous::MAGMA,
            ColourMap::Viridis => colorous::VIRIDIS,
        }
        .eval_continuous(t);
        [c.r, c.g, c.b]
    }
}

/// The inferno colour of t in [0, 1] ([`ColourMap::Inferno`]).
pub fn false_colour(t: f64) -> [u8; 3] {
    ColourMap::Inferno.colour(t)
}

/// A diverging colour for t in [−1, 1]: ColorBrewer's red-blue (Brewer, from `colorous`),
/// blue at −1 through a light grey at 0 to red at +1, so that a signed difference reads at a
/// glance (too dark is blue, too bright red).
pub fn diverging_colour(t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    // colorous' RED_BLUE runs from red (0) to blue (1).
    let c = colorous::RED_BLUE.eval_continuous(0.5 * (1.0 - t));
    [c.r, c.g, c.b]
}

/// The colour of a value beyond a map's range (above `max`, or below `-max` on a signed
/// map): a saturated green, found in neither the inferno nor the blue-white-red map, shown
/// as a swatch above the colour bar with the count of such pixels.
pub const OVER_RANGE: [u8; 3] = [0, 220, 0];

/// How an unsigned map's values become colours: linear over [0, `max`], or with `log`
/// logarithmic over [`max`·10⁻³, `max`] (three decades; smaller values at the bottom colour),
/// through `colours`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapScale {
    /// The top of the colour bar; larger values are drawn [`OVER_RANGE`].
    pub max: f64,
    /// Three decades on a log scale instead of a linear one.
    pub log: bool,
    /// The colour map.
    pub colours: ColourMap,
}

/// Decades a log-scaled map spans.
const LOG_DECADES: f64 = 3.0;

/// A map's range: `max`, or 1 for a non-positive or non-finite one.
fn usable_max(max: f64) -> f64 {
    if max.is_finite() && max > 0.0 {
        max
    } else {
        1.0
    }
}

impl MapScale {
    fn max(&self) -> f64 {
        usable_max(self.max)
    }

    /// The colour of value `v` (non-negative): the colour map at its position on the bar,
    /// [`OVER_RANGE`] above `max`.
    pub fn colour(&self, v: f64) -> [u8; 3] {
        let max = self.max();
        if v > max {
            return OVER_RANGE;
        }
        self.colours.colour(self.position(v))
    }

    /// Where `v` sits on the bar, 0 (bottom) to 1 (top).
    pub fn position(&self, v: f64) -> f64 {
        let max = self.max();
        if !self.log {
            return (v / max).clamp(0.0, 1.0);
        }
        let lo = max * 10f64.powf(-LOG_DECADES);
        if !(v > lo) {
            return 0.0;
        }
        ((v / lo).log10() / LOG_DECADES).clamp(0.0, 1.0)
    }

    /// The value at bar position `t`.
    pub fn value_at(&self, t: f64) -> f64 {
        let max = self.max();
        if self.log {
            max * 10f64.powf(LOG_DECADES * (t - 1.0))
        } else {
            t * max
        }
    }
}

/// Draws a false-colour map of per-pixel `values` (None: not part of the comparison, drawn
/// grey) scaled from 0 to `max`, with a colour bar labelled `label` and a title, as a PNG.
/// Values above `max` are drawn [`OVER_RANGE`] and counted beside the bar.
pub fn write_error_map(
    path: &Path,
    width: u32,
    height: u32,
    values: &[Option<f64>],
    max: f64,
    title: &str,
    label: &str,
) -> Result<(), PlotError> {
    let scale = MapScale {
        max,
        log: false,
        colours: ColourMap::Inferno,
    };
    write_error_map_with(path, width, height, values, &scale, title, label)
}

/// [`write_error_map`] on a chosen scale (linear or three decades of log).
pub fn write_error_map_with(
    path: &Path,
    width: u32,
    height: u32,
    values: &[Option<f64>],
    scale: &MapScale,
    title: &str,
    label: &str,
) -> Result<(), PlotError> {
    let image = MapImage {
        path,
        width,
        height,
        values,
    };
    let map = Map {
        colour: &|v| scale.colour(v),
        bar: &|t| scale.colours.colour(t),
        tick: &|t| scale.value_at(t),
    };
    draw_map(&image, &map, title, label)
}

/// Draws a FLIP map (per-pixel errors in [0, 1], as `sss_render::flip` gives them) in magma,
/// as NVIDIA draws them, with a 0–1 colour bar labelled `FLIP` and a title, as a PNG.
pub fn write_flip_map(
    path: &Path,
    width: u32,
    height: u32,
    values: &[f32],
    title: &str,
) -> Result<(), PlotError> {
    let values: Vec<Option<f64>> = values.iter().map(|&v| Some(f64::from(v))).collect();
    let scale = MapScale {
        max: 1.0,
        log: false,
        colours: ColourMap::Magma,
    };
    write_error_map_with(path, width, height, &values, &scale, title, "FLIP")
}

/// Draws a map of signed per-pixel `values` (None: drawn grey) from −`max` (blue) through 0
/// (white) to +`max` (red) with a colour bar, as a PNG: where an image is darker or brighter
/// than its reference.
pub fn write_signed_map(
    path: &Path,
    width: u32,
    height: u32,
    values: &[Option<f64>],
    max: f64,
    title: &str,
    label: &str,
) -> Result<(), PlotError> {
    let image = MapImage {
        path,
        width,
        height,
        values,
    };
    let max = usable_max(max);
    let map = Map {
        colour: &|v| {
            if v.abs() > max {
                OVER_RANGE
            } else {
                diverging_colour(v / max)
            }
        },
        bar: &|t| diverging_colour(2.0 * t - 1.0),
        tick: &|t| (2.0 * t - 1.0) * max,
    };
    draw_map(&image, &map, title, label)
}

/// Where a map goes and what it shows.
struct MapImage<'a> {
    path: &'a Path,
    width: u32,
    height: u32,
    values: &'a [Option<f64>],
}

/// How values become colours: a value's colour ([`OVER_RANGE`] beyond the range), the bar's
/// colour at t ∈ [0, 1] (bottom to top) and the value a bar position stands for.
struct Map<'a> {
    colour: &'a dyn Fn(f64) -> [u8; 3],
    bar: &'a dyn Fn(f64) -> [u8; 3],
    tick: &'a dyn Fn(f64) -> f64,
}

fn draw_map(
    image: &MapImage<'_>,
    map: &Map<'_>,
    title: &str,
    label: &str,
) -> Result<(), PlotError> {
    let MapImage {
        path,
        width,
        height,
        values,
    } = *image;
    let draw_err = |message: String| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    };
    if values.len() != width as usize * height as usize {
        return Err(draw_err(format!(
            "{} values for a {width}x{height} image",
            values.len()
        )));
    }
    crate::check_writable(path)?;
    let scale = (512 / width.max(height)).clamp(1, 8);
    let (iw, ih) = (width * scale, height * scale);
    // Each pixel's colour once: drawn, and counted where it marks a value beyond the range.
    let colours: Vec<[u8; 3]> = values
        .iter()
        .map(|v| v.map_or([128, 128, 128], |v| (map.colour)(v)))
        .collect();
    let over = values
        .iter()
        .zip(&colours)
        .filter(|(v, c)| v.is_some() && **c == OVER_RANGE)
        .count();
    let over_text = format!("{over} px beyond the range");
    // Wide enough for the tick labels, the bar's label and the over-range count (about 7
    // pixels a character at 13 px).
    let text_w = 7 * label.chars().count().max(over_text.chars().count()) as u32;
    let (bar_w, margin, title_h) = (150u32.max(text_w + 30), 10u32, 30u32);
    // 20 pixels under the bar for its label (which the bottom margin alone used to clip).
    let size = (
        iw + bar_w + 2 * margin,
        ih.max(200) + title_h + 2 * margin + 20,
    );
    crate::ensure_font()?;
    let draw = |tmp: &Path| -> Result<(), String> {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        root.draw_text(
            title,
            &("sans-serif", 18).into_text_style(&root),
            (margin as i32, 5),
        )
        .map_err(|e| e.to_string())?;
        let (ox, oy) = (margin as i32, (title_h + margin) as i32);
        for y in 0..height {
            for x in 0..width {
                let col = colours[(y * width + x) as usize];
                let c = RGBColor(col[0], col[1], col[2]);
                for dy in 0..scale {
                    for dx in 0..scale {
                        root.draw_pixel(
                            (ox + (x * scale + dx) as i32, oy + (y * scale + dy) as i32),
                            &c,
                        )
                        .map_err(|e| e.to_string())?;
                    }
                }
            }
        }
        // Colour bar, under the over-range swatch.
        let bx = ox + iw as i32 + 20;
        let style = ("sans-serif", 13).into_text_style(&root);
        root.draw(&Rectangle::new(
            [(bx, oy), (bx + 20, oy + 14)],
            RGBColor(OVER_RANGE[0], OVER_RANGE[1], OVER_RANGE[2]).filled(),
        ))
        .map_err(|e| e.to_string())?;
        root.draw_text(&over_text, &style, (bx + 26, oy))
            .map_err(|e| e.to_string())?;
        let oy = oy + 24;
        let bh = ih.max(200) as i32 - 24;
        for j in 0..bh {
            let t = 1.0 - j as f64 / (bh - 1).max(1) as f64;
            let col = (map.bar)(t);
            root.draw(&Rectangle::new(
                [(bx, oy + j), (bx + 20, oy + j + 1)],
                RGBColor(col[0], col[1], col[2]).filled(),
            ))
            .map_err(|e| e.to_string())?;
        }
        for k in 0..=4 {
            let t = k as f64 / 4.0;
            let yy = oy + ((1.0 - t) * (bh - 1) as f64) as i32;
            root.draw_text(&format!("{:.3e}", (map.tick)(t)), &style, (bx + 26, yy - 6))
                .map_err(|e| e.to_string())?;
        }
        root.draw_text(label, &style, (bx, oy + bh + 4))
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())
    };
    sss_util::write_atomic_with(
        path,
        |tmp| draw(tmp).map_err(draw_err),
        |e| draw_err(e.to_string()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_diverging_map_is_white_at_zero_and_darkens_towards_each_end() {
        // ColorBrewer's RdBu (11 classes) through d3's uniform B-spline: #053061 and #67001f
        // at the ends; in the middle (#fddbc7 + 4·#f7f7f7 + #d1e5f0) / 6 = (241.7, 239.3,
        // 237.8), truncated.
        // Within 1 of each (the table's f32 arithmetic truncates).
        let near = |a: [u8; 3], b: [u8; 3]| a.iter().zip(b).all(|(x, y)| x.abs_diff(y) <= 1);
        assert!(near(diverging_colour(0.0), [241, 239, 237]));
        assert!(near(diverging_colour(-1.0), [0x05, 0x30, 0x61]));
        assert!(near(diverging_colour(1.0), [0x67, 0x00, 0x1f]));
        assert_eq!(diverging_colour(7.0), diverging_colour(1.0));
        assert_eq!(diverging_colour(f64::NAN), diverging_colour(0.0));
        // Blue below zero, red above; farther from zero, farther from white.
        let sum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
        let (a, b) = (diverging_colour(-0.3), diverging_colour(0.3));
        assert!(a[2] > a[0] && b[0] > b[2]);
        assert!(sum(diverging_colour(0.6)) < sum(b) && sum(diverging_colour(-0.6)) < sum(a));
    }

    #[test]
    fn the_colour_maps_are_matplotlibs_tables() {
        // The first and last entries of matplotlib's _cm_listed.py tables (×255, rounded).
        assert_eq!(ColourMap::Inferno.colour(0.0), [0, 0, 4]);
        assert_eq!(ColourMap::Inferno.colour(1.0), [252, 255, 164]);
        assert_eq!(ColourMap::Magma.colour(0.0), [0, 0, 4]);
        assert_eq!(ColourMap::Magma.colour(1.0), [252, 253, 191]);
        assert_eq!(ColourMap::Viridis.colour(0.0), [68, 1, 84]);
        assert_eq!(ColourMap::Viridis.colour(1.0), [253, 231, 37]);
        // Viridis' middle entry (index 128 of 256: 0.127568, 0.566949, 0.550556).
        let mid = ColourMap::Viridis.colour(128.0 / 255.0);
        for (c, want) in mid.iter().zip([0.127568f64, 0.566949, 0.550556]) {
            assert!((f64::from(*c) - 255.0 * want).abs() <= 1.0, "{mid:?}");
        }
        assert_eq!(ColourMap::Inferno.colour(f64::NAN), [0, 0, 4]);
        assert_eq!(false_colour(2.0), ColourMap::Inferno.colour(1.0));
    }

    #[test]
    fn values_beyond_the_range_are_marked_and_the_log_scale_spans_three_decades() {
        let lin = MapScale {
            max: 0.2,
            log: false,
            colours: ColourMap::Inferno,
        };
        assert_eq!(lin.colour(0.2), false_colour(1.0));
        assert_eq!(lin.colour(0.2000001), OVER_RANGE);
        assert_eq!(lin.colour(0.1), false_colour(0.5));
        // The marker is in neither map.
        for k in 0..=100 {
            let t = k as f64 / 100.0;
            for map in [ColourMap::Inferno, ColourMap::Magma, ColourMap::Viridis] {
                assert_ne!(map.colour(t), OVER_RANGE);
            }
            assert_ne!(diverging_colour(2.0 * t - 1.0), OVER_RANGE);
        }
        let log = MapScale {
            max: 0.2,
            log: true,
            colours: ColourMap::Magma,
        };
        assert!((log.position(0.2) - 1.0).abs() < 1e-12);
        assert!((log.position(0.02) - 2.0 / 3.0).abs() < 1e-12);
        assert!((log.position(0.002) - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(log.position(0.0002), 0.0);
        assert_eq!(log.position(0.0), 0.0);
        assert_eq!(log.colour(0.3), OVER_RANGE);
        assert_eq!(log.colour(0.2), ColourMap::Magma.colour(1.0));
        for t in [0.0, 0.25, 0.5, 1.0] {
            assert!((log.position(log.value_at(t)) - t).abs() < 1e-12);
            assert!((lin.position(lin.value_at(t)) - t).abs() < 1e-12);
        }
        // Bad maxima count as 1.
        let bad = MapScale {
            max: f64::NAN,
            log: false,
            colours: ColourMap::Inferno,
        };
        assert_eq!(bad.colour(1.0), false_colour(1.0));
        assert_eq!(bad.colour(1.5), OVER_RANGE);
    }

    #[test]
    fn a_signed_map_is_written_and_a_wrong_size_is_an_error() {
        let dir = std::env::temp_dir().join(format!("sss-plot-signed-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("d.png");
        let values: Vec<Option<f64>> = (0..12)
            .map(|i| (i != 5).then_some(i as f64 - 6.0))
            .collect();
        write_signed_map(&p, 4, 3, &values, 6.0, "signed", "Δ").unwrap();
        assert!(std::fs::metadata(&p).unwrap().len() > 100);
        let e = write_signed_map(&p, 5, 3, &values, 6.0, "signed", "Δ").unwrap_err();
        assert!(e.to_string().contains("12 values for a 5x3 image"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
