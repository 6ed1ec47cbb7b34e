//! A single self-contained HTML report: headings, paragraphs, tables and figures.
//!
//! The page loads nothing from outside: SVG figures are inlined, PNG figures are `data:` URIs,
//! styles and the script are inline, and a Content-Security-Policy forbids any other source,
//! so the file can be mailed or archived and still shows everything. All text is HTML-escaped.
//!
//! A small inline script runs on `load` and checks that each figure was really drawn (an `<img>`
//! is complete with a non-zero natural width, an inline `<svg>` has a non-empty bounding box).
//! It writes the result into `<p id="figure-check" data-ok="…" data-total="…">`: a headless
//! browser (`chromium --headless --dump-dom`) can assert it, and a reader sees it only when a
//! figure is broken (the line is hidden when every figure rendered).

use std::fmt::Write as _;
use std::hash::{Hash, Hasher};
use std::io;
use std::path::{Path, PathBuf};

use super::atomic::write_atomic;

/// One table: caption, header row and body rows (each row as long as the header).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Caption shown above the table.
    pub caption: String,
    /// Column titles (with units, e.g. `"RMS e₂ (mrad)"`).
    pub header: Vec<String>,
    /// Body rows; cells that parse as numbers are right-aligned.
    pub rows: Vec<Vec<String>>,
}

/// The picture of a report figure.
#[derive(Debug, Clone, PartialEq)]
pub enum Image {
    /// An SVG document (e.g. from [`super::plot::render_svg`]), inlined into the page.
    Svg(String),
    /// PNG file bytes (e.g. from [`super::plot::render_png`]), embedded as a base64 data URI.
    Png(Vec<u8>),
    /// An interactive figure: the chart data of [`super::chart::chart_json`], drawn in the page
    /// by the vendored uPlot (zoom, pan, hover values).
    Chart(String),
}

/// A figure: picture and caption.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportFigure {
    /// Caption below the picture (also the PNG's alt text).
    pub caption: String,
    /// The picture.
    pub image: Image,
}

/// One piece of the report, rendered in order.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    /// A section heading (`<h2>`).
    Heading(String),
    /// A paragraph of plain text.
    Paragraph(String),
    /// Preformatted text, e.g. the scenario file or the command line (`<pre>`).
    Code(String),
    /// A table.
    Table(Table),
    /// A figure.
    Figure(ReportFigure),
    /// A bulleted list of sentences (e.g. the verdict), with a CSS class.
    List {
        /// CSS class of the `<ul>` (`"verdict"`).
        class: String,
        /// The items, plain text.
        items: Vec<String>,
    },
    /// The table of contents: a link to every heading of the page, drawn here.
    Toc,
    /// Opens a folded part (`<details>`) with this summary line; closed by [`Block::DetailsEnd`].
    DetailsStart(String),
    /// Closes the folded part opened last.
    DetailsEnd,
    /// The 3-D replay of the runs: the data of [`super::replay::replay_json`], drawn by the
    /// page's WebGL script (`assets/replay.js`).
    Replay(String),
}

/// A report page: title and blocks in reading order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Report {
    /// Page title (`<title>` and `<h1>`).
    pub title: String,
    /// Content in order.
    pub blocks: Vec<Block>,
}

/// Why a report could not be built or written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A table row has a different number of cells than the header.
    #[error(
        "table {caption:?}: row {row} has {len} cells but the header has {expected}; \
         give every row one cell per column"
    )]
    RaggedTable {
        /// Table caption.
        caption: String,
        /// Row index (0-based).
        row: usize,
        /// Cells in that row.
        len: usize,
        /// Cells in the header.
        expected: usize,
    },
    /// An SVG figure is not a plain `<svg>…</svg>` document (or contains a script).
    #[error("figure {caption:?}: the SVG must be one <svg>…</svg> element without scripts")]
    BadSvg {
        /// Figure caption.
        caption: String,
    },
    /// A PNG figure does not start with the PNG signature.
    #[error("figure {caption:?}: the image bytes are not a PNG file")]
    BadPng {
        /// Figure caption.
        caption: String,
    },
    /// Writing the HTML file failed.
    #[error("writing report to {}: {source}", path.display())]
    Io {
        /// The file that could not be written.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
}

