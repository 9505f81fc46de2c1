//! What the page shows of each scene, read from the output directory: the pictures under
//! `scenes/<scene>/` and the runs of `results.csv`.

use super::{data_uri, data_uri_of_png};
use sss_plot::{LabelledSeries, hover_svg};
use std::path::Path;

/// One run of `results.csv`: the columns the page shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub scene: String,
    pub method: String,
    pub param: String,
    pub value: f64,
    pub threads: usize,
    pub seconds: f64,
    pub rel_rmse: f64,
    pub frac_within_eps: f64,
    pub mean_ratio: f64,
    /// Absent in files without the column.
    pub flip: Option<f64>,
}

/// The rows of `results.csv` text; rows that do not parse are left out (the page shows what
/// it can; `cargo xtask check-results` judges the file).
pub fn parse_results(text: &str) -> Vec<Row> {
    let mut lines = text.lines();
    let Some(header) = lines.next() else {
        return Vec::new();
    };
    let header: Vec<&str> = header.split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let (
        Some(scene),
        Some(method),
        Some(param),
        Some(value),
        Some(threads),
        Some(seconds),
        Some(rel),
        Some(within),
        Some(ratio),
    ) = (
        col("scene"),
        col("method"),
        col("param"),
        col("value"),
        col("threads"),
        col("seconds_total"),
        col("rel_rmse"),
        col("frac_within_eps"),
        col("mean_ratio"),
    )
    else {
        return Vec::new();
    };
    let flip = col("flip");
    lines
        .filter_map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != header.len() {
                return None;
            }
            let num = |i: usize| f[i].parse::<f64>().ok();
            Some(Row {
                scene: f[scene].to_string(),
                method: f[method].to_string(),
                param: f[param].to_string(),
                value: num(value)?,
                threads: f[threads].parse().ok()?,
                seconds: num(seconds)?,
                rel_rmse: num(rel)?,
                frac_within_eps: num(within)?,
                mean_ratio: num(ratio)?,
                flip: flip.and_then(num),
            })
        })
        .collect()
}

/// One method's pictures and figures in a scene's viewer.
#[derive(Clone, Debug, Default)]
pub struct MethodView {
    /// `method param=value`.
    pub label: String,
    /// Data URIs of the method's image, signed error map, relative error map and FLIP map.
    pub image: Option<String>,
    pub signed: Option<String>,
    pub error: Option<String>,
    pub flip: Option<String>,
    /// Its run with the most threads, where `results.csv` has it.
    pub row: Option<Row>,
}

/// One scene's viewer.
#[derive(Clone, Debug, Default)]
pub struct Viewer {
    pub scene: String,
    /// What the reference is and what the methods are, one sentence for the reader.
    pub about: String,
    pub width: u32,
    pub height: u32,
    /// Data URI of the reference picture.
    pub reference: String,
    pub methods: Vec<MethodView>,
    /// The hardest region: x, y, width, height in pixels.
    pub crop: Option<[u32; 4]>,
    /// SVG charts (error and FLIP against time).
    pub charts: Vec<String>,
}

/// The pixels of a picture: width, height, 8-bit RGB.
pub type Pixels = (u32, u32, Vec<[u8; 3]>);

/// An 8-bit RGB picture decoded from PNG bytes (RGB or RGBA, 8 bits), or `None`.
pub fn decode_rgb(png_bytes: &[u8]) -> Option<Pixels> {
    let mut reader = png::Decoder::new(std::io::Cursor::new(png_bytes))
        .read_info()
        .ok()?;
    let mut buf = vec![0; reader.output_buffer_size()?];
    let info = reader.next_frame(&mut buf).ok()?;
    if info.bit_depth != png::BitDepth::Eight {
        return None;
    }
    let step = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        _ => return None,
    };
    let px = buf[..info.buffer_size()]
        .chunks_exact(step)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Some((info.width, info.height, px))
}

