//! The Markdown `report.md` is written in, as HTML: headings, paragraphs, pipe tables, `- `
//! lists, `code`, *emphasis*, **strong** and images. That subset is all the report uses; any
//! other line is a paragraph's text, escaped, so nothing in the report can inject markup.
//! Images are handed to `image` with their alternative text, which returns the markup to
//! show (a picture inlined) or `None` for a file that is not there (then the alternative text
//! is shown instead of a broken image).

use sss_plot::escape_xml;
use std::fmt::Write as _;

/// An `id` for a heading: lower-case letters and digits, other runs as one `-`.
pub fn slug(text: &str) -> String {
    let mut s = String::new();
    for c in text.chars() {
        if c.is_alphanumeric() {
            s.extend(c.to_lowercase());
        } else if !s.ends_with('-') && !s.is_empty() {
            s.push('-');
        }
    }
    s.trim_end_matches('-').to_string()
}

/// Inline markup of one escaped line: `code`, **strong**, *emphasis*, and ![alt](file).
fn inline(text: &str, image: &mut Images<'_>) -> String {
    let mut out = String::new();
    let mut rest = text;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('`')
            && let Some(end) = r.find('`')
        {
            let _ = write!(out, "<code>{}</code>", escape_xml(&r[..end]));
            rest = &r[end + 1..];
        } else if let Some(r) = rest.strip_prefix("![")
            && let Some(mid) = r.find("](")
            && let Some(end) = r[mid..].find(')')
        {
            let (alt, file) = (&r[..mid], &r[mid + 2..mid + end]);
            match image(file, alt) {
                Some(markup) => out.push_str(&markup),
                None => {
                    let _ = write!(
                        out,
                        "<em>[{} — {} not found]</em>",
                        escape_xml(alt),
                        escape_xml(file)
                    );
                }
            }
            rest = &r[mid + end + 1..];
        } else if let Some(r) = rest.strip_prefix("**")
            && let Some(end) = r.find("**")
            && end > 0
        {
            let _ = write!(out, "<strong>{}</strong>", inline(&r[..end], image));
            rest = &r[end + 2..];
        } else if let Some(r) = rest.strip_prefix('*')
            && let Some(end) = r.find('*')
            && end > 0
            && !r.starts_with(' ')
        {
            let _ = write!(out, "<em>{}</em>", inline(&r[..end], image));
            rest = &r[end + 1..];
        } else {
            let c = rest.chars().next().unwrap_or(' ');
            out.push_str(&escape_xml(&c.to_string()));
            rest = &rest[c.len_utf8()..];
        }
    }
    out
}

/// The cells of a table row `| a | b |`.
fn cells(line: &str) -> Vec<&str> {
    let t = line.trim();
    let t = t.strip_prefix('|').unwrap_or(t);
    let t = t.strip_suffix('|').unwrap_or(t);
    t.split('|').map(str::trim).collect()
}

fn is_rule(line: &str) -> bool {
    let c = cells(line);
    !c.is_empty()
        && c.iter()
            .all(|c| !c.is_empty() && c.chars().all(|ch| matches!(ch, '-' | ':')))
}

/// How an image (its file, its alternative text) becomes markup.
pub type Images<'a> = dyn FnMut(&str, &str) -> Option<String> + 'a;

