//! The page itself: markup of each scene's viewer, the style sheet and the script (inline:
//! the page needs nothing beyond its own file).

use super::super::output::{md_num, md_pct};
use super::markdown::slug;
use super::scenes::{MethodView, Viewer};
use sss_plot::escape_xml;
use std::fmt::Write as _;

const STYLE: &str = r#"
body { font-family: system-ui, sans-serif; margin: 0 auto; max-width: 1400px; padding: 0 1.5em 4em; color: #222; }
nav { position: sticky; top: 0; background: #fff; padding: .5em 0; border-bottom: 1px solid #ddd; z-index: 2; }
nav a { margin-right: 1em; }
table { border-collapse: collapse; margin: .6em 0; font-size: 13px; }
th, td { border: 1px solid #ccc; padding: 2px 6px; text-align: right; }
th:first-child, td:first-child { text-align: left; }
code { background: #f3f3f3; padding: 0 2px; }
img.figure { max-width: 100%; display: block; margin: .5em 0; }
.viewer { border-top: 2px solid #888; margin-top: 2em; }
.buttons button { margin: 2px; padding: 3px 8px; border: 1px solid #999; background: #f7f7f7; cursor: pointer; }
.buttons button.on { background: #234; color: #fff; }
.controls { margin: .4em 0; font-size: 14px; }
.stage { --split: 50%; display: flex; gap: 1.5em; flex-wrap: wrap; align-items: flex-start; }
.stack { position: relative; width: min(100%, 720px); }
.stack img { width: 100%; display: block; image-rendering: pixelated; }
.stack .test { position: absolute; left: 0; top: 0; clip-path: inset(0 0 0 var(--split)); }
.stack .test:not(.on), .caption:not(.on), .maps > div:not(.on) { display: none; }
.stack .split { position: absolute; left: 0; bottom: -1.6em; width: 100%; margin: 0; }
.stack .bar { position: absolute; top: 0; bottom: 0; left: var(--split); border-left: 2px solid #fff; pointer-events: none; }
.stack .box { position: absolute; border: 2px dashed #0f0; pointer-events: none; }
.stack .tag { position: absolute; top: 4px; padding: 1px 5px; background: rgba(0,0,0,.6); color: #fff; font-size: 12px; }
.stage.side .stack { display: grid; grid-template-columns: 1fr 1fr; gap: 6px; width: min(100%, 1200px); }
.stage.side .stack .test { position: static; clip-path: none; }
.stage.side .split, .stage.side .bar, .stage.side .box, .stage.side .tag { display: none; }
.caption { margin-top: 2em; font-size: 14px; }
.crops { display: flex; gap: 1em; flex-wrap: wrap; }
.crops figure { margin: 0; }
.crops canvas { border: 1px solid #999; image-rendering: pixelated; max-width: 100%; }
.maps img { max-width: 32%; margin-right: 1%; vertical-align: top; }
tr[data-m] { cursor: pointer; }
tr.on { background: #dde8f5; }
svg.chart { max-width: 100%; height: auto; margin-right: 1em; }
"#;

const SCRIPT: &str = r#"
(function () {
  var body = document.body, errors = 0;
  window.addEventListener('error', function (e) {
    if (!(e.target && e.target.tagName === 'IMG')) { errors++; body.dataset.errors = errors; }
  }, true);
  function crops(v) {
    var c = v.querySelector('.crops');
    if (!c) return;
    var r = c.dataset.crop.split(',').map(Number), z = +v.querySelector('.zoom').value;
    var test = v.querySelector('.test.on'), ref = v.querySelector('.ref');
    [[ref, '.crop-ref'], [test, '.crop-test']].forEach(function (p) {
      var cv = c.querySelector(p[1]);
      if (!p[0] || !cv || !p[0].naturalWidth) return;
      cv.width = r[2] * z; cv.height = r[3] * z;
      var g = cv.getContext('2d');
      g.imageSmoothingEnabled = false;
      g.drawImage(p[0], r[0], r[1], r[2], r[3], 0, 0, r[2] * z, r[3] * z);
    });
    c.querySelector('.crop-name').textContent = test ? test.alt : '';
  }
  function select(v, m) {
    v.querySelectorAll('[data-m]').forEach(function (e) { e.classList.toggle('on', e.dataset.m === m); });
    crops(v);
  }
  document.querySelectorAll('.viewer').forEach(function (v) {
    v.querySelectorAll('button[data-m], tr[data-m]').forEach(function (b) {
      b.addEventListener('click', function () { select(v, b.dataset.m); });
    });
    var stage = v.querySelector('.stage'), split = v.querySelector('.split');
    split.addEventListener('input', function () { stage.style.setProperty('--split', split.value + '%'); });
    v.querySelectorAll('input.mode').forEach(function (r) {
      r.addEventListener('change', function () { stage.classList.toggle('side', r.value === 'side' && r.checked); });
    });
    var zoom = v.querySelector('.zoom');
    if (zoom) zoom.addEventListener('input', function () { crops(v); });
  });
  window.addEventListener('load', function () {
    var imgs = Array.prototype.slice.call(document.images);
    var broken = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); });
    body.dataset.images = imgs.length;
    body.dataset.broken = broken.length;
    body.dataset.charts = document.querySelectorAll('svg.chart').length;
    body.dataset.points = document.querySelectorAll('svg.chart circle').length;
    document.querySelectorAll('.viewer').forEach(crops);
    body.dataset.errors = errors;
    body.dataset.ready = '1';
  });
})();
"#;

/// The figures of a method's run, one line.
fn caption(m: &MethodView) -> String {
    match &m.row {
        Some(r) => format!(
            "<b>{}</b>: {} s ({} threads), rel. RMSE {}, FLIP {}, mean / ref. mean {}, within 5 %: {}",
            escape_xml(&m.label),
            md_num(Some(r.seconds), 3),
            r.threads,
            md_pct(Some(r.rel_rmse)),
            md_num(r.flip, 3),
            md_num(Some(r.mean_ratio), 4),
            md_pct(Some(r.frac_within_eps))
        ),
        None => format!("<b>{}</b>", escape_xml(&m.label)),
    }
}

fn img(uri: Option<&str>, class: &str, alt: &str, m: Option<usize>) -> String {
    match uri {
        Some(u) => format!(
            "<img class=\"{class}\"{} src=\"{}\" alt=\"{}\">",
            m.map_or(String::new(), |i| format!(" data-m=\"{i}\"")),
            escape_xml(u),
            escape_xml(alt)
        ),
        None => String::new(),
    }
}

fn viewer(v: &Viewer) -> String {
    let mut s = String::new();
    let id = slug(&v.scene);
    let on = |i: usize| if i == 0 { " on" } else { "" };
    let _ = write!(
        s,
        "<section class=\"viewer\" id=\"scene-{id}\"><h2>{}</h2>\
         <p>{}×{} pixels. {} Drag the slider: reference left, method right; click a method or \
         a row of the table.</p><div class=\"buttons\">",
        escape_xml(&v.scene),
        v.width,
        v.height,
        v.about
    );
    for (i, m) in v.methods.iter().enumerate() {
        let _ = write!(
            s,
            "<button class=\"{}\" data-m=\"{i}\">{}</button>",
            on(i).trim(),
            escape_xml(&m.label)
        );
    }
    let _ = write!(
        s,
        "</div><div class=\"controls\"><label><input type=\"radio\" class=\"mode\" \
         name=\"mode-{id}\" value=\"slider\" checked> slider</label> <label><input \
         type=\"radio\" class=\"mode\" name=\"mode-{id}\" value=\"side\"> side by side</label>"
    );
    if let Some([_, _, w, _]) = v.crop {
        // The crops start about 320 pixels wide.
        let zoom = (320 / w.max(1)).clamp(2, 24);
        let _ = write!(
            s,
            " &nbsp; crop zoom <input type=\"range\" class=\"zoom\" min=\"1\" max=\"32\" \
             value=\"{zoom}\">"
        );
    }
    s.push_str("</div><div class=\"stage\"><div class=\"stack\">");
    s.push_str(&img(Some(&v.reference), "ref", "reference", None));
    for (i, m) in v.methods.iter().enumerate() {
        if m.image.is_some() {
            s.push_str(&img(
                m.image.as_deref(),
                &format!("test{}", on(i)),
                &m.label,
                Some(i),
            ));
        }
    }
    s.push_str(
        "<div class=\"bar\"></div><span class=\"tag\" style=\"left:4px\">reference</span>\
         <span class=\"tag\" style=\"right:4px\">method</span>",
    );
    if let Some([x, y, w, h]) = v.crop {
        let (fw, fh) = (f64::from(v.width.max(1)), f64::from(v.height.max(1)));
        let _ = write!(
            s,
            "<div class=\"box\" style=\"left:{:.3}%;top:{:.3}%;width:{:.3}%;height:{:.3}%\"></div>",
            100.0 * f64::from(x) / fw,
            100.0 * f64::from(y) / fh,
            100.0 * f64::from(w) / fw,
            100.0 * f64::from(h) / fh
        );
    }
    s.push_str(
        "<input type=\"range\" class=\"split\" min=\"0\" max=\"100\" value=\"50\" \
         aria-label=\"split\"></div>",
    );
    if let Some([x, y, w, h]) = v.crop {
        let _ = write!(
            s,
            "<div><p>The hardest region (dashed; {w}×{h} pixels at {x}, {y}: where the methods \
             differ most from the reference):</p><div class=\"crops\" data-crop=\"{x},{y},{w},{h}\">\
             <figure><canvas class=\"crop-ref\"></canvas><figcaption>reference</figcaption></figure>\
             <figure><canvas class=\"crop-test\"></canvas><figcaption class=\"crop-name\">\
             </figcaption></figure></div></div>"
        );
    }
    s.push_str("</div>");
    for (i, m) in v.methods.iter().enumerate() {
        let _ = write!(
            s,
            "<div class=\"caption{}\" data-m=\"{i}\">{}</div>",
            on(i),
            caption(m)
        );
    }
    s.push_str("<div class=\"maps\">");
    for (i, m) in v.methods.iter().enumerate() {
        let _ = write!(s, "<div class=\"{}\" data-m=\"{i}\">", on(i).trim());
        s.push_str(&img(
            m.signed.as_deref(),
            "map",
            &format!("{}: signed error", m.label),
            None,
        ));
        s.push_str(&img(
            m.error.as_deref(),
            "map",
            &format!("{}: relative error", m.label),
            None,
        ));
        s.push_str(&img(
            m.flip.as_deref(),
            "map",
            &format!("{}: HDR-FLIP", m.label),
            None,
        ));
        s.push_str("</div>");
    }
    s.push_str(
        "</div><table><thead><tr><th>method</th><th>seconds</th><th>threads</th>\
                <th>rel. RMSE</th><th>HDR-FLIP</th><th>mean / ref. mean</th><th>within 5 %</th>\
                </tr></thead><tbody>",
    );
    for (i, m) in v.methods.iter().enumerate() {
        let r = m.row.as_ref();
        let _ = write!(
            s,
            "<tr class=\"{}\" data-m=\"{i}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td></tr>",
            on(i).trim(),
            escape_xml(&m.label),
            md_num(r.map(|r| r.seconds), 3),
            r.map_or("–".into(), |r| r.threads.to_string()),
            md_pct(r.map(|r| r.rel_rmse)),
            md_num(r.and_then(|r| r.flip), 3),
            md_num(r.map(|r| r.mean_ratio), 4),
            md_pct(r.map(|r| r.frac_within_eps)),
        );
    }
    s.push_str("</tbody></table><div class=\"charts\">");
    for c in &v.charts {
        s.push_str(&c.replacen("<svg ", "<svg class=\"chart\" ", 1));
    }
    s.push_str("</div></section>\n");
    s
}

/// The whole page: the viewers, then the report's body (already HTML).
pub fn page(viewers: &[Viewer], report: &str) -> String {
    let mut s = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>sss: comparison report</title><style>",
    );
    s.push_str(STYLE);
    s.push_str("</style></head><body><nav>");
    for v in viewers {
        let _ = write!(
            s,
            "<a href=\"#scene-{}\">{}</a>",
            slug(&v.scene),
            escape_xml(&v.scene)
        );
    }
    s.push_str("<a href=\"#report\">report</a></nav>");
    if !viewers.is_empty() {
        s.push_str("<h1>Scenes: every method against the reference</h1>");
    }
    for v in viewers {
        s.push_str(&viewer(v));
    }
    s.push_str("<section id=\"report\">");
    s.push_str(report);
    s.push_str("</section><script>");
    s.push_str(SCRIPT);
    s.push_str("</script></body></html>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::super::scenes::Row;
    use super::*;

    #[test]
    fn figures_read_plainly() {
        assert_eq!(md_num(Some(4.56789), 3), "4.57");
        assert_eq!(md_num(Some(0.012345), 3), "0.0123");
        assert_eq!(md_num(Some(1234.4), 3), "1234");
        assert_eq!(md_num(Some(2.5e-5), 2), "2.5e-5");
        assert_eq!(md_num(Some(0.0), 3), "0");
        assert_eq!(md_num(None, 3), "–");
        assert_eq!(md_num(Some(f64::NAN), 3), "–");
        assert_eq!(md_pct(Some(0.0391)), "3.91 %");
    }

    #[test]
    fn a_viewer_holds_every_methods_pictures_and_figures() {
        let row = Row {
            scene: "s".into(),
            method: "exact".into(),
            param: "spacing_mfp".into(),
            value: 2.0,
            threads: 2,
            seconds: 1.5,
            rel_rmse: 0.04,
            frac_within_eps: 0.5,
            mean_ratio: 1.0,
            flip: Some(0.02),
        };
        let uri = |k: &str| Some(format!("data:image/png;base64,{k}"));
        let v = Viewer {
            scene: "s <1>".into(),
            about: "About.".into(),
            width: 40,
            height: 20,
            reference: "data:image/png;base64,REF".into(),
            methods: vec![
                MethodView {
                    label: "exact spacing_mfp=2".into(),
                    image: uri("A"),
                    signed: uri("AS"),
                    error: uri("AE"),
                    flip: uri("AF"),
                    row: Some(row),
                },
                MethodView {
                    label: "separable taps=15".into(),
                    image: uri("B"),
                    ..MethodView::default()
                },
            ],
            crop: Some([10, 5, 10, 5]),
            charts: vec!["<svg x></svg>".into()],
        };
        let html = page(&[v], "<p>report</p>");
        assert!(html.starts_with("<!DOCTYPE html>") && html.ends_with("</html>\n"));
        assert!(
            !html.contains("src=\"http") && !html.contains("href=\"http"),
            "no network"
        );
        for k in ["REF", "A", "AS", "AF", "B"] {
            assert!(html.contains(&format!("base64,{k}\"")), "{k} missing");
        }
        assert!(html.contains("s &lt;1&gt;") && !html.contains("s <1>"));
        assert!(html.contains("<img class=\"test on\" data-m=\"0\""));
        assert!(html.contains("<img class=\"test\" data-m=\"1\""));
        assert!(html.contains("rel. RMSE 4.00 %, FLIP 0.0200"));
        assert!(html.contains("data-crop=\"10,5,10,5\""));
        assert!(html.contains("left:25.000%;top:25.000%;width:25.000%;height:25.000%"));
        assert!(html.contains("<svg class=\"chart\" x></svg>"));
        assert!(html.contains("<p>report</p>"));
    }
}