/// The names in directory `dir`, sorted (none where it cannot be read).
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .filter_map(|e| e.file_name().to_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// The PNG at `path`, read once: its data URI and its pixels.
fn read_picture(path: &Path) -> Option<(String, Option<Pixels>)> {
    let bytes = std::fs::read(path).ok()?;
    Some((data_uri_of_png(&bytes), decode_rgb(&bytes)))
}

/// A method's picture at `path` as a data URI; its pixels join `same_size` when they are as
/// large as the reference (`size`), for the hardest region.
fn method_picture(
    path: &Path,
    size: (u32, u32),
    same_size: &mut Vec<Vec<[u8; 3]>>,
) -> Option<String> {
    let (uri, pixels) = read_picture(path)?;
    if let Some((w, h, px)) = pixels
        && (w, h) == size
    {
        same_size.push(px);
    }
    Some(uri)
}

/// The window of a quarter of each side (at least 8 pixels, at most the picture) where the
/// pictures differ most from the reference, summed over pictures and channels; `None` when
/// no picture matches the reference's size or none differs.
pub fn hardest_region(reference: &Pixels, others: &[Vec<[u8; 3]>]) -> Option<[u32; 4]> {
    let (w, h, r) = reference;
    let (w, h) = (*w as usize, *h as usize);
    let n = w * h;
    let others: Vec<&Vec<[u8; 3]>> = others.iter().filter(|o| o.len() == n).collect();
    if n == 0 || others.is_empty() {
        return None;
    }
    // Summed-area table of the per-pixel difference.
    let mut sat = vec![0u64; (w + 1) * (h + 1)];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let d: u64 = others
                .iter()
                .map(|o| {
                    (0..3)
                        .map(|c| u64::from(o[i][c].abs_diff(r[i][c])))
                        .sum::<u64>()
                })
                .sum();
            sat[(y + 1) * (w + 1) + x + 1] =
                d + sat[y * (w + 1) + x + 1] + sat[(y + 1) * (w + 1) + x] - sat[y * (w + 1) + x];
        }
    }
    let (cw, ch) = ((w / 4).max(8).min(w), (h / 4).max(8).min(h));
    let mut best: Option<(u64, [u32; 4])> = None;
    for y in 0..=h - ch {
        for x in 0..=w - cw {
            let s = sat[(y + ch) * (w + 1) + x + cw] + sat[y * (w + 1) + x]
                - sat[y * (w + 1) + x + cw]
                - sat[(y + ch) * (w + 1) + x];
            if best.is_none_or(|(b, _)| s > b) {
                best = Some((s, [x as u32, y as u32, cw as u32, ch as u32]));
            }
        }
    }
    best.filter(|(s, _)| *s > 0).map(|(_, c)| c)
}

/// The value of a picture's file name as `results.csv` writes it (`{}` of the f64).
fn file_value(v: f64) -> String {
    format!("{v}")
}

/// The stem of a run's pictures: `<method>_<value>`.
fn stem(r: &Row) -> String {
    format!("{}_{}", r.method, file_value(r.value))
}

/// The viewers of every scene with a `scenes/<scene>/reference.png`, in the order of
/// `results.csv` (then by name); each method in the order of its first run.
pub fn viewers(out: &Path) -> Vec<Viewer> {
    let dir = out.join("scenes");
    let rows = std::fs::read_to_string(out.join("results.csv"))
        .map(|t| parse_results(&t))
        .unwrap_or_default();
    let mut names: Vec<String> = Vec::new();
    for r in &rows {
        if !names.contains(&r.scene) {
            names.push(r.scene.clone());
        }
    }
    for n in file_names(&dir) {
        if !names.contains(&n) && dir.join(&n).is_dir() {
            names.push(n);
        }
    }
    let mut viewers = Vec::new();
    for scene in names {
        let sdir = dir.join(&scene);
        let Some((reference_uri, Some(reference))) = read_picture(&sdir.join("reference.png"))
        else {
            continue;
        };
        let runs: Vec<&Row> = rows.iter().filter(|r| r.scene == scene).collect();
        // The methods with pictures: each `<method>_<value>_flip.png` or `_error.png`.
        let mut stems: Vec<String> = file_names(&sdir)
            .iter()
            .filter_map(|f| {
                f.strip_suffix("_error.png")
                    .or_else(|| f.strip_suffix("_flip.png"))
                    .map(String::from)
            })
            .collect();
        stems.sort();
        stems.dedup();
        stems.sort_by_key(|s| {
            runs.iter()
                .position(|r| stem(r) == *s)
                .unwrap_or(usize::MAX)
        });
        let mut pictures = Vec::new();
        let mut methods = Vec::new();
        for s in &stems {
            let row = runs
                .iter()
                .filter(|r| stem(r) == *s)
                .max_by_key(|r| r.threads)
                .map(|r| (*r).clone());
            let label = row.as_ref().map_or(s.clone(), |r| {
                format!("{} {}={}", r.method, r.param, file_value(r.value))
            });
            let file = |suffix: &str| data_uri(&sdir.join(format!("{s}{suffix}.png")));
            let size = (reference.0, reference.1);
            methods.push(MethodView {
                label,
                image: method_picture(&sdir.join(format!("{s}.png")), size, &mut pictures),
                signed: file("_signed"),
                error: file("_error"),
                flip: file("_flip"),
                row,
            });
        }
        let crop = hardest_region(&reference, &pictures);
        viewers.push(Viewer {
            scene: scene.clone(),
            about: "The reference (<code>exact</code>) and every method's most expensive run \
                    at one exposure (the reference's)."
                .into(),
            width: reference.0,
            height: reference.1,
            reference: reference_uri,
            methods,
            crop,
            charts: charts(&scene, &runs),
        });
    }
    viewers
}