/// `markdown` as HTML, images through `image`.
pub fn to_html(markdown: &str, image: &mut Images<'_>) -> String {
    let lines: Vec<&str> = markdown.lines().collect();
    let mut out = String::new();
    let mut i = 0;
    let mut para: Vec<&str> = Vec::new();
    let flush = |para: &mut Vec<&str>, out: &mut String, image: &mut Images<'_>| {
        if !para.is_empty() {
            let _ = writeln!(out, "<p>{}</p>", inline(&para.join(" "), image));
            para.clear();
        }
    };
    while i < lines.len() {
        let line = lines[i];
        let t = line.trim_start();
        if t.is_empty() {
            flush(&mut para, &mut out, image);
            i += 1;
        } else if let Some(level) = (1..=6).find(|&n| {
            // Bytes, not `t[..n]`: a line may start with a character of several bytes.
            let b = t.as_bytes();
            b.len() > n && b[..n].iter().all(|&c| c == b'#') && b[n] == b' '
        }) {
            flush(&mut para, &mut out, image);
            let text = t[level + 1..].trim();
            let _ = writeln!(
                out,
                "<h{level} id=\"{}\">{}</h{level}>",
                slug(text),
                inline(text, image)
            );
            i += 1;
        } else if t.starts_with('|') && i + 1 < lines.len() && is_rule(lines[i + 1]) {
            flush(&mut para, &mut out, image);
            out.push_str("<table>\n<thead><tr>");
            for c in cells(t) {
                let _ = write!(out, "<th>{}</th>", inline(c, image));
            }
            out.push_str("</tr></thead>\n<tbody>\n");
            i += 2;
            while i < lines.len() && lines[i].trim_start().starts_with('|') {
                out.push_str("<tr>");
                for c in cells(lines[i]) {
                    let _ = write!(out, "<td>{}</td>", inline(c, image));
                }
                out.push_str("</tr>\n");
                i += 1;
            }
            out.push_str("</tbody></table>\n");
        } else if t.starts_with("- ") || t.starts_with("* ") {
            flush(&mut para, &mut out, image);
            out.push_str("<ul>\n");
            while i < lines.len() {
                let l = lines[i].trim_start();
                if let Some(item) = l.strip_prefix("- ").or_else(|| l.strip_prefix("* ")) {
                    let _ = writeln!(out, "<li>{}</li>", inline(item, image));
                    i += 1;
                } else {
                    break;
                }
            }
            out.push_str("</ul>\n");
        } else {
            para.push(t);
            i += 1;
        }
    }
    flush(&mut para, &mut out, image);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn html(md: &str) -> String {
        to_html(md, &mut |f: &str, alt: &str| {
            (f == "a.png").then(|| format!("<img src=\"data:image/png;base64,AA\" alt=\"{alt}\">"))
        })
    }

    #[test]
    fn the_reports_subset_becomes_html() {
        let md = "# Title here\n\nSome `code <x>` and *it* and **bold**.\nSame paragraph.\n\n\
                  | a | b |\n|---|---|\n| 1 | `2` |\n| 3 | 4 |\n\n- one\n- *two*\n\n\
                  ![plot](a.png)\n\n![gone](b.png)\n";
        let h = html(md);
        assert!(h.contains("<h1 id=\"title-here\">Title here</h1>"), "{h}");
        assert!(h.contains("<p>Some <code>code &lt;x&gt;</code> and <em>it</em> and <strong>bold</strong>. Same paragraph.</p>"), "{h}");
        assert!(
            h.contains("<thead><tr><th>a</th><th>b</th></tr></thead>"),
            "{h}"
        );
        assert!(
            h.contains("<tr><td>1</td><td><code>2</code></td></tr>"),
            "{h}"
        );
        assert!(h.contains("<tr><td>3</td><td>4</td></tr>"), "{h}");
        assert!(
            h.contains("<ul>\n<li>one</li>\n<li><em>two</em></li>\n</ul>"),
            "{h}"
        );
        assert!(
            h.contains("<img src=\"data:image/png;base64,AA\" alt=\"plot\""),
            "{h}"
        );
        assert!(
            h.contains("[gone — b.png not found]") && !h.contains("b.png\""),
            "{h}"
        );
    }

    #[test]
    fn nothing_in_the_text_becomes_markup() {
        let h = html("<script>alert(1)</script> & |x|\n\n#not a heading\n");
        assert!(!h.contains("<script>"), "{h}");
        assert!(
            h.contains("&lt;script&gt;alert(1)&lt;/script&gt; &amp; |x|"),
            "{h}"
        );
        assert!(h.contains("<p>#not a heading</p>"), "{h}");
        // A lone asterisk or backtick is text.
        let h = html("3 * 4 and a ` tick");
        assert_eq!(h, "<p>3 * 4 and a ` tick</p>\n");
    }

    /// A line starting with a character of several bytes is text, not a heading, and does
    /// not panic: the heading test sliced the line at byte 1, inside the `–` (the shard
    /// merge's fuzz target reached it through a report section of a shard).
    #[test]
    fn lines_starting_with_wide_characters_are_text() {
        for line in ["–", "–x", "é# x", "#–", "##–x", "€€€€€€€€ y", "# é"]
        {
            let h = html(&format!("{line}\n"));
            if line == "# é" {
                assert_eq!(h, "<h1 id=\"é\">é</h1>\n");
            } else {
                assert_eq!(h, format!("<p>{line}</p>\n"), "{line}");
            }
        }
    }

    #[test]
    fn slugs_are_plain() {
        assert_eq!(
            slug("Scenes: references & error"),
            "scenes-references-error"
        );
        assert_eq!(slug("  x  "), "x");
    }
}