impl Report {
    /// An empty report.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    /// Appends a heading.
    pub fn heading(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Heading(text.into()));
        self
    }

    /// Appends a paragraph.
    pub fn paragraph(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }

    /// Appends preformatted text.
    pub fn code(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Code(text.into()));
        self
    }

    /// Appends a table.
    pub fn table(&mut self, table: Table) -> &mut Self {
        self.blocks.push(Block::Table(table));
        self
    }

    /// Appends a bulleted list of sentences with a CSS class.
    pub fn list(&mut self, class: &str, items: Vec<String>) -> &mut Self {
        self.blocks.push(Block::List {
            class: class.into(),
            items,
        });
        self
    }

    /// Appends the table of contents (links to every heading of the page).
    pub fn toc(&mut self) -> &mut Self {
        self.blocks.push(Block::Toc);
        self
    }

    /// Opens a folded part: `summary` shows, the blocks up to [`Report::end_details`] open
    /// on a click.
    pub fn details(&mut self, summary: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::DetailsStart(summary.into()));
        self
    }

    /// Closes the folded part opened last.
    pub fn end_details(&mut self) -> &mut Self {
        self.blocks.push(Block::DetailsEnd);
        self
    }

    /// Appends the 3-D replay (data of [`super::replay::replay_json`]).
    pub fn replay(&mut self, json: String) -> &mut Self {
        self.blocks.push(Block::Replay(json));
        self
    }

    /// Appends a figure.
    pub fn figure(&mut self, caption: impl Into<String>, image: Image) -> &mut Self {
        self.blocks.push(Block::Figure(ReportFigure {
            caption: caption.into(),
            image,
        }));
        self
    }

    /// Number of figures (the `data-total` of the figure check).
    pub fn figure_count(&self) -> usize {
        self.blocks
            .iter()
            .filter(|b| matches!(b, Block::Figure(_)))
            .count()
    }

    /// Renders the page.
    ///
    /// The Content-Security-Policy allows only `data:` images, inline styles and the one
    /// checker script (by nonce), so inline event handlers inside figures cannot run either.
    /// The nonce is a hash of the page body: the output is deterministic.
    pub fn to_html(&self) -> Result<String, ReportError> {
        let total = self.figure_count();
        let title = escape(&self.title);
        let mut body = String::with_capacity(64 * 1024);
        let _ = writeln!(body, "<h1>{title}</h1>");
        let _ = writeln!(
            body,
            "<p id=\"figure-check\" class=\"pending\" data-ok=\"0\" data-total=\"{total}\">\
             Figure check has not run (JavaScript is disabled?).</p>"
        );
        let mut fig_no = 0;
        let anchors = self.anchors();
        let mut heading_no = 0;
        let mut open_details = 0usize;
        for block in &self.blocks {
            match block {
                Block::Heading(t) => {
                    let _ = writeln!(
                        body,
                        "<h2 id=\"{}\">{}</h2>",
                        anchors[heading_no].0,
                        escape(t)
                    );
                    heading_no += 1;
                }
                Block::List { class, items } => {
                    let _ = writeln!(body, "<ul class=\"{}\">", escape(class));
                    for i in items {
                        let _ = writeln!(body, "<li>{}</li>", escape(i));
                    }
                    body.push_str("</ul>\n");
                }
                Block::Toc => {
                    body.push_str("<nav id=\"toc\"><strong>Contents</strong><ol>\n");
                    for (id, t) in &anchors {
                        let _ = writeln!(body, "<li><a href=\"#{id}\">{}</a></li>", escape(t));
                    }
                    body.push_str("</ol></nav>\n");
                }
                Block::DetailsStart(summary) => {
                    open_details += 1;
                    let _ = writeln!(body, "<details><summary>{}</summary>", escape(summary));
                }
                Block::Replay(json) => replay_html(&mut body, json),
                Block::DetailsEnd => {
                    if open_details > 0 {
                        open_details -= 1;
                        body.push_str("</details>\n");
                    }
                }
                Block::Paragraph(t) => {
                    let _ = writeln!(body, "<p>{}</p>", escape(t));
                }
                Block::Code(t) => {
                    let _ = writeln!(body, "<pre>{}</pre>", escape(t));
                }
                Block::Table(t) => table_html(&mut body, t)?,
                Block::Figure(f) => {
                    fig_no += 1;
                    figure_html(&mut body, f, fig_no)?;
                }
            }
        }
        for _ in 0..open_details {
            body.push_str("</details>\n");
        }
        let nonce = {
            let mut hasher = std::collections::hash_map::DefaultHasher::new();
            body.hash(&mut hasher);
            format!("{:016x}", hasher.finish())
        };
        let mut h = String::with_capacity(body.len() + 8 * 1024);
        h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        let _ = writeln!(
            h,
            "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; \
             img-src data:; style-src 'unsafe-inline'; script-src 'nonce-{nonce}'\">"
        );
        h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        h.push_str("<meta name=\"generator\" content=\"ofmpc\">\n");
        let _ = writeln!(h, "<title>{title}</title>");
        let charts = self.blocks.iter().any(|b| {
            matches!(
                b,
                Block::Figure(ReportFigure {
                    image: Image::Chart(_),
                    ..
                })
            )
        });
        let replay = self.blocks.iter().any(|b| matches!(b, Block::Replay(_)));
        let chart_css = if charts { UPLOT_CSS } else { "" };
        let _ = writeln!(
            h,
            "<style>{CSS}{chart_css}</style>\n</head>\n<body>\n<main>"
        );
        h.push_str(&body);
        h.push_str("</main>\n");
        if charts {
            let _ = writeln!(h, "<script nonce=\"{nonce}\">{UPLOT_JS}</script>");
            let _ = writeln!(h, "<script nonce=\"{nonce}\">{CHARTS_JS}</script>");
        }
        if replay {
            let _ = writeln!(h, "<script nonce=\"{nonce}\">{REPLAY_JS}</script>");
        }
        let _ = writeln!(
            h,
            "<script nonce=\"{nonce}\">{SCRIPT}</script>\n</body>\n</html>"
        );
        Ok(h)
    }

    /// The anchor id and text of every heading, in order: `sec-<slug>`, unique on the page.
    fn anchors(&self) -> Vec<(String, String)> {
        let mut seen = std::collections::HashSet::new();
        let mut v = Vec::new();
        for b in &self.blocks {
            if let Block::Heading(t) = b {
                let mut slug: String = t
                    .chars()
                    .map(|c| {
                        if c.is_ascii_alphanumeric() {
                            c.to_ascii_lowercase()
                        } else {
                            '-'
                        }
                    })
                    .collect();
                while slug.contains("--") {
                    slug = slug.replace("--", "-");
                }
                let base = format!("sec-{}", slug.trim_matches('-'));
                let mut id = base.clone();
                let mut k = 2;
                while !seen.insert(id.clone()) {
                    id = format!("{base}-{k}");
                    k += 1;
                }
                v.push((id, t.clone()));
            }
        }
        v
    }

    /// Renders the page and writes it to `path` atomically.
    pub fn write(&self, path: &Path) -> Result<(), ReportError> {
        let html = self.to_html()?;
        write_atomic(path, html.as_bytes()).map_err(|source| ReportError::Io {
            path: path.to_path_buf(),
            source,
        })
    }
}

