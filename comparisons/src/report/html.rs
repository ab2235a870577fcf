//! `report.html`: a self-contained page of a command's Markdown report with its plots inlined
//! as SVG, for people who would rather look than read; one file to open or attach.

use pulldown_cmark::{html, Options, Parser};
use std::path::{Path, PathBuf};

const STYLE: &str = "body{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}\
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}th,td{border:1px solid #ccc;padding:0.25em 0.6em;text-align:right}\
th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}tr:nth-child(even){background:#fafafa}\
code{background:#f3f3f3;padding:0 0.2em}figure{margin:1.5em 0}figure svg{max-width:100%;height:auto}\
figcaption{font-size:0.85em;color:#555}";

/// The page: `markdown` rendered (tables, lists, code), then each plot of `plots` (SVG files;
/// missing ones are skipped) inlined in a figure with its file name as caption.
pub fn page(title: &str, markdown: &str, plots: &[PathBuf]) -> String {
    let mut body = String::new();
    html::push_html(&mut body, Parser::new_ext(markdown, Options::ENABLE_TABLES));
    let mut figures = String::new();
    for p in plots {
        let Ok(svg) = std::fs::read_to_string(p) else {
            continue;
        };
        // Inline SVG: no XML declaration inside HTML.
        let svg = match svg.find("<svg") {
            Some(k) => &svg[k..],
            None => continue,
        };
        let name = p
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        figures += &format!(
            "<figure>{svg}<figcaption>{}</figcaption></figure>\n",
            escape(&name)
        );
    }
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title><style>{STYLE}</style></head>\n<body>\n<h1>{t}</h1>\n{body}{figures}<footer><p>grainbench {v}</p></footer>\n</body></html>\n",
        t = escape(title),
        v = env!("CARGO_PKG_VERSION"),
    )
}

/// Writes [`page`] to `dir/report.html` atomically; returns its path.
pub fn write(
    dir: &Path,
    title: &str,
    markdown: &str,
    plots: &[PathBuf],
) -> std::io::Result<PathBuf> {
    let path = dir.join("report.html");
    grainbench_engine::snapshot::write_atomic(&path, page(title, markdown, plots).as_bytes())?;
    Ok(path)
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_and_plots_are_inlined() {
        let dir = tempfile::tempdir().unwrap();
        let svg = dir.path().join("pf.svg");
        std::fs::write(
            &svg,
            "<?xml version=\"1.0\"?>\n<svg width=\"10\" height=\"10\"><circle r=\"2\"/></svg>",
        )
        .unwrap();
        let md = "## run <x>\n\n| code | Φ |\n| --- | ---: |\n| rust | 0.6030 |\n\n- note `a`\n";
        let html = page("t & u", md, &[svg, dir.path().join("missing.svg")]);
        assert!(html.contains("<title>t &amp; u</title>"));
        assert!(
            html.contains("<table>") && html.contains("<td>rust</td>"),
            "{html}"
        );
        assert!(
            html.contains("<svg width=\"10\"") && !html.contains("<?xml"),
            "{html}"
        );
        assert!(html.contains("<figcaption>pf.svg</figcaption>"));
        assert_eq!(html.matches("<figure>").count(), 1);
        assert!(html.contains("<li>note <code>a</code></li>"));
    }
}