/// The rows of `truth.csv` text as the page shows them: each model's `exact` image of a case
/// (`scene` is the case, `method` the model; `frac_within_eps` unknown, NaN).
pub fn parse_truth(text: &str) -> Vec<Row> {
    let mut lines = text.lines();
    let Some(header) = lines.next() else {
        return Vec::new();
    };
    let header: Vec<&str> = header.split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let [
        Some(case),
        Some(renderer),
        Some(method),
        Some(model),
        Some(threads),
        Some(seconds),
        Some(rel),
        Some(r),
        Some(g),
        Some(b),
    ] = [
        "case",
        "renderer",
        "method",
        "model",
        "threads",
        "seconds",
        "rel_rmse",
        "mean_ratio_r",
        "mean_ratio_g",
        "mean_ratio_b",
    ]
    .map(col)
    else {
        return Vec::new();
    };
    lines
        .filter_map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != header.len() || f[renderer] != "sss" || f[method] != "exact" {
                return None;
            }
            let num = |i: usize| f[i].parse::<f64>().ok();
            Some(Row {
                scene: f[case].to_string(),
                method: f[model].to_string(),
                param: String::new(),
                value: 0.0,
                threads: f[threads].parse().ok()?,
                seconds: num(seconds)?,
                rel_rmse: num(rel)?,
                frac_within_eps: f64::NAN,
                mean_ratio: (num(r)? + num(g)? + num(b)?) / 3.0,
                flip: None,
            })
        })
        .collect()
}

/// The viewers of the truth experiment's cases (`truth/<case>/`: `reference.png`, the
/// `volpath` reference, and each model's `exact` image `<model>.png` with its signed
/// difference `<model>_difference.png`), figures from `truth.csv`.
pub fn truth_viewers(out: &Path) -> Vec<Viewer> {
    let dir = out.join("truth");
    let rows = std::fs::read_to_string(out.join("truth.csv"))
        .map(|t| parse_truth(&t))
        .unwrap_or_default();
    let mut viewers = Vec::new();
    for case in file_names(&dir) {
        let cdir = dir.join(&case);
        let Some((reference_uri, Some(reference))) = read_picture(&cdir.join("reference.png"))
        else {
            continue;
        };
        let models: Vec<String> = file_names(&cdir)
            .iter()
            .filter_map(|f| f.strip_suffix("_difference.png").map(String::from))
            .collect();
        let mut pictures = Vec::new();
        let methods = models
            .iter()
            .map(|m| {
                let size = (reference.0, reference.1);
                MethodView {
                    label: format!("exact, {m}"),
                    image: method_picture(&cdir.join(format!("{m}.png")), size, &mut pictures),
                    signed: data_uri(&cdir.join(format!("{m}_difference.png"))),
                    error: None,
                    flip: None,
                    row: rows
                        .iter()
                        .find(|r| r.scene == case && r.method == *m)
                        .cloned(),
                }
            })
            .collect();
        viewers.push(Viewer {
            scene: case.clone(),
            about: "Real light transport against every model: the reference is \
                    <code>volpath</code> (volumetric path tracing of the medium), each model is \
                    rendered by <code>exact</code>, all at the reference's exposure; the map is \
                    the luminance difference over the reference's mean (±50 %)."
                .into(),
            width: reference.0,
            height: reference.1,
            reference: reference_uri,
            crop: hardest_region(&reference, &pictures),
            methods,
            charts: Vec::new(),
        });
    }
    viewers
}