/// Escapes text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
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

/// Standard base64 (RFC 4648 §4, with `=` padding).
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(char::from(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Whether a cell reads as a number (right-aligned).
fn is_numeric(cell: &str) -> bool {
    let t = cell.trim();
    !t.is_empty() && t.replace('\u{2212}', "-").parse::<f64>().is_ok()
}

fn table_html(h: &mut String, t: &Table) -> Result<(), ReportError> {
    for (i, row) in t.rows.iter().enumerate() {
        if row.len() != t.header.len() {
            return Err(ReportError::RaggedTable {
                caption: t.caption.clone(),
                row: i,
                len: row.len(),
                expected: t.header.len(),
            });
        }
    }
    h.push_str("<table>\n");
    if !t.caption.is_empty() {
        let _ = writeln!(h, "<caption>{}</caption>", escape(&t.caption));
    }
    h.push_str("<thead><tr>");
    for c in &t.header {
        let _ = write!(h, "<th>{}</th>", escape(c));
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for row in &t.rows {
        h.push_str("<tr>");
        for c in row {
            if is_numeric(c) {
                let _ = write!(h, "<td class=\"num\">{}</td>", escape(c));
            } else {
                let _ = write!(h, "<td>{}</td>", escape(c));
            }
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody>\n</table>\n");
    Ok(())
}

/// The `<svg …>…</svg>` element of an SVG document (XML declaration and comments before it
/// dropped), or `None` if it is not one or contains a script.
fn svg_element(svg: &str) -> Option<&str> {
    let mut s = svg.trim();
    if s.starts_with("<?xml") {
        s = s[s.find("?>")? + 2..].trim_start();
    }
    while s.starts_with("<!--") {
        s = s[s.find("-->")? + 3..].trim_start();
    }
    let lower = s.to_ascii_lowercase();
    let ok = lower.starts_with("<svg")
        && lower.ends_with("</svg>")
        && !lower.contains("<script")
        && !lower.contains("<foreignobject");
    ok.then_some(s)
}

fn figure_html(h: &mut String, f: &ReportFigure, no: usize) -> Result<(), ReportError> {
    let caption = escape(&f.caption);
    match &f.image {
        Image::Svg(svg) => {
            let el = svg_element(svg).ok_or_else(|| ReportError::BadSvg {
                caption: f.caption.clone(),
            })?;
            let _ = writeln!(
                h,
                "<figure class=\"report-figure\" id=\"figure-{no}\" data-kind=\"svg\">\n{el}"
            );
        }
        Image::Chart(json) => {
            let _ = writeln!(
                h,
                "<figure class=\"report-figure\" id=\"figure-{no}\" data-kind=\"chart\">\n\
                 <div class=\"chart\"></div>\n<script type=\"application/json\" class=\"chart-data\">{}</script>",
                json.replace('<', "\\u003c")
            );
        }
        Image::Png(png) => {
            if !png.starts_with(b"\x89PNG\r\n\x1a\n") {
                return Err(ReportError::BadPng {
                    caption: f.caption.clone(),
                });
            }
            let _ = writeln!(
                h,
                "<figure class=\"report-figure\" id=\"figure-{no}\" data-kind=\"png\">\n\
                 <img alt=\"{caption}\" src=\"data:image/png;base64,{}\">",
                base64(png)
            );
        }
    }
    let _ = writeln!(h, "<figcaption>{caption}</figcaption>\n</figure>");
    Ok(())
}

/// The replay's section: canvas, controls and data (see `assets/replay.js`).
fn replay_html(h: &mut String, json: &str) {
    let _ = writeln!(
        h,
        "<section id=\"replay\" class=\"replay\" data-ready=\"no\">\n\
         <div class=\"replay-controls\"><button type=\"button\" id=\"replay-play\">Play</button>\n\
         <input type=\"range\" id=\"replay-slider\" min=\"0\" max=\"0\" value=\"0\" step=\"1\">\n\
         <span id=\"replay-time\">t = 0 s</span>\n<select id=\"replay-run\"></select>\n\
         <label>speed <select id=\"replay-speed\"><option value=\"1\" selected>1×</option>\
         <option value=\"4\">4×</option><option value=\"16\">16×</option><option value=\"64\">64×</option>\
         </select></label>\n\
         <label><input type=\"checkbox\" id=\"replay-follow\"> slow motion</label></div>\n\
         <canvas id=\"replay-canvas\" width=\"960\" height=\"540\"></canvas>\n\
         <p id=\"replay-state\" class=\"replay-state\"></p>\n\
         <script type=\"application/json\" id=\"replay-data\">{}</script>\n</section>",
        json.replace('<', "\\u003c")
    );
}

/// uPlot 1.6.32 (MIT, `assets/uplot/LICENSE`), from the npm registry.
const UPLOT_JS: &str = include_str!("../../assets/uplot/uPlot.iife.min.js");
/// uPlot's style sheet.
const UPLOT_CSS: &str = include_str!("../../assets/uplot/uPlot.min.css");
/// Draws the [`Image::Chart`] figures with uPlot.
const CHARTS_JS: &str = include_str!("../../assets/charts.js");
/// The 3-D replay (raw WebGL).
const REPLAY_JS: &str = include_str!("../../assets/replay.js");

const CSS: &str = "
body{margin:0;background:#fff;color:#1a1a1a;font:16px/1.5 'DejaVu Sans',Verdana,sans-serif}
main{max-width:1180px;margin:0 auto;padding:1.5em}
h1{font-size:1.6em;margin:.2em 0 .6em}h2{font-size:1.25em;margin:1.6em 0 .5em;border-bottom:1px solid #ddd}
pre{background:#f6f6f6;padding:.8em;overflow-x:auto;font-size:.85em}
table{border-collapse:collapse;margin:1em 0;font-size:.9em}
caption{text-align:left;font-weight:bold;padding:.3em 0}
th,td{border:1px solid #ccc;padding:.25em .6em}th{background:#f0f0f0}td.num{text-align:right;font-variant-numeric:tabular-nums}
figure{margin:1.2em 0}div.chart{display:flex;flex-wrap:wrap;gap:12px}div.chart-panel{flex:0 0 auto}
section.replay{margin:1em 0}#replay-canvas{width:100%;max-width:960px;border:1px solid #ddd;background:#fbfbfb;display:block}
.replay-controls{display:flex;gap:.8em;align-items:center;margin:.4em 0}#replay-slider{flex:1;max-width:600px}.replay-state{font-size:.85em;color:#444;font-variant-numeric:tabular-nums}
figure svg,figure img{display:block;max-width:100%;height:auto}
figcaption{font-size:.9em;color:#444;margin-top:.4em}
nav#toc{background:#f6f8fa;border:1px solid #ddd;padding:.5em 1em;margin:1em 0;font-size:.92em}nav#toc ol{margin:.3em 0;columns:2}
ul.verdict{background:#f3f7ff;border-left:4px solid #3b6fd8;padding:.6em 1em .6em 2em;margin:1em 0}
details{margin:.5em 0;border:1px solid #e3e3e3;border-radius:4px;padding:.2em .8em}summary{cursor:pointer;font-weight:bold;padding:.3em 0}
#figure-check{font-size:.85em;padding:.3em .6em;border-radius:3px}
#figure-check.ok{display:none}#figure-check.bad,#figure-check.pending{background:#fdecea;color:#8a1c1c}
";

const SCRIPT: &str = "
(function () {
  function drawn(fig) {
    if (fig.getAttribute('data-kind') === 'chart') {
      var cs = fig.querySelectorAll('canvas');
      return fig.getAttribute('data-drawn') === 'yes' && cs.length > 0 && cs[0].width > 0;
    }
    var img = fig.querySelector('img');
    if (img) { return img.complete && img.naturalWidth > 0 && img.naturalHeight > 0; }
    var svg = fig.querySelector('svg');
    if (!svg) { return false; }
    var r = svg.getBoundingClientRect();
    var b;
    try { b = svg.getBBox(); } catch (e) { return false; }
    return r.width > 0 && r.height > 0 && b.width > 0 && b.height > 0;
  }
  // Text that does not fit: a text run past the window's left or right edge, or cut by a
  // box that hides its overflow; and text on the charts' canvases (charts.js, data-clipped).
  // Scrollable boxes (the scenario's <pre>) and closed <details> do not count.
  function clippedText() {
    var bad = [], vw = document.documentElement.clientWidth;
    var walker = document.createTreeWalker(document.querySelector('main') || document.body, NodeFilter.SHOW_TEXT);
    var range = document.createRange();
    for (var node = walker.nextNode(); node; node = walker.nextNode()) {
      if (!node.textContent.trim()) { continue; }
      var el = node.parentElement;
      if (!el || el.closest('script, style, svg, pre')) { continue; }
      range.selectNodeContents(node);
      var r = range.getBoundingClientRect();
      if (r.width === 0 && r.height === 0) { continue; }
      var what = node.textContent.trim().slice(0, 40);
      if (r.left < -1 || r.right > vw + 1) { bad.push('[' + what + '] past the window edge'); continue; }
      for (var a = el; a && a !== document.body; a = a.parentElement) {
        var cs = getComputedStyle(a);
        if (cs.overflowX === 'hidden' || cs.overflowX === 'clip' || cs.overflowY === 'hidden' || cs.overflowY === 'clip') {
          var b = a.getBoundingClientRect();
          if (r.left < b.left - 1 || r.right > b.right + 1 || r.top < b.top - 1 || r.bottom > b.bottom + 1) {
            bad.push('[' + what + '] cut by its box'); break;
          }
        }
      }
    }
    var panels = document.querySelectorAll('[data-clipped]');
    for (var i = 0; i < panels.length; i++) {
      if (panels[i].id === 'figure-check') { continue; }
      if (+panels[i].getAttribute('data-clipped') > 0) { bad.push(panels[i].getAttribute('data-clipped-what')); }
    }
    return bad;
  }
  function check() {
    if (location.hash.indexOf('open-all') >= 0) {
      var ds = document.querySelectorAll('details');
      for (var d = 0; d < ds.length; d++) { ds[d].open = true; }
    }
    var figs = document.querySelectorAll('figure.report-figure');
    var ok = 0;
    for (var i = 0; i < figs.length; i++) {
      var good = drawn(figs[i]);
      figs[i].setAttribute('data-rendered', good ? 'yes' : 'no');
      if (good) { ok++; }
    }
    var el = document.getElementById('figure-check');
    el.setAttribute('data-ok', String(ok));
    el.setAttribute('data-total', String(figs.length));
    var clip = clippedText();
    el.setAttribute('data-clipped', String(clip.length));
    el.setAttribute('data-clipped-what', clip.slice(0, 8).join(' | '));
    el.className = ok === figs.length ? 'ok' : 'bad';
    // Readers see the check only when it fails: the page's figures are the report.
    el.textContent = ok === figs.length
      ? ''
      : (figs.length - ok) + ' of ' + figs.length + ' figures could not be drawn by this browser.';
  }
  if (document.readyState === 'complete') { check(); } else { window.addEventListener('load', check); }
})();
";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_rfc4648_vectors() {
        // RFC 4648 section 10.
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, enc) in cases {
            assert_eq!(base64(plain.as_bytes()), enc, "{plain:?}");
        }
        // All byte values: decode back with an independent table-free decoder.
        let all: Vec<u8> = (0..=255u8).collect();
        let enc = base64(&all);
        let val = |c: u8| -> u32 {
            match c {
                b'A'..=b'Z' => u32::from(c - b'A'),
                b'a'..=b'z' => u32::from(c - b'a') + 26,
                b'0'..=b'9' => u32::from(c - b'0') + 52,
                b'+' => 62,
                b'/' => 63,
                _ => panic!("bad char {c}"),
            }
        };
        let mut dec = Vec::new();
        for q in enc.as_bytes().chunks(4) {
            let n = q
                .iter()
                .take_while(|&&c| c != b'=')
                .fold((0u32, 0), |(n, k), &c| {
                    (n | (val(c) << (18 - 6 * k)), k + 1)
                });
            let bytes = [(n.0 >> 16) as u8, (n.0 >> 8) as u8, n.0 as u8];
            dec.extend_from_slice(&bytes[..n.1 - 1]);
        }
        assert_eq!(dec, all);
    }

    #[test]
    fn escape_covers_markup_characters() {
        assert_eq!(
            escape(r#"<b>"a" & 'b'</b>"#),
            "&lt;b&gt;&quot;a&quot; &amp; &#39;b&#39;&lt;/b&gt;"
        );
        assert_eq!(escape("q₂ (rad·s⁻¹)"), "q₂ (rad·s⁻¹)");
    }

    #[test]
    fn text_is_escaped_everywhere() {
        let mut r = Report::new("<script>alert(1)</script>");
        r.heading("a<b").paragraph("x & y").code("<pre>");
        r.table(Table {
            caption: "<i>".into(),
            header: vec!["<h>".into()],
            rows: vec![vec!["<c>".into()]],
        });
        r.figure("<cap>", Image::Png(b"\x89PNG\r\n\x1a\nrest".to_vec()));
        let html = r.to_html().unwrap();
        for raw in [
            "<script>alert",
            "a<b",
            "x & y",
            "<pre><pre>",
            "<i>",
            "<h>",
            "<c>",
            "<cap>",
        ] {
            assert!(!html.contains(raw), "unescaped {raw}");
        }
        assert_eq!(
            html.matches("<script").count(),
            1,
            "only the checker script"
        );
    }

    #[test]
    fn ragged_table_is_an_error() {
        let mut r = Report::new("t");
        r.table(Table {
            caption: "Table I".into(),
            header: vec!["a".into(), "b".into()],
            rows: vec![vec!["1".into(), "2".into()], vec!["3".into()]],
        });
        let e = r.to_html().unwrap_err();
        assert!(matches!(
            e,
            ReportError::RaggedTable {
                row: 1,
                len: 1,
                expected: 2,
                ..
            }
        ));
        assert!(e.to_string().contains("Table I"));
    }

    #[test]
    fn bad_images_are_errors() {
        let mut r = Report::new("t");
        r.figure("f", Image::Png(b"GIF89a".to_vec()));
        assert!(matches!(r.to_html(), Err(ReportError::BadPng { .. })));
        for bad in [
            "<div/>",
            "<svg><script>x()</script></svg>",
            "<svg></svg><img src=x>",
            "<svg><foreignObject/></svg>",
        ] {
            let mut r = Report::new("t");
            r.figure("f", Image::Svg(bad.into()));
            assert!(
                matches!(r.to_html(), Err(ReportError::BadSvg { .. })),
                "{bad}"
            );
        }
        assert_eq!(
            svg_element("<?xml version=\"1.0\"?>\n<!-- c -->\n<svg a=\"1\"></svg>\n"),
            Some("<svg a=\"1\"></svg>")
        );
    }

    #[test]
    fn structure_and_numeric_cells() {
        let mut r = Report::new("Run");
        r.table(Table {
            caption: "Errors".into(),
            header: vec!["controller".into(), "RMS (mrad)".into()],
            rows: vec![
                vec!["first".into(), "0.125".into()],
                vec!["usual".into(), "−3".into()],
            ],
        });
        r.figure(
            "A",
            Image::Svg("<svg width=\"1\" height=\"1\"></svg>".into()),
        );
        r.figure("B", Image::Png(b"\x89PNG\r\n\x1a\n".to_vec()));
        let html = r.to_html().unwrap();
        assert!(html.contains("data-total=\"2\""));
        assert!(html.contains("<td>first</td><td class=\"num\">0.125</td>"));
        assert!(html.contains("<td class=\"num\">−3</td>"));
        assert!(html.contains("id=\"figure-1\" data-kind=\"svg\""));
        assert!(html.contains("id=\"figure-2\" data-kind=\"png\""));
        assert!(html.contains("src=\"data:image/png;base64,iVBORw0KGgo=\""));
        // Nothing is loaded from elsewhere.
        for ext in ["src=\"http", "href=", "url(", "<link", "@import"] {
            assert!(!html.contains(ext), "{ext}");
        }
    }

    #[test]
    fn write_is_atomic_and_reports_path() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("report.html");
        Report::new("x").write(&p).unwrap();
        assert!(std::fs::read_to_string(&p)
            .unwrap()
            .starts_with("<!DOCTYPE html>"));
        let bad = tmp.path().join("missing/report.html");
        let e = Report::new("x").write(&bad).unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
    }
}