/// The scene's relative RMSE and FLIP against run time (runs with the most threads), one
/// series per method, each point labelled with its run.
fn charts(scene: &str, runs: &[&Row]) -> Vec<String> {
    let threads = runs.iter().map(|r| r.threads).max().unwrap_or(0);
    let mut methods: Vec<&str> = Vec::new();
    for r in runs {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let series = |y: &dyn Fn(&Row) -> Option<f64>| -> Vec<LabelledSeries> {
        methods
            .iter()
            .map(|m| LabelledSeries {
                name: m.to_string(),
                points: runs
                    .iter()
                    .filter(|r| r.method == *m && r.threads == threads)
                    .filter_map(|r| {
                        let v = y(r)?;
                        let label = format!(
                            "{} {}={}: {:.3} s, rel. RMSE {:.3} %, FLIP {}, mean ratio {:.4}",
                            r.method,
                            r.param,
                            file_value(r.value),
                            r.seconds,
                            100.0 * r.rel_rmse,
                            r.flip.map_or("–".into(), |f| format!("{f:.4}")),
                            r.mean_ratio
                        );
                        Some((r.seconds, v, label))
                    })
                    .collect(),
                color: None,
            })
            .collect()
    };
    let mut out = vec![hover_svg(
        &format!("{scene}: relative RMSE against time ({threads} threads)"),
        "seconds",
        "relative RMSE",
        &series(&|r| Some(r.rel_rmse)),
        true,
        true,
    )];
    if runs.iter().any(|r| r.flip.is_some()) {
        out.push(hover_svg(
            &format!("{scene}: HDR-FLIP against time ({threads} threads)"),
            "seconds",
            "mean HDR-FLIP",
            &series(&|r| r.flip),
            true,
            true,
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_parse_by_column_name() {
        let text = "scene,method,param,value,threads,seconds_total,rel_rmse,frac_within_eps,mean_ratio,flip,warnings\n\
                    s,exact,spacing_mfp,2e0,2,1.5e0,1e-1,5e-1,1e0,2e-2,0\n\
                    s,exact,spacing_mfp,bad,2,1,1,1,1,1,0\n\
                    s,pathtrace,spp,1.6e1,1,3e0,2e-1,1e-1,9.9e-1,,0\n";
        let rows = parse_results(text);
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].value, 2.0);
        assert_eq!(rows[0].flip, Some(0.02));
        assert_eq!(rows[1].flip, None);
        assert_eq!(file_value(rows[1].value), "16");
        assert_eq!(file_value(0.05), "0.05");
        assert!(parse_results("no,columns\n1,2\n").is_empty());
    }

    #[test]
    fn truth_rows_are_each_models_exact_run() {
        let text = "case,scene,medium,light,renderer,method,model,param,value,threads,seconds,shading_s,\
                    mean_ratio_r,mean_ratio_g,mean_ratio_b,rel_rmse,rel_rmse_floor,warnings\n\
                    c,s,skin1,quad,sss,exact,pbd,,0e0,2,3e-1,1e-1,7e-1,8e-1,9e-1,2.5e-1,,0\n\
                    c,s,skin1,quad,sss,pathtrace,pbd,spp,2.56e2,2,5e-1,1e-1,7e-1,8e-1,9e-1,3e-1,,0\n\
                    c,s,skin1,quad,mitsuba,volpathmis,,spp,1.6e1,2,5e-1,1e-1,1,1,1,1,,0\n";
        let rows = parse_truth(text);
        assert_eq!(rows.len(), 1);
        assert_eq!(
            (rows[0].scene.as_str(), rows[0].method.as_str()),
            ("c", "pbd")
        );
        assert!((rows[0].mean_ratio - 0.8).abs() < 1e-12);
        assert_eq!(rows[0].rel_rmse, 0.25);
        assert!(parse_truth("case\nx\n").is_empty());
    }

    #[test]
    fn the_hardest_region_is_where_pictures_differ() {
        let (w, h) = (40u32, 32u32);
        let reference = (w, h, vec![[100u8; 3]; (w * h) as usize]);
        let mut a = reference.2.clone();
        // A bright patch at (28..34, 20..26).
        for y in 20..26 {
            for x in 28..34 {
                a[(y * w + x) as usize] = [200, 100, 100];
            }
        }
        let c = hardest_region(&reference, &[a.clone()]).unwrap();
        assert_eq!((c[2], c[3]), (10, 8));
        // The window holds the whole 6 × 6 patch.
        assert!(
            c[0] <= 28 && c[0] + c[2] >= 34 && c[1] <= 20 && c[1] + c[3] >= 26,
            "{c:?}"
        );
        assert_eq!(
            hardest_region(&reference, std::slice::from_ref(&reference.2)),
            None
        );
        assert_eq!(hardest_region(&reference, &[vec![[0; 3]; 3]]), None);
    }
}
