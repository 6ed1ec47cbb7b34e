//! Figures: a grid of panels with line or marker series, rendered to PNG and SVG.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (`assets/fonts/`), registered with
//! plotters' `ab_glyph` backend before the first drawing; plotters is built without system font
//! support, so figures look the same on every machine, including one with no fonts at all.
//! (The SVG names the family `sans-serif` and is laid out with DejaVu metrics; a viewer draws its
//! own sans-serif font.)
//!
//! Data handling: points with a NaN or infinite coordinate (or one beyond ±[`HUGE`]) are
//! skipped and break a line into separate pieces (a diverged run ends its line instead of
//! drawing a spike); on a logarithmic axis points with y < [`TINY`] (so all y ≤ 0) are skipped
//! too. An axis range is never degenerate: no data gives [0, 1], constant data a band around
//! the value. Long lines with non-decreasing x are reduced to the
//! first, lowest, highest and last point of each pixel column (M4 reduction), which draws
//! the same pixels with far fewer points and keeps the SVG small. Markers that land on the same
//! pixel are drawn once.
//!
//! A panel may have equal scales on x and y ([`Panel::equal_aspect`]) or be a 3-D plot
//! ([`Panel::new_3d`], [`Axes3d`]): an orthographic view with z up and the same scale on all
//! three axes, drawn through plotters' 3-D coordinates with its own projection matrix, back
//! panes, ticks and axis descriptions. In PNG output wide lines are drawn segment by segment
//! (plotters fills a wide polyline as one polygon, which cancels where a path runs back over
//! itself); the SVG keeps one polyline per run.
//!
//! Colours come from a fixed colour-blind-safe palette (Okabe–Ito), indexed by
//! [`Series::color`]; the named indices [`COLOR_USUAL`], [`COLOR_FIRST`], [`COLOR_SECOND`] and
//! [`COLOR_REFERENCE`] keep each controller in the same colour in every figure.

use std::collections::HashSet;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::backend::RGBPixel;
use plotters::chart::SeriesAnno;
use plotters::coord::cartesian::Cartesian3d;
use plotters::coord::ranged1d::Ranged;
use plotters::coord::ranged3d::ProjectionMatrix;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle, FontTransform};

use super::atomic::write_atomic;

/// Font family name under which the embedded font is registered (plotters' default family).
pub const FONT_FAMILY: &str = "sans-serif";

/// DejaVu Sans 2.37 (license: `assets/fonts/LICENSE`).
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Default size of one panel in pixels (width, height).
pub const DEFAULT_PANEL_SIZE: (u32, u32) = (560, 340);

/// Smallest accepted panel size in pixels; below it axis labels overlap the plot.
pub const MIN_PANEL_SIZE: (u32, u32) = (200, 150);

/// Largest accepted canvas (width × height pixels): 40 megapixels, 120 MB of RGB buffer.
pub const MAX_CANVAS_PIXELS: u64 = 40_000_000;

/// Height of the figure title band in pixels (0 when the title is empty).
const TITLE_HEIGHT: u32 = 44;

/// The palette: Okabe & Ito, "Color Universal Design" (2008), distinguishable with the common
/// colour-vision deficiencies. Index with [`color`].
pub const PALETTE: [RGBColor; 11] = [
    RGBColor(0, 0, 0),       // black
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 114, 178),   // blue
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(240, 228, 66),  // yellow
    // Beyond Okabe & Ito, from Paul Tol's "muted" scheme (for more controller kinds):
    RGBColor(136, 34, 85),  // wine
    RGBColor(51, 34, 136),  // indigo
    RGBColor(153, 153, 51), // olive
];

/// Palette index of reference signals (black).
pub const COLOR_REFERENCE: usize = 0;
/// Palette index of the usual (positional) predictive controller, Eq. (43) (vermillion).
pub const COLOR_USUAL: usize = 1;
/// Palette index of the first incremental predictive algorithm (blue).
pub const COLOR_FIRST: usize = 2;
/// Palette index of the second incremental predictive algorithm (bluish green).
pub const COLOR_SECOND: usize = 3;

/// Palette index of a controller by name: a distinct colour for every kind, the baselines
/// (`pid`, `ctc`, `ctc-adaptive`, `dob-mpc`) included; an adaptive variant is far from its base
/// (reddish purple and indigo against blue and green).
pub fn controller_color(name: &str) -> usize {
    match name {
        "usual" => COLOR_USUAL,
        "first" => COLOR_FIRST,
        "second" => COLOR_SECOND,
        "first-adaptive" => 6,
        "second-adaptive" => 9,
        "pid" => 4,
        "ctc" => 5,
        "ctc-adaptive" => 8,
        "dob-mpc" => 10,
        _ => COLOR_REFERENCE,
    }
}

/// The palette colour for index `i` (wraps around after [`PALETTE`]`.len()`).
pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Solid line; NaN/inf points break it. An isolated finite point is drawn as a dot.
    Line,
    /// Dashed line (e.g. a reference signal).
    Dashed,
    /// One filled circle per point, no line (e.g. the samples of a diverged run).
    Markers,
}

/// One data series of a panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text; an empty label gives no legend entry.
    pub label: String,
    /// Abscissae (same length as `y`).
    pub x: Vec<f64>,
    /// Ordinates (same length as `x`).
    pub y: Vec<f64>,
    /// Line, dashed line or markers.
    pub style: SeriesStyle,
    /// Palette index, see [`color`] and the `COLOR_*` constants.
    pub color: usize,
}

impl Series {
    /// A solid line.
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: usize) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            style: SeriesStyle::Line,
            color,
        }
    }

    /// A dashed line.
    pub fn dashed(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: usize) -> Self {
        Self {
            style: SeriesStyle::Dashed,
            ..Self::line(label, x, y, color)
        }
    }

    /// Markers only.
    pub fn markers(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: usize) -> Self {
        Self {
            style: SeriesStyle::Markers,
            ..Self::line(label, x, y, color)
        }
    }
}

/// One plot (axes, series, legend) in the figure grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Title above the plot (may be empty).
    pub title: String,
    /// X axis label with unit, e.g. `"t (s)"`.
    pub x_label: String,
    /// Y axis label with unit, e.g. `"e₂ (rad)"`.
    pub y_label: String,
    /// Series drawn in order (later ones on top).
    pub series: Vec<Series>,
    /// Logarithmic y axis (points with y ≤ 0 are skipped).
    pub log_y: bool,
    /// Equal scales on x and y: one data unit has the same length in pixels on both axes (a
    /// circle is drawn round). The data range of the tighter axis is widened about its centre;
    /// both keep a 5 % margin so that nothing touches the frame. Ignored with `log_y`.
    pub equal_aspect: bool,
    /// 3-D content. When set, the panel is a 3-D plot of [`Axes3d::series`] with axes
    /// `x_label`, `y_label` and [`Axes3d::z_label`]; `series` must then be empty and `log_y`
    /// false (see [`validate`]).
    pub three_d: Option<Axes3d>,
}

impl Panel {
    /// An empty linear panel.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            log_y: false,
            equal_aspect: false,
            three_d: None,
        }
    }

    /// An empty 3-D panel with the default [`View3d`]; add series to
    /// [`Panel::series_3d`].
    pub fn new_3d(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        z_label: impl Into<String>,
    ) -> Self {
        Self {
            three_d: Some(Axes3d {
                z_label: z_label.into(),
                series: Vec::new(),
                view: View3d::default(),
            }),
            ..Self::new(title, x_label, y_label)
        }
    }

    /// The 3-D series of this panel, making it a 3-D panel (with an empty z label and the
    /// default view) if it was not one.
    pub fn series_3d(&mut self) -> &mut Vec<Series3d> {
        &mut self.three_d.get_or_insert_with(Axes3d::default).series
    }
}

/// One data series of a 3-D panel. Points with a NaN, infinite or huge (beyond ±[`HUGE`])
/// coordinate are skipped and break a line.
#[derive(Debug, Clone, PartialEq)]
pub struct Series3d {
    /// Legend text; an empty label gives no legend entry.
    pub label: String,
    /// x coordinates (same length as `y` and `z`).
    pub x: Vec<f64>,
    /// y coordinates.
    pub y: Vec<f64>,
    /// z coordinates (drawn vertical).
    pub z: Vec<f64>,
    /// Line, dashed line or markers.
    pub style: SeriesStyle,
    /// Palette index, see [`color`] and the `COLOR_*` constants.
    pub color: usize,
}

impl Series3d {
    /// A solid line.
    pub fn line(
        label: impl Into<String>,
        x: Vec<f64>,
        y: Vec<f64>,
        z: Vec<f64>,
        color: usize,
    ) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            z,
            style: SeriesStyle::Line,
            color,
        }
    }

    /// A dashed line.
    pub fn dashed(
        label: impl Into<String>,
        x: Vec<f64>,
        y: Vec<f64>,
        z: Vec<f64>,
        color: usize,
    ) -> Self {
        Self {
            style: SeriesStyle::Dashed,
            ..Self::line(label, x, y, z, color)
        }
    }

    /// Markers only.
    pub fn markers(
        label: impl Into<String>,
        x: Vec<f64>,
        y: Vec<f64>,
        z: Vec<f64>,
        color: usize,
    ) -> Self {
        Self {
            style: SeriesStyle::Markers,
            ..Self::line(label, x, y, z, color)
        }
    }
}

/// The direction a 3-D panel is seen from. The z axis is drawn vertical (pointing up) and the
/// projection is orthographic and keeps handedness: a right-handed frame (such as a robot's base
/// frame) looks right-handed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View3d {
    /// Azimuth of the viewer in degrees, about +z from the +x axis towards +y.
    pub yaw_deg: f64,
    /// Elevation of the viewer above the xy plane in degrees (positive: looking down).
    pub pitch_deg: f64,
}

impl Default for View3d {
    /// Azimuth −60°, elevation 30° (the usual default of engineering plot tools): x runs to the
    /// right and towards the viewer, y to the right and away, z up.
    fn default() -> Self {
        Self {
            yaw_deg: -60.0,
            pitch_deg: 30.0,
        }
    }
}

/// The 3-D part of a [`Panel`]: all three axes have the same scale (a sphere looks round).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Axes3d {
    /// Z axis label with unit, e.g. `"z (mm)"` (x and y use the panel's labels).
    pub z_label: String,
    /// Series drawn in order (later ones on top).
    pub series: Vec<Series3d>,
    /// Viewing direction.
    pub view: View3d,
}

/// A titled grid of panels, filled row by row.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Title across the top (may be empty).
    pub title: String,
    /// Panels in reading order.
    pub panels: Vec<Panel>,
    /// Panels per row (≥ 1; more columns than panels is reduced to the number of panels).
    pub columns: usize,
    /// Size of one panel in pixels (width, height); at least [`MIN_PANEL_SIZE`].
    pub panel_size: (u32, u32),
}

impl Figure {
    /// An empty figure with [`DEFAULT_PANEL_SIZE`] panels.
    pub fn new(title: impl Into<String>, columns: usize) -> Self {
        Self {
            title: title.into(),
            panels: Vec::new(),
            columns,
            panel_size: DEFAULT_PANEL_SIZE,
        }
    }

    /// Grid shape (rows, columns) actually used.
    pub fn grid(&self) -> (usize, usize) {
        let cols = self.columns.clamp(1, self.panels.len().max(1));
        (self.panels.len().div_ceil(cols), cols)
    }

    /// Canvas size in pixels (width, height).
    pub fn canvas_size(&self) -> (u32, u32) {
        let (rows, cols) = self.grid();
        let title = if self.title.is_empty() {
            0
        } else {
            TITLE_HEIGHT
        };
        let w = (cols as u64 * u64::from(self.panel_size.0)).min(u64::from(u32::MAX)) as u32;
        let h = (rows as u64 * u64::from(self.panel_size.1) + u64::from(title))
            .min(u64::from(u32::MAX)) as u32;
        (w, h)
    }
}

/// Why a figure could not be rendered or written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The figure has no panels.
    #[error("figure {figure:?} has no panels; add at least one Panel")]
    NoPanels {
        /// Figure title.
        figure: String,
    },
    /// `columns` is 0.
    #[error("figure {figure:?}: columns is 0; use at least 1 panel per row")]
    ZeroColumns {
        /// Figure title.
        figure: String,
    },
    /// Panel or canvas size out of bounds.
    #[error(
        "figure {figure:?}: panel size {width}x{height} px gives an unusable canvas; \
         panels must be at least {}x{} px and the whole figure at most {} megapixels",
        MIN_PANEL_SIZE.0, MIN_PANEL_SIZE.1, MAX_CANVAS_PIXELS / 1_000_000
    )]
    BadSize {
        /// Figure title.
        figure: String,
        /// Requested panel width.
        width: u32,
        /// Requested panel height.
        height: u32,
    },
    /// A series has different numbers of x and y values.
    #[error(
        "figure {figure:?}, panel {panel:?}, series {series:?}: x has {x_len} values but y has \
         {y_len}; give exactly one y value per x value"
    )]
    LengthMismatch {
        /// Figure title.
        figure: String,
        /// Panel title.
        panel: String,
        /// Series label.
        series: String,
        /// Length of `x`.
        x_len: usize,
        /// Length of `y`.
        y_len: usize,
    },
    /// A 3-D series has different numbers of x, y and z values.
    #[error(
        "figure {figure:?}, panel {panel:?}, 3-D series {series:?}: x, y and z have {x_len}, \
         {y_len} and {z_len} values; give exactly one point (x, y, z) per index"
    )]
    LengthMismatch3d {
        /// Figure title.
        figure: String,
        /// Panel title.
        panel: String,
        /// Series label.
        series: String,
        /// Length of `x`.
        x_len: usize,
        /// Length of `y`.
        y_len: usize,
        /// Length of `z`.
        z_len: usize,
    },
    /// A 3-D panel also has 2-D series or a logarithmic axis.
    #[error(
        "figure {figure:?}, panel {panel:?} is a 3-D panel but also has 2-D series or log_y set; \
         put 2-D series in a panel of their own"
    )]
    Mixed3d {
        /// Figure title.
        figure: String,
        /// Panel title.
        panel: String,
    },
    /// A 3-D view angle is NaN or infinite.
    #[error(
        "figure {figure:?}, panel {panel:?}: view yaw {yaw_deg}° / pitch {pitch_deg}° is not \
         finite; use finite angles in degrees (e.g. View3d::default())"
    )]
    BadView {
        /// Figure title.
        figure: String,
        /// Panel title.
        panel: String,
        /// The yaw given.
        yaw_deg: f64,
        /// The pitch given.
        pitch_deg: f64,
    },
    /// The embedded font could not be registered (a corrupt build).
    #[error(
        "the embedded DejaVu Sans font could not be loaded; the binary is damaged, rebuild it"
    )]
    Font,
    /// plotters reported a drawing error.
    #[error("drawing figure {figure:?} failed: {message}")]
    Draw {
        /// Figure title.
        figure: String,
        /// plotters' message.
        message: String,
    },
    /// PNG encoding failed.
    #[error("encoding figure {figure:?} as PNG failed: {message}")]
    Png {
        /// Figure title.
        figure: String,
        /// Encoder message.
        message: String,
    },
    /// Writing an output file failed.
    #[error("writing figure to {}: {source}", path.display())]
    Io {
        /// The file that could not be written.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
}

/// A figure rendered in memory in both formats.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// PNG file contents (8-bit RGB).
    pub png: Vec<u8>,
    /// SVG document.
    pub svg: String,
    /// Canvas size in pixels (width, height).
    pub size: (u32, u32),
}

/// Registers the embedded font with plotters exactly once per process.
pub fn ensure_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| register_font(FONT_FAMILY, FontStyle::Normal, FONT_BYTES).is_ok());
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

/// Checks the figure before any drawing.
pub fn validate(fig: &Figure) -> Result<(), PlotError> {
    if fig.panels.is_empty() {
        return Err(PlotError::NoPanels {
            figure: fig.title.clone(),
        });
    }
    if fig.columns == 0 {
        return Err(PlotError::ZeroColumns {
            figure: fig.title.clone(),
        });
    }
    let (w, h) = fig.canvas_size();
    if fig.panel_size.0 < MIN_PANEL_SIZE.0
        || fig.panel_size.1 < MIN_PANEL_SIZE.1
        || u64::from(w) * u64::from(h) > MAX_CANVAS_PIXELS
    {
        return Err(PlotError::BadSize {
            figure: fig.title.clone(),
            width: fig.panel_size.0,
            height: fig.panel_size.1,
        });
    }
    for p in &fig.panels {
        validate_panel(fig, p)?;
    }
    Ok(())
}

/// One panel of [`validate`]: a 3-D panel holds no 2-D series and no log axis and has a
/// finite view, and every series has as many values per coordinate.
fn validate_panel(fig: &Figure, p: &Panel) -> Result<(), PlotError> {
    if let Some(a) = &p.three_d {
        if !p.series.is_empty() || p.log_y {
            return Err(PlotError::Mixed3d {
                figure: fig.title.clone(),
                panel: p.title.clone(),
            });
        }
        if !(a.view.yaw_deg.is_finite() && a.view.pitch_deg.is_finite()) {
            return Err(PlotError::BadView {
                figure: fig.title.clone(),
                panel: p.title.clone(),
                yaw_deg: a.view.yaw_deg,
                pitch_deg: a.view.pitch_deg,
            });
        }
        for s in &a.series {
            if s.x.len() != s.y.len() || s.x.len() != s.z.len() {
                return Err(PlotError::LengthMismatch3d {
                    figure: fig.title.clone(),
                    panel: p.title.clone(),
                    series: s.label.clone(),
                    x_len: s.x.len(),
                    y_len: s.y.len(),
                    z_len: s.z.len(),
                });
            }
        }
    }
    for s in &p.series {
        if s.x.len() != s.y.len() {
            return Err(PlotError::LengthMismatch {
                figure: fig.title.clone(),
                panel: p.title.clone(),
                series: s.label.clone(),
                x_len: s.x.len(),
                y_len: s.y.len(),
            });
        }
    }
    Ok(())
}

/// Renders `fig` to PNG bytes.
pub fn render_png(fig: &Figure) -> Result<Vec<u8>, PlotError> {
    validate(fig)?;
    ensure_font()?;
    let (w, h) = fig.canvas_size();
    let mut buf = vec![255u8; w as usize * h as usize * 3];
    {
        let backend = BitMapBackend::<RGBPixel>::with_buffer_and_format(&mut buf, (w, h))
            .map_err(|e| draw_error(fig, e))?;
        let root = backend.into_drawing_area();
        draw_figure(&root, fig, LineMode::Segments)?;
        root.present().map_err(|e| draw_error(fig, e))?;
    }
    encode_png(&buf, w, h).map_err(|e| PlotError::Png {
        figure: fig.title.clone(),
        message: e.to_string(),
    })
}

/// Renders `fig` to an SVG document.
pub fn render_svg(fig: &Figure) -> Result<String, PlotError> {
    validate(fig)?;
    ensure_font()?;
    let size = fig.canvas_size();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_figure(&root, fig, LineMode::Polylines)?;
        root.present().map_err(|e| draw_error(fig, e))?;
    }
    Ok(svg)
}

/// Renders `fig` in both formats (in memory).
pub fn render_both(fig: &Figure) -> Result<Rendered, PlotError> {
    Ok(Rendered {
        png: render_png(fig)?,
        svg: render_svg(fig)?,
        size: fig.canvas_size(),
    })
}

/// Renders `fig` and writes `png_path` and `svg_path`, each atomically (see
/// [`super::atomic::write_atomic`]): nothing is written unless both renderings succeeded, and
/// no file is ever left half-written.
pub fn render(fig: &Figure, png_path: &Path, svg_path: &Path) -> Result<Rendered, PlotError> {
    let r = render_both(fig)?;
    write_atomic(png_path, &r.png).map_err(|source| PlotError::Io {
        path: png_path.to_path_buf(),
        source,
    })?;
    write_atomic(svg_path, r.svg.as_bytes()).map_err(|source| PlotError::Io {
        path: svg_path.to_path_buf(),
        source,
    })?;
    Ok(r)
}

/// Encodes an 8-bit RGB buffer (row-major, `w·h·3` bytes) as PNG.
pub fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, png::EncodingError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Best);
        let mut writer = enc.write_header()?;
        writer.write_image_data(rgb)?;
        writer.finish()?;
    }
    Ok(out)
}

fn draw_error(fig: &Figure, e: impl std::fmt::Display) -> PlotError {
    PlotError::Draw {
        figure: fig.title.clone(),
        message: e.to_string(),
    }
}

/// How lines wider than one pixel are handed to the backend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LineMode {
    /// One polyline per run (SVG: the viewer strokes it correctly and the file stays small).
    Polylines,
    /// One element per segment (bitmap). plotters fills a wide polyline as a single polygon,
    /// so where a path runs back over itself (a path retraced, a reversal) the overlapping parts
    /// cancel and leave a gap or two thin edges instead of the line; single segments cannot
    /// overlap themselves.
    Segments,
}

/// Draws title and panel grid.
fn draw_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    mode: LineMode,
) -> Result<(), PlotError> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| draw_error(fig, e);
    root.fill(&WHITE).map_err(err)?;
    let body = if fig.title.is_empty() {
        root.clone()
    } else {
        let (top, body) = root.split_vertically(TITLE_HEIGHT);
        let (w, h) = top.dim_in_pixel();
        let fit = fit_text(
            &|t, size| text_width(&top, t, size),
            &fig.title,
            fit_width(w),
            &FIGURE_TITLE_SIZES,
        );
        let n = fit.lines.len() as i32;
        let line_h = (fit.size * 1.15).round() as i32;
        for (i, line) in fit.lines.iter().enumerate() {
            let style = TextStyle::from((FONT_FAMILY, fit.size).into_font())
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center));
            let y = h as i32 / 2 + (2 * i as i32 - (n - 1)) * line_h / 2;
            top.draw(&Text::new(line.as_str(), (w as i32 / 2, y), style))
                .map_err(err)?;
        }
        body
    };
    let (rows, cols) = fig.grid();
    let cells = body.split_evenly((rows, cols));
    for (panel, cell) in fig.panels.iter().zip(cells.iter()) {
        draw_panel(cell, panel, fig, mode)?;
    }
    Ok(())
}

/// A series reduced to drawable pieces.
struct Prepared<'a> {
    series: &'a Series,
    /// Runs of consecutive valid points (a line is drawn through each run).
    runs: Vec<Vec<(f64, f64)>>,
}

/// Magnitudes above this are treated like infinity (skipped): plotters' tick computation
/// overflows on spans near `f64::MAX`, and such values only occur in diverged runs.
pub const HUGE: f64 = 1e250;

/// Spans below this are treated as zero: ticks this fine would need subnormal numbers.
pub const TINY: f64 = 1e-250;

/// Range of y values shown on a logarithmic axis (others are skipped). plotters' log ticks
/// need the axis end ratio to stay finite, so the axis may cover at most ~300 decades.
pub const LOG_LIMITS: (f64, f64) = (1e-150, 1e150);

/// Whether (x, y) can be drawn on this panel.
fn valid(x: f64, y: f64, log_y: bool) -> bool {
    x.abs() <= HUGE && y.abs() <= HUGE && (!log_y || (LOG_LIMITS.0..=LOG_LIMITS.1).contains(&y))
}

/// Splits a series into runs of valid points.
fn split_runs(s: &Series, log_y: bool) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    for (&x, &y) in s.x.iter().zip(&s.y) {
        if valid(x, y, log_y) {
            cur.push((x, y));
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

/// Finite (min, max) of the values, or `None` if there are none.
fn min_max(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values.fold(None, |acc, v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })
}

/// A non-degenerate linear axis range containing `data` (values within ±[`HUGE`]), padded by
/// `pad` (≤ 1) of the span on each side. An empty range gives [0, 1]; a (nearly) constant one
/// is widened to ±10 % of the value (±1 around 0, at least ±[`TINY`]). Spans below 1e-9 of the
/// magnitude count as constant: plotting them would only show floating-point noise.
pub fn linear_range(data: Option<(f64, f64)>, pad: f64) -> (f64, f64) {
    let Some((lo, hi)) = data else {
        return (0.0, 1.0);
    };
    let mag = lo.abs().max(hi.abs());
    let span = hi - lo;
    if span <= 1e-9 * mag || span < TINY {
        let mid = 0.5 * lo + 0.5 * hi;
        let half = if mid == 0.0 {
            1.0
        } else {
            (0.1 * mid.abs()).max(TINY)
        };
        return (mid - half, mid + half);
    }
    (lo - pad * span, hi + pad * span)
}

/// A non-degenerate logarithmic range containing `data` (within [`LOG_LIMITS`]), padded by 5 %
/// of its width in decades on each side (at most 2 decades); a constant value v gives
/// [v/2, 2v], no data [1, 10].
pub fn log_range(data: Option<(f64, f64)>) -> (f64, f64) {
    let Some((lo, hi)) = data else {
        return (1.0, 10.0);
    };
    if hi <= lo * (1.0 + 1e-9) {
        return (lo / 2.0, hi * 2.0);
    }
    // 5 % of the decades, computed in logarithms so that hi / lo cannot overflow.
    let f = 10f64.powf((0.05 * (hi.log10() - lo.log10())).min(2.0));
    (lo / f, hi * f)
}

/// Shared precision for the tick labels of one linear axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TickFormat {
    /// Power of ten by which the axis values were divided (0 = plain decimal notation); shown
    /// as an `e<exponent>` suffix on every label.
    pub exponent: i32,
    /// Digits after the decimal point of the mantissa.
    pub decimals: usize,
}

impl TickFormat {
    /// Chooses one format for all `ticks` (the axis key points, already divided by
    /// 10^`exponent`): the fewest decimals that print every tick distinctly and within 1 ‰ of
    /// the tick step.
    pub fn for_ticks(ticks: &[f64], exponent: i32) -> Self {
        let mut sorted: Vec<f64> = ticks.iter().copied().filter(|v| v.is_finite()).collect();
        sorted.sort_by(f64::total_cmp);
        let mag = sorted.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let step = sorted
            .windows(2)
            .map(|w| w[1] - w[0])
            .filter(|d| *d > 0.0)
            .fold(f64::INFINITY, f64::min);
        // A single tick has no step; any precision that shows it exactly to 3 digits will do.
        let step = if step.is_finite() {
            step
        } else {
            mag.max(1.0) * 1e-3
        };
        let base = (-(step.log10() + 1e-9).floor()).max(0.0) as usize;
        for decimals in base..base + 4 {
            let f = Self { exponent, decimals };
            let texts: Vec<String> = sorted.iter().map(|&v| f.format(v)).collect();
            let distinct = texts.windows(2).all(|w| w[0] != w[1]);
            let accurate = sorted.iter().all(|&v| {
                let m: f64 = format!("{v:.decimals$}").parse().unwrap_or(f64::NAN);
                (m - v).abs() <= 1e-3 * step
            });
            if distinct && accurate {
                return f;
            }
        }
        Self {
            exponent,
            decimals: base + 4,
        }
    }

    /// Formats one (divided) value: mantissa with the chosen decimals and the `e` suffix;
    /// zero is always `"0"`, never `"-0.00"` or `"0e-4"`.
    pub fn format(&self, v: f64) -> String {
        let m = format!("{:.*}", self.decimals, v);
        if m.parse::<f64>().map(|p| p == 0.0).unwrap_or(false) {
            return "0".to_string();
        }
        if self.exponent == 0 {
            m
        } else {
            format!("{m}e{}", self.exponent)
        }
    }
}

/// The power of ten an axis with largest magnitude `mag` is divided by: 0 for magnitudes in
/// [0.01, 1e5) (and 0), else ⌊log10 mag⌋. Besides short labels this keeps the values handed to
/// plotters near 1: its tick computation uses absolute tolerances (f64::EPSILON) and produces
/// wrong ticks for spans below about 1e-14.
pub fn axis_exponent(mag: f64) -> i32 {
    if mag == 0.0 || !mag.is_finite() || (1e-2..1e5).contains(&mag) {
        0
    } else {
        mag.log10().floor() as i32
    }
}

/// A linear axis ready for plotters: values are divided by 10^`exponent`, `range` is in those
/// units, `format` labels them.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearAxis {
    /// Power of ten the data is divided by.
    pub exponent: i32,
    /// Axis range in divided units (never degenerate, see [`linear_range`]).
    pub range: (f64, f64),
    /// Tick label format.
    pub format: TickFormat,
    /// Number of labels to request from plotters (`x_labels`/`y_labels`): the requested count,
    /// raised where plotters would otherwise place fewer than two ticks.
    pub labels: usize,
}

impl LinearAxis {
    /// Axis for data spanning `data` (raw units), padded by `pad` of the span, with about
    /// `labels` tick labels.
    pub fn new(data: Option<(f64, f64)>, pad: f64, labels: usize) -> Self {
        let exponent = axis_exponent(data.map_or(0.0, |(lo, hi)| lo.abs().max(hi.abs())));
        let s = 10f64.powi(-exponent);
        let range = linear_range(data.map(|(lo, hi)| (lo * s, hi * s)), pad);
        let coord = RangedCoordf64::from(range.0..range.1);
        let (labels, ticks) = (labels.max(2)..labels.max(2) + 12)
            .map(|n| (n, coord.key_points(n)))
            .find(|(_, t)| t.len() >= 2)
            .unwrap_or_else(|| (labels, coord.key_points(labels)));
        Self {
            exponent,
            range,
            format: TickFormat::for_ticks(&ticks, exponent),
            labels,
        }
    }

    /// Factor from raw to axis units (10^-exponent).
    pub fn scale(&self) -> f64 {
        10f64.powi(-self.exponent)
    }
}

/// A compact label for one value with ≤ 3 significant digits (used on logarithmic axes):
/// `"0.02"`, `"150"`, `"1e-6"`, `"2.5e7"`.
pub fn format_general(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 {
            "0".to_string()
        } else {
            v.to_string()
        };
    }
    let e = v.abs().log10().floor() as i32;
    let trim = |s: String| -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    if (-3..5).contains(&e) {
        let decimals = (2 - e).max(0) as usize;
        trim(format!("{:.*}", decimals, v))
    } else {
        let mut m = v / 10f64.powi(e);
        let mut e = e;
        // Rounding 9.996 to two decimals gives 10.00: renormalize.
        if (m.abs() * 100.0).round() >= 1000.0 {
            m /= 10.0;
            e += 1;
        }
        format!("{}e{}", trim(format!("{:.2}", m)), e)
    }
}

/// Indices kept by M4 reduction: within each run of consecutive points with the same pixel
/// column, the first, the lowest, the highest and the last point, in their original order.
/// `columns` must be non-decreasing; `columns.len() == ys.len()`.
pub fn m4_indices(columns: &[i32], ys: &[f64]) -> Vec<usize> {
    let n = columns.len().min(ys.len());
    let mut keep = Vec::new();
    let mut start = 0;
    while start < n {
        let mut end = start;
        let (mut imin, mut imax) = (start, start);
        while end < n && columns[end] == columns[start] {
            if ys[end] < ys[imin] {
                imin = end;
            }
            if ys[end] > ys[imax] {
                imax = end;
            }
            end += 1;
        }
        let mut group = [start, imin, imax, end - 1];
        group.sort_unstable();
        for (k, &i) in group.iter().enumerate() {
            if k == 0 || group[k - 1] != i {
                keep.push(i);
            }
        }
        start = end;
    }
    keep
}

/// Pixel width estimate of the widest tick label, for the y label area.
fn label_width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, labels: &[String]) -> u32 {
    let font = TextStyle::from((FONT_FAMILY, 12).into_font());
    labels
        .iter()
        .map(|l| {
            area.estimate_text_size(l, &font)
                .map(|(w, _)| w)
                .unwrap_or(0)
        })
        .max()
        .unwrap_or(0)
}

/// Font sizes tried for a figure title, one line each, largest first; then [`TWO_LINE_SIZES`].
const FIGURE_TITLE_SIZES: [TitleSize; 9] = [
    TitleSize::One(22.0),
    TitleSize::One(21.0),
    TitleSize::One(20.0),
    TitleSize::One(19.0),
    TitleSize::One(18.0),
    TitleSize::Two(18.0),
    TitleSize::Two(16.0),
    TitleSize::Two(14.0),
    TitleSize::Two(12.0),
];

/// Font sizes tried for a panel title (one line), largest first.
const PANEL_TITLE_SIZES: [TitleSize; 6] = [
    TitleSize::One(16.0),
    TitleSize::One(15.0),
    TitleSize::One(14.0),
    TitleSize::One(13.0),
    TitleSize::One(12.0),
    TitleSize::One(11.0),
];

/// A candidate layout of a title: one line or two lines at a font size (px).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TitleSize {
    /// One line at this size.
    One(f64),
    /// Up to two lines (broken at a space) at this size.
    Two(f64),
}

/// A title laid out to fit a width.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedText {
    /// Font size (px).
    pub size: f64,
    /// One or two lines; the text is shortened with "…" only if no candidate fits.
    pub lines: Vec<String>,
}

/// The width (px) available for a title in an area `w` px wide: 16 px margin on each side, and
/// 4 % less for fonts that render a little wider than the embedded one (SVG in a browser).
fn fit_width(w: u32) -> u32 {
    (f64::from(w.saturating_sub(32)) * 0.96) as u32
}

/// Width in pixels of `text` in the embedded font at `size` px.
fn text_width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, text: &str, size: f64) -> u32 {
    area.estimate_text_size(text, &TextStyle::from((FONT_FAMILY, size).into_font()))
        .map(|(w, _)| w)
        .unwrap_or(u32::MAX)
}

/// The layout rule that keeps titles inside their area: the first candidate of `sizes` whose
/// lines (`measure(text, size)` px wide) all fit in `max_w`; a two-line candidate breaks at the
/// space that makes the longer line shortest. If none fits, the last candidate's size is used
/// and the text shortened with "…" (never clipped).
pub fn fit_text(
    measure: &dyn Fn(&str, f64) -> u32,
    text: &str,
    max_w: u32,
    sizes: &[TitleSize],
) -> FittedText {
    for cand in sizes {
        match *cand {
            TitleSize::One(size) => {
                if measure(text, size) <= max_w {
                    return FittedText {
                        size,
                        lines: vec![text.to_string()],
                    };
                }
            }
            TitleSize::Two(size) => {
                let best = text
                    .match_indices(' ')
                    .map(|(i, _)| (text[..i].trim_end(), text[i + 1..].trim_start()))
                    .map(|(a, b)| (measure(a, size).max(measure(b, size)), a, b))
                    .min_by_key(|(w, _, _)| *w);
                if let Some((w, a, b)) = best {
                    if w <= max_w {
                        return FittedText {
                            size,
                            lines: vec![a.to_string(), b.to_string()],
                        };
                    }
                }
            }
        }
    }
    let size = match sizes.last() {
        Some(TitleSize::One(s) | TitleSize::Two(s)) => *s,
        None => 12.0,
    };
    let chars: Vec<char> = text.chars().collect();
    let mut n = chars.len();
    while n > 0 {
        let t: String = chars[..n].iter().collect::<String>() + "…";
        if measure(&t, size) <= max_w {
            return FittedText {
                size,
                lines: vec![t],
            };
        }
        n -= 1;
    }
    FittedText {
        size,
        lines: vec![String::new()],
    }
}

/// Height of one row of the legend strip above a 2-D plot (px).
const LEGEND_ROW: u32 = 17;

/// Width of a legend entry's sample (line, dashes or marker) and the gap after it (px).
const LEGEND_SAMPLE: u32 = 26;

/// Space between two legend entries on a row (px).
const LEGEND_GAP: u32 = 16;

/// The layout rule that keeps legends off the data: a 2-D panel's legend is a strip of rows
/// above its plot area, entries placed left to right and wrapped to the next row when a row is
/// full, each row centred. Returns each entry's (row, x offset) and the number of rows, for
/// entries `widths` px wide in a strip `width` px wide.
pub fn legend_rows(widths: &[u32], width: u32) -> (Vec<(u32, u32)>, u32) {
    let mut rows: Vec<Vec<(usize, u32)>> = Vec::new();
    let mut x = 0;
    for (i, &w) in widths.iter().enumerate() {
        if rows.is_empty() || (x > 0 && x + w > width) {
            rows.push(Vec::new());
            x = 0;
        }
        if let Some(row) = rows.last_mut() {
            row.push((i, x));
        }
        x += w + LEGEND_GAP;
    }
    let mut pos = vec![(0, 0); widths.len()];
    for (r, row) in rows.iter().enumerate() {
        let used = row.last().map_or(0, |&(i, x)| x + widths[i]);
        let left = width.saturating_sub(used) / 2;
        for &(i, x) in row {
            pos[i] = (r as u32, left + x);
        }
    }
    (pos, rows.len() as u32)
}

/// Draws the legend strip of a 2-D panel (entries of labelled series; a series without a
/// drawable point gets "(no data)") at the top of `area`; returns the area left for the plot.
fn legend_strip<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, SeriesStyle, RGBColor)],
    fig: &Figure,
) -> Result<DrawingArea<DB, Shift>, PlotError> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| draw_error(fig, e);
    if entries.is_empty() {
        return Ok(area.clone());
    }
    let (w, _) = area.dim_in_pixel();
    let max_text = w.saturating_sub(LEGEND_SAMPLE + 8);
    let texts: Vec<String> = entries
        .iter()
        .map(|(label, _, _)| {
            fit_text(
                &|t, size| text_width(area, t, size),
                label,
                max_text,
                &[TitleSize::One(12.0)],
            )
            .lines
            .join(" ")
        })
        .collect();
    let widths: Vec<u32> = texts
        .iter()
        .map(|t| LEGEND_SAMPLE + text_width(area, t, 12.0))
        .collect();
    let (pos, rows) = legend_rows(&widths, w);
    let (strip, rest) = area.split_vertically(rows * LEGEND_ROW + 4);
    for ((text, &(row, x)), (_, style, c)) in texts.iter().zip(&pos).zip(entries) {
        let (x, y) = (x as i32, (row * LEGEND_ROW + LEGEND_ROW / 2 + 2) as i32);
        let line = c.stroke_width(2);
        match style {
            SeriesStyle::Markers => strip.draw(&Circle::new((x + 10, y), 3, c.filled())),
            SeriesStyle::Line => strip.draw(&PathElement::new(vec![(x, y), (x + 20, y)], line)),
            SeriesStyle::Dashed => strip
                .draw(&PathElement::new(vec![(x, y), (x + 8, y)], line))
                .and_then(|_| strip.draw(&PathElement::new(vec![(x + 12, y), (x + 20, y)], line))),
        }
        .map_err(err)?;
        let font = TextStyle::from((FONT_FAMILY, 12).into_font())
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        strip
            .draw(&Text::new(
                text.as_str(),
                (x + LEGEND_SAMPLE as i32, y),
                font,
            ))
            .map_err(err)?;
    }
    Ok(rest)
}

/// Draws one panel: margins and caption, then a 2-D or 3-D chart.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    fig: &Figure,
    mode: LineMode,
) -> Result<(), PlotError> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| draw_error(fig, e);
    // The margins and caption plotters' ChartBuilder would add, drawn once here so that the chart
    // below can be built (and measured) more than once.
    let inner = area.margin(10, 10, 10, 18);
    let inner = if panel.title.is_empty() {
        inner
    } else {
        let fit = fit_text(
            &|t, size| text_width(&inner, t, size),
            &panel.title,
            fit_width(inner.dim_in_pixel().0),
            &PANEL_TITLE_SIZES,
        );
        inner
            .titled(fit.lines.join(" ").as_str(), (FONT_FAMILY, fit.size))
            .map_err(err)?
    };
    match &panel.three_d {
        Some(axes) => draw_panel_3d(&inner, panel, axes, fig, mode),
        None => draw_panel_2d(&inner, panel, fig, mode),
    }
}

/// Number of tick labels requested on each 2-D axis.
const N_LABELS: usize = 6;

/// Height of the x label area of a 2-D chart (tick labels and axis description).
const X_LABEL_AREA: u32 = 44;

/// Width of the y label area for the tick labels of `axis` (widest label + 40 px for the
/// rotated axis description).
fn y_label_area<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, axis: &LinearAxis) -> u32 {
    let keys = RangedCoordf64::from(axis.range.0..axis.range.1).key_points(axis.labels);
    let labels: Vec<String> = keys.iter().map(|v| axis.format.format(*v)).collect();
    label_width(area, &labels) + 40
}

/// Widens `x` or `y` (raw data ranges, both non-degenerate) about its centre so that one data
/// unit has the same length on both axes of a plot `pixels` = (width, height) in size: the axis
/// with more data per pixel keeps its range, the other one gets the same units per pixel.
/// Non-finite results (spans near `f64::MAX`) leave the ranges unchanged.
pub fn equal_aspect_ranges(
    x: (f64, f64),
    y: (f64, f64),
    pixels: (f64, f64),
) -> ((f64, f64), (f64, f64)) {
    let (w, h) = (pixels.0.max(1.0), pixels.1.max(1.0));
    let per_px = ((x.1 - x.0) / w).max((y.1 - y.0) / h);
    let (cx, cy) = (0.5 * x.0 + 0.5 * x.1, 0.5 * y.0 + 0.5 * y.1);
    let (hx, hy) = (0.5 * per_px * w, 0.5 * per_px * h);
    let out = ((cx - hx, cx + hx), (cy - hy, cy + hy));
    let ok = [out.0 .0, out.0 .1, out.1 .0, out.1 .1]
        .iter()
        .all(|v| v.is_finite() && v.abs() <= HUGE)
        && per_px > 0.0;
    if ok {
        out
    } else {
        (x, y)
    }
}

/// Size in pixels (width, height) of the plotting area of a 2-D chart on `area` with a y label
/// area `y_label_px` wide, measured on a chart built like the real one (building draws nothing).
fn plot_pixels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    y_label_px: u32,
    fig: &Figure,
) -> Result<(f64, f64), PlotError> {
    let chart = ChartBuilder::on(area)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(y_label_px)
        .build_cartesian_2d(0f64..1f64, 0f64..1f64)
        .map_err(|e| draw_error(fig, e))?;
    let (x0, y0) = chart.backend_coord(&(0.0, 0.0));
    let (x1, y1) = chart.backend_coord(&(1.0, 1.0));
    Ok((f64::from((x1 - x0).max(1)), f64::from((y0 - y1).max(1))))
}

/// Axes with equal scales for data spanning `x_data` and `y_data`, and the y label area width
/// they need. The plot size depends on the width of the y tick labels, which depends on the y
/// range; the width only grows, so a few rounds reach a fixed point.
fn equal_aspect_axes<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    x_data: Option<(f64, f64)>,
    y_data: Option<(f64, f64)>,
    fig: &Figure,
) -> Result<(LinearAxis, LinearAxis, u32), PlotError> {
    const PAD: f64 = 0.05;
    let (xr, yr) = (linear_range(x_data, PAD), linear_range(y_data, PAD));
    let mut label_px = y_label_area(area, &LinearAxis::new(Some(yr), 0.0, N_LABELS));
    let mut rounds = 0;
    loop {
        let (xe, ye) = equal_aspect_ranges(xr, yr, plot_pixels(area, label_px, fig)?);
        let (xa, ya) = (
            LinearAxis::new(Some(xe), 0.0, N_LABELS),
            LinearAxis::new(Some(ye), 0.0, N_LABELS),
        );
        let need = y_label_area(area, &ya);
        rounds += 1;
        if need <= label_px || rounds >= 4 {
            return Ok((xa, ya, label_px.max(need)));
        }
        label_px = need;
    }
}

/// The legend of a 2-D panel: each labelled series with its style and colour, "(no data)"
/// after the label of one without a valid point.
fn legend_entries(
    panel: &Panel,
    runs: &[Vec<Vec<(f64, f64)>>],
) -> Vec<(String, SeriesStyle, RGBColor)> {
    panel
        .series
        .iter()
        .zip(runs)
        .filter(|(s, _)| !s.label.is_empty())
        .map(|(s, r)| {
            let label = if r.iter().any(|r| !r.is_empty()) {
                s.label.clone()
            } else {
                format!("{} (no data)", s.label)
            };
            (label, s.style, color(s.color))
        })
        .collect()
}

/// The axes of a 2-D panel for the data's ranges: the x axis, the linear y axis (`None` for
/// a logarithmic one) and the width of the y label area (px).
fn panel_axes_2d<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    x_data: Option<(f64, f64)>,
    y_data: Option<(f64, f64)>,
    fig: &Figure,
) -> Result<(LinearAxis, Option<LinearAxis>, u32), PlotError> {
    Ok(if panel.log_y {
        let y_range = log_range(y_data);
        // Labels are decades (and 2x/5x multiples) between the ends; the ends bound the width.
        let labels = [format_general(y_range.0), format_general(y_range.1)];
        (
            LinearAxis::new(x_data, 0.0, N_LABELS),
            None,
            label_width(area, &labels) + 40,
        )
    } else if panel.equal_aspect {
        let (x, y, px) = equal_aspect_axes(area, x_data, y_data, fig)?;
        (x, Some(y), px)
    } else {
        let y = LinearAxis::new(y_data, 0.05, N_LABELS);
        let px = y_label_area(area, &y);
        (LinearAxis::new(x_data, 0.0, N_LABELS), Some(y), px)
    })
}

/// Draws a 2-D panel into `area` (inside the panel's margins and caption).
fn draw_panel_2d<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    fig: &Figure,
    mode: LineMode,
) -> Result<(), PlotError> {
    let runs: Vec<Vec<Vec<(f64, f64)>>> = panel
        .series
        .iter()
        .map(|s| split_runs(s, panel.log_y))
        .collect();
    let area = &legend_strip(area, &legend_entries(panel, &runs), fig)?;
    let points = || runs.iter().flatten().flatten();
    let x_data = min_max(points().map(|p| p.0));
    let y_data = min_max(points().map(|p| p.1));
    let (x_axis, y_axis, y_label_px) = panel_axes_2d(area, panel, x_data, y_data, fig)?;
    // Points in axis units (the log axis is not divided).
    let (sx, sy) = (
        x_axis.scale(),
        y_axis.as_ref().map_or(1.0, LinearAxis::scale),
    );
    let prepared: Vec<Prepared> = panel
        .series
        .iter()
        .zip(runs)
        .map(|(series, runs)| Prepared {
            series,
            runs: runs
                .into_iter()
                .map(|r| r.into_iter().map(|(x, y)| (x * sx, y * sy)).collect())
                .collect(),
        })
        .collect();

    let mut builder = ChartBuilder::on(area);
    builder
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(y_label_px);
    let axes = (&x_axis, y_axis.as_ref(), y_data);
    draw_chart_2d(&mut builder, axes, panel, &prepared, fig, mode)
}

/// Builds the panel's chart on `builder` with its axes (x, linear y or `None` for a logarithmic
/// one over `y_data`), draws the mesh and labels, then the series.
fn draw_chart_2d<DB: DrawingBackend>(
    builder: &mut ChartBuilder<'_, '_, DB>,
    (x_axis, y_axis, y_data): (&LinearAxis, Option<&LinearAxis>, Option<(f64, f64)>),
    panel: &Panel,
    prepared: &[Prepared],
    fig: &Figure,
    mode: LineMode,
) -> Result<(), PlotError> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| draw_error(fig, e);
    let x_formatter = |v: &f64| x_axis.format.format(*v);
    let x_range = x_axis.range.0..x_axis.range.1;

    match y_axis {
        None => {
            let y_range = log_range(y_data);
            let mut chart = builder
                .build_cartesian_2d(x_range, (y_range.0..y_range.1).log_scale())
                .map_err(err)?;
            let y_formatter = |v: &f64| format_general(*v);
            chart
                .configure_mesh()
                .x_desc(panel.x_label.as_str())
                .y_desc(panel.y_label.as_str())
                .x_labels(x_axis.labels)
                .y_labels(N_LABELS)
                .x_label_formatter(&x_formatter)
                .y_label_formatter(&y_formatter)
                .label_style((FONT_FAMILY, 12))
                .axis_desc_style((FONT_FAMILY, 13))
                .bold_line_style(RGBColor(215, 215, 215))
                .light_line_style(RGBColor(242, 242, 242))
                .draw()
                .map_err(err)?;
            draw_series(&mut chart, prepared, fig, mode)
        }
        Some(y_axis) => {
            let mut chart = builder
                .build_cartesian_2d(x_range, y_axis.range.0..y_axis.range.1)
                .map_err(err)?;
            let y_formatter = |v: &f64| y_axis.format.format(*v);
            chart
                .configure_mesh()
                .x_desc(panel.x_label.as_str())
                .y_desc(panel.y_label.as_str())
                .x_labels(x_axis.labels)
                .y_labels(y_axis.labels)
                .x_label_formatter(&x_formatter)
                .y_label_formatter(&y_formatter)
                .label_style((FONT_FAMILY, 12))
                .axis_desc_style((FONT_FAMILY, 13))
                .bold_line_style(RGBColor(215, 215, 215))
                .light_line_style(RGBColor(242, 242, 242))
                .draw()
                .map_err(err)?;
            draw_series(&mut chart, prepared, fig, mode)
        }
    }
}

/// Draws one run of at least two points as a solid or dashed line, in 2-D or
/// 3-D coordinates alike; returns its annotation (for the legend entry).
fn draw_line_run<'a, 'b, DB, CT>(
    chart: &'b mut ChartContext<'a, DB, CT>,
    run: Vec<CT::From>,
    style: SeriesStyle,
    mode: LineMode,
    line: ShapeStyle,
) -> Result<&'b mut SeriesAnno<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
    CT::From: Clone + 'static,
{
    match (style, mode) {
        (SeriesStyle::Line, LineMode::Polylines) => chart.draw_series(LineSeries::new(run, line)),
        (SeriesStyle::Line, LineMode::Segments) => chart.draw_series(
            run.windows(2)
                .map(|w| PathElement::new(vec![w[0].clone(), w[1].clone()], line)),
        ),
        _ => chart.draw_series(DashedLineSeries::new(run, 8, 5, line)),
    }
}

/// Draws the prepared series into a chart with an f64 x axis (the legend is drawn above the
/// plot by [`legend_strip`]).
fn draw_series<'a, DB, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    prepared: &[Prepared],
    fig: &Figure,
    mode: LineMode,
) -> Result<(), PlotError>
where
    DB: DrawingBackend + 'a,
    Y: Ranged<ValueType = f64>,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| draw_error(fig, e);
    for p in prepared {
        let s = p.series;
        let c = color(s.color);
        let line = c.stroke_width(2);
        let fill = c.filled();
        match s.style {
            SeriesStyle::Markers => {
                let mut seen = HashSet::new();
                let pts: Vec<(f64, f64)> = p
                    .runs
                    .iter()
                    .flatten()
                    .copied()
                    .filter(|pt| seen.insert(chart.backend_coord(pt)))
                    .collect();
                chart
                    .draw_series(pts.into_iter().map(|pt| Circle::new(pt, 3, fill)))
                    .map_err(err)?;
            }
            SeriesStyle::Line | SeriesStyle::Dashed => {
                for run in &p.runs {
                    if run.len() == 1 {
                        chart
                            .draw_series(run.iter().map(|&pt| Circle::new(pt, 2, fill)))
                            .map_err(err)?;
                        continue;
                    }
                    let run = reduce_run(chart, run);
                    draw_line_run(chart, run, s.style, mode, line).map_err(err)?;
                }
            }
        }
    }
    Ok(())
}

/// Sets the legend text and sample (line, dashed line or marker in colour `c`) of a series.
fn legend_entry<'a, DB: DrawingBackend + 'a>(
    anno: &mut SeriesAnno<'a, DB>,
    label: String,
    style: SeriesStyle,
    c: RGBColor,
) {
    let line = c.stroke_width(2);
    let fill = c.filled();
    anno.label(label);
    match style {
        SeriesStyle::Markers => {
            anno.legend(move |(x, y)| Circle::new((x + 10, y), 3, fill));
        }
        SeriesStyle::Line => {
            anno.legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line));
        }
        SeriesStyle::Dashed => {
            anno.legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (8, 0)], line)
                    + PathElement::new(vec![(12, 0), (20, 0)], line)
            });
        }
    }
}

/// Estimated size (width, height) in pixels of the legend box for series `labels` (empty ones
/// have no entry; room for a "(no data)" suffix is kept), or `None` without entries: the text
/// block + 30 px sample + 10 px margins, 16 px per entry, as plotters lays it out.
fn legend_size<DB: DrawingBackend, CT: CoordTranslate>(
    area: &DrawingArea<DB, CT>,
    labels: &[&str],
) -> Option<(u32, u32)> {
    let style = TextStyle::from((FONT_FAMILY, 12).into_font());
    let labelled: Vec<&str> = labels.iter().copied().filter(|l| !l.is_empty()).collect();
    if labelled.is_empty() {
        return None;
    }
    let text_w = labelled
        .iter()
        .map(|l| {
            let text = format!("{l} (no data)");
            area.estimate_text_size(&text, &style)
                .map(|(w, _)| w)
                .unwrap_or(0)
        })
        .max()
        .unwrap_or(0);
    Some((text_w + 50, 16 * labelled.len() as u32 + 20))
}

/// Splits a 3-D series into runs of valid points (all coordinates finite and within ±[`HUGE`]).
fn split_runs_3d(s: &Series3d) -> Vec<Vec<(f64, f64, f64)>> {
    let mut runs = Vec::new();
    let mut cur: Vec<(f64, f64, f64)> = Vec::new();
    for ((&x, &y), &z) in s.x.iter().zip(&s.y).zip(&s.z) {
        if x.abs() <= HUGE && y.abs() <= HUGE && z.abs() <= HUGE {
            cur.push((x, y, z));
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

/// Axis ranges of a 3-D plot with equal scales: every axis gets the same span, the largest data
/// span padded by `pad` of it on each side, centred on its own data. Constant data (all spans
/// below 1e-9 of the magnitude) gets ±10 % of the largest magnitude (±1 at the origin); an axis
/// without data is centred on 0, and no data at all gives [0, 1] on every axis. The span is at
/// least 2e-6 of the largest magnitude, so no axis shows only floating-point noise.
pub fn cube_ranges(data: [Option<(f64, f64)>; 3], pad: f64) -> [(f64, f64); 3] {
    if data.iter().all(Option::is_none) {
        return [(0.0, 1.0); 3];
    }
    let mag = data
        .iter()
        .flatten()
        .fold(0.0f64, |m, (lo, hi)| m.max(lo.abs()).max(hi.abs()));
    let half_data = data
        .iter()
        .flatten()
        .fold(0.0f64, |m, (lo, hi)| m.max(0.5 * hi - 0.5 * lo));
    let half = if half_data <= 0.5e-9 * mag || half_data < TINY {
        if mag == 0.0 {
            1.0
        } else {
            (0.1 * mag).max(TINY)
        }
    } else {
        (half_data * (1.0 + 2.0 * pad)).max(1e-6 * mag)
    };
    data.map(|d| {
        let mid = d.map_or(0.0, |(lo, hi)| 0.5 * lo + 0.5 * hi);
        (mid - half, mid + half)
    })
}

/// Side of the cube (in plotters' 3-D pixel units) the three axes are mapped onto before the
/// projection; large, so that positions are not rounded visibly (plotters maps them to integers).
const CUBE: i32 = 20_000;

/// Space kept free around the projected box of a 3-D panel (left, right, top, bottom, in
/// pixels) for tick labels and axis descriptions.
const MARGIN_3D: (f64, f64, f64, f64) = (62.0, 62.0, 8.0, 46.0);

/// Tick mark length of 3-D axes in pixels; labels sit at twice this distance from the axis.
const TICK_3D: i32 = 5;

/// Number of tick labels requested on each 3-D axis.
const N_LABELS_3D: usize = 5;

/// Unit vectors of a view in data coordinates: (screen right, screen up, towards the viewer).
fn view_basis(view: View3d) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let (a, e) = (view.yaw_deg.to_radians(), view.pitch_deg.to_radians());
    let toward = [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()];
    let right = [-a.sin(), a.cos(), 0.0];
    // up = toward × right, so that right × up = toward (handedness is kept).
    let up = [-e.sin() * a.cos(), -e.sin() * a.sin(), e.cos()];
    (right, up, toward)
}

/// The projection of plotters' cube coordinates (0..[`CUBE`] on each axis) onto the pixel
/// rectangle `(x0, y0)`–`(x1, y1)`: orthographic along the view, scaled so that the whole box
/// fits inside the rectangle less [`MARGIN_3D`] and `legend_px` more on the right (room for the
/// legend). Row 2 is the depth (larger is farther).
fn projection_3d(
    view: View3d,
    (x0, y0): (i32, i32),
    (x1, y1): (i32, i32),
    legend_px: f64,
) -> ProjectionMatrix {
    let (r, u, v) = view_basis(view);
    let (ml, mr, mt, mb) = MARGIN_3D;
    let mr = mr.max(legend_px);
    let w = (f64::from(x1 - x0) - ml - mr).max(20.0);
    let h = (f64::from(y1 - y0) - mt - mb).max(20.0);
    let side = f64::from(CUBE);
    let extent = |a: [f64; 3]| side * (a[0].abs() + a[1].abs() + a[2].abs());
    let k = (w / extent(r)).min(h / extent(u));
    let (ox, oy) = (f64::from(x0) + ml + 0.5 * w, f64::from(y0) + mt + 0.5 * h);
    let c = 0.5 * side;
    let dot_c = |a: [f64; 3]| c * (a[0] + a[1] + a[2]);
    ProjectionMatrix::from([
        [k * r[0], k * r[1], k * r[2], ox - k * dot_c(r)],
        [-k * u[0], -k * u[1], -k * u[2], oy + k * dot_c(u)],
        [-v[0], -v[1], -v[2], dot_c(v)],
        [0.0, 0.0, 0.0, 1.0],
    ])
}

/// A 3-D series reduced to drawable pieces (in axis units).
struct Prepared3d<'a> {
    series: &'a Series3d,
    runs: Vec<Vec<(f64, f64, f64)>>,
}

/// A point of a 3-D chart as plotters' coordinate tuple.
fn pt3(p: [f64; 3]) -> (f64, f64, f64) {
    (p[0], p[1], p[2])
}

/// Draws the box of a 3-D chart the way engineering plot tools do: the three back faces filled
/// and gridded at the ticks, tick marks and labels along the front bottom edges of x and y and
/// along the leftmost vertical edge of z, each with its axis description beyond the labels.
/// Tick labels point away from the box; an edge seen end-on (shorter than 20 px) gets none.
fn draw_axes_3d<DB: DrawingBackend>(
    chart: &ChartContext<'_, DB, Cartesian3d<RangedCoordf64, RangedCoordf64, RangedCoordf64>>,
    names: [&str; 3],
    axes: &[LinearAxis; 3],
    fig: &Figure,
) -> Result<(), PlotError> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| draw_error(fig, e);
    let coord = chart.as_coord_spec();
    let area = chart.plotting_area();
    let ranges = [axes[0].range, axes[1].range, axes[2].range];
    let lo = [ranges[0].0, ranges[1].0, ranges[2].0];
    let hi = [ranges[0].1, ranges[1].1, ranges[2].1];
    let px = |p: [f64; 3]| coord.translate(&pt3(p));
    let depth = |p: [f64; 3]| coord.projected_depth(&p[0], &p[1], &p[2]);
    let with = |mut p: [f64; 3], i: usize, v: f64| {
        p[i] = v;
        p
    };
    let ticks: Vec<Vec<f64>> = axes
        .iter()
        .map(|a| RangedCoordf64::from(a.range.0..a.range.1).key_points(a.labels))
        .collect();
    // The back side of each axis: the face farther from the viewer (ties: the low end).
    let back: Vec<f64> = (0..3)
        .map(|i| {
            if depth(with(lo, i, hi[i])) > depth(lo) {
                hi[i]
            } else {
                lo[i]
            }
        })
        .collect();
    draw_back_faces(area, &back, lo, hi, &ticks).map_err(err)?;

    let (x0, y0) = px([
        0.5 * lo[0] + 0.5 * hi[0],
        0.5 * lo[1] + 0.5 * hi[1],
        0.5 * lo[2] + 0.5 * hi[2],
    ]);
    let tick_font = TextStyle::from((FONT_FAMILY, 12).into_font()).color(&BLACK);
    let axis_line = ShapeStyle::from(RGBColor(60, 60, 60)).stroke_width(1);
    for (idx, name) in names.iter().enumerate() {
        let starts = edge_starts(idx, lo, hi);
        let mid_of = |s: [f64; 3]| {
            let (a, b) = (px(s), px(with(s, idx, hi[idx])));
            (f64::from(a.0 + b.0) / 2.0, f64::from(a.1 + b.1) / 2.0)
        };
        // x and y: the lowest edge on screen (the front bottom one when seen from above);
        // z: the leftmost. Ties: the one nearer to the viewer.
        let score = |s: [f64; 3]| {
            let (mx, my) = mid_of(s);
            let d = f64::from(depth(s) + depth(with(s, idx, hi[idx])));
            if idx == 2 {
                (mx, d)
            } else {
                (-my, d)
            }
        };
        let Some(start) = starts.into_iter().min_by(|a, b| {
            score(*a)
                .partial_cmp(&score(*b))
                .unwrap_or(std::cmp::Ordering::Equal)
        }) else {
            continue;
        };
        let end = with(start, idx, hi[idx]);
        let (b, e) = (px(start), px(end));
        let (dx, dy) = (f64::from(e.0 - b.0), f64::from(e.1 - b.1));
        let len = dx.hypot(dy);
        area.draw(&PathElement::new(vec![pt3(start), pt3(end)], axis_line))
            .map_err(err)?;
        if len < 20.0 {
            continue;
        }
        // Unit normal of the edge on screen, pointing away from the box centre.
        let (mx, my) = mid_of(start);
        let (mut nx, mut ny) = (-dy / len, dx / len);
        if nx * (mx - f64::from(x0)) + ny * (my - f64::from(y0)) < 0.0 {
            (nx, ny) = (-nx, -ny);
        }
        let off = |d: f64| ((nx * d).round() as i32, (ny * d).round() as i32);
        let (lw, lh) = draw_ticks_3d(
            area,
            (&axes[idx], &ticks[idx]),
            (start, idx),
            (nx, ny),
            &tick_font,
            axis_line,
        )
        .map_err(err)?;
        if name.is_empty() {
            continue;
        }
        let extent = nx.abs() * f64::from(lw) + ny.abs() * f64::from(lh);
        let gap = f64::from(TICK_3D + 3) + extent + 8.0;
        let (style, gap) = axis_title_style(nx, ny, gap);
        // Anchor at the start point of the edge and offset to the description position.
        let (ox, oy) = off(gap);
        let to = (
            (mx - f64::from(b.0)).round() as i32 + ox,
            (my - f64::from(b.1)).round() as i32 + oy,
        );
        area.draw(&(EmptyElement::at(pt3(start)) + Text::new(name.to_string(), to, style)))
            .map_err(err)?;
    }
    Ok(())
}

/// The ticks of axis `idx` of a 3-D chart along its edge from `start`, each a short line and
/// its label on the side of the outward normal `(nx, ny)` (screen); returns the largest label
/// size (width, height in pixels).
fn draw_ticks_3d<DB: DrawingBackend>(
    area: &DrawingArea<DB, Cartesian3d<RangedCoordf64, RangedCoordf64, RangedCoordf64>>,
    (a, ticks): (&LinearAxis, &[f64]),
    (start, idx): ([f64; 3], usize),
    (nx, ny): (f64, f64),
    tick_font: &TextStyle<'_>,
    axis_line: ShapeStyle,
) -> Result<(u32, u32), DrawingAreaErrorKind<DB::ErrorType>> {
    let (h, v) = label_alignment(nx, ny);
    let off = |d: f64| ((nx * d).round() as i32, (ny * d).round() as i32);
    let (mut lw, mut lh) = (0u32, 0u32);
    for &t in ticks {
        let text = a.format.format(t);
        if let Ok((w, h)) = area.estimate_text_size(&text, tick_font) {
            (lw, lh) = (lw.max(w), lh.max(h));
        }
        let style = tick_font.clone().pos(Pos::new(h, v));
        let mut at = start;
        at[idx] = t;
        area.draw(
            &(EmptyElement::at(pt3(at))
                + PathElement::new(vec![(0, 0), off(f64::from(TICK_3D))], axis_line)
                + Text::new(text, off(f64::from(TICK_3D + 3)), style)),
        )?;
    }
    Ok((lw, lh))
}

/// The three back faces of a 3-D chart's box (`back[i]`: the far end of
/// axis `i`), filled, gridded at the `ticks` and outlined.
fn draw_back_faces<DB: DrawingBackend>(
    area: &DrawingArea<DB, Cartesian3d<RangedCoordf64, RangedCoordf64, RangedCoordf64>>,
    back: &[f64],
    lo: [f64; 3],
    hi: [f64; 3],
    ticks: &[Vec<f64>],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let with = |mut p: [f64; 3], i: usize, v: f64| {
        p[i] = v;
        p
    };
    let pane = ShapeStyle::from(RGBColor(247, 247, 247)).filled();
    let grid = ShapeStyle::from(RGBColor(215, 215, 215)).stroke_width(1);
    let frame = ShapeStyle::from(RGBColor(150, 150, 150)).stroke_width(1);
    for (i, &back_i) in back.iter().enumerate() {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let base = with(lo, i, back_i);
        let corners = [
            base,
            with(base, j, hi[j]),
            with(with(base, j, hi[j]), k, hi[k]),
            with(base, k, hi[k]),
        ];
        area.draw(&Polygon::new(corners.map(pt3).to_vec(), pane))?;
        for (a, b) in [(j, k), (k, j)] {
            for &t in &ticks[a] {
                let p = with(base, a, t);
                area.draw(&PathElement::new(
                    vec![pt3(p), pt3(with(p, b, hi[b]))],
                    grid,
                ))?;
            }
        }
        let mut outline = corners.map(pt3).to_vec();
        outline.push(pt3(base));
        area.draw(&PathElement::new(outline, frame))?;
    }

    Ok(())
}

/// The start points of the four edges of the box `[lo, hi]` parallel to
/// axis `idx`.
fn edge_starts(idx: usize, lo: [f64; 3], hi: [f64; 3]) -> Vec<[f64; 3]> {
    let others: Vec<usize> = (0..3).filter(|&i| i != idx).collect();
    let mut starts = Vec::with_capacity(4);
    for &a in &[lo[others[0]], hi[others[0]]] {
        for &b in &[lo[others[1]], hi[others[1]]] {
            let mut p = lo;
            p[others[0]] = a;
            p[others[1]] = b;
            starts.push(p);
        }
    }
    starts
}

/// Where a tick label sits relative to its tick, for an edge whose outward
/// screen normal is `(nx, ny)`: the label points away from the box.
fn label_alignment(nx: f64, ny: f64) -> (HPos, VPos) {
    let h = if nx > 0.5 {
        HPos::Left
    } else if nx < -0.5 {
        HPos::Right
    } else {
        HPos::Center
    };
    let v = if ny > 0.5 {
        VPos::Top
    } else if ny < -0.5 {
        VPos::Bottom
    } else {
        VPos::Center
    };
    (h, v)
}

/// The style of an axis description beyond its tick labels and its
/// distance `gap` from the edge: rotated along a vertical-ish edge (8 px
/// farther), else level and above or below.
fn axis_title_style(nx: f64, ny: f64, gap: f64) -> (TextStyle<'static>, f64) {
    let font = (FONT_FAMILY, 13).into_font();
    if nx.abs() > 0.7 {
        let style = TextStyle::from(font.transform(FontTransform::Rotate270))
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Center));
        (style, gap + 8.0)
    } else {
        let vpos = if ny >= 0.0 { VPos::Top } else { VPos::Bottom };
        let style = TextStyle::from(font)
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, vpos));
        (style, gap)
    }
}

/// Draws a 3-D panel into `area` (inside the panel's margins and caption).
fn draw_panel_3d<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, Shift>,
    panel: &Panel,
    axes3d: &Axes3d,
    fig: &Figure,
    mode: LineMode,
) -> Result<(), PlotError> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| draw_error(fig, e);
    let (axes, prepared) = prepare_3d(axes3d);
    let ranges = [axes[0].range, axes[1].range, axes[2].range];

    let mut chart = ChartBuilder::on(area)
        .build_cartesian_3d(
            ranges[0].0..ranges[0].1,
            ranges[1].0..ranges[1].1,
            ranges[2].0..ranges[2].1,
        )
        .map_err(err)?;
    let labels: Vec<&str> = axes3d.series.iter().map(|s| s.label.as_str()).collect();
    // The legend goes in the upper right corner, beside the box (which is made narrower).
    let legend_px = match legend_size(chart.plotting_area(), &labels) {
        Some((w, _)) => f64::from(w + 10),
        None => 0.0,
    };
    let (px, py) = chart.plotting_area().get_pixel_range();
    let projection = projection_3d(
        axes3d.view,
        (px.start, py.start),
        (px.end, py.end),
        legend_px,
    );
    chart
        .set_3d_pixel_range((CUBE, CUBE, CUBE))
        .with_projection(|_| projection);

    draw_axes_3d(
        &chart,
        [
            panel.x_label.as_str(),
            panel.y_label.as_str(),
            axes3d.z_label.as_str(),
        ],
        &axes,
        fig,
    )?;

    let mut any_label = false;
    for p in &prepared {
        let s = p.series;
        let c = color(s.color);
        let line = c.stroke_width(2);
        let fill = c.filled();
        let label = if p.runs.is_empty() {
            format!("{} (no data)", s.label)
        } else {
            s.label.clone()
        };
        let coord = chart.as_coord_spec().clone();
        let px = |pt: &(f64, f64, f64)| coord.translate(pt);
        let thin = |run: &[(f64, f64, f64)]| {
            let thinned = thin_run(run, px);
            let pts: Vec<[f64; 3]> = thinned.iter().map(|p| [p.0, p.1, p.2]).collect();
            cap_indices(&pts, MAX_TRACE_POINTS)
                .into_iter()
                .map(|i| thinned[i])
                .collect::<Vec<_>>()
        };
        let mut labelled = false;
        let mut annotate = |anno: &mut SeriesAnno<'a, DB>| {
            if !labelled && !s.label.is_empty() {
                legend_entry(anno, label.clone(), s.style, c);
                labelled = true;
            }
        };
        match s.style {
            SeriesStyle::Markers => {
                let mut seen = HashSet::new();
                let pts: Vec<(f64, f64, f64)> = p
                    .runs
                    .iter()
                    .flatten()
                    .copied()
                    .filter(|pt| seen.insert(px(pt)))
                    .collect();
                let anno = chart
                    .draw_series(pts.into_iter().map(|pt| Circle::new(pt, 3, fill)))
                    .map_err(err)?;
                annotate(anno);
            }
            SeriesStyle::Line | SeriesStyle::Dashed => {
                if p.runs.is_empty() {
                    let anno = chart
                        .draw_series(std::iter::empty::<Circle<(f64, f64, f64), i32>>())
                        .map_err(err)?;
                    annotate(anno);
                }
                for run in &p.runs {
                    let run = thin(run);
                    let anno = if run.len() == 1 {
                        chart
                            .draw_series(run.into_iter().map(|pt| Circle::new(pt, 2, fill)))
                            .map_err(err)?
                    } else {
                        draw_line_run(&mut chart, run, s.style, mode, line).map_err(err)?
                    };
                    annotate(anno);
                }
            }
        }
        any_label |= !s.label.is_empty();
    }
    if any_label {
        draw_legend(&mut chart).map_err(err)?;
    }
    Ok(())
}

/// The points of `run` that land on another pixel (`px`) than their
/// predecessor, and the last one: the others add nothing to a line or to
/// markers.
fn thin_run(
    run: &[(f64, f64, f64)],
    px: impl Fn(&(f64, f64, f64)) -> (i32, i32),
) -> Vec<(f64, f64, f64)> {
    let mut out: Vec<(f64, f64, f64)> = Vec::with_capacity(run.len());
    let mut last = None;
    for (i, pt) in run.iter().enumerate() {
        let here = px(pt);
        if last != Some(here) || i + 1 == run.len() {
            out.push(*pt);
        }
        last = Some(here);
    }
    out
}

/// The series' legend in the upper right corner of a chart.
fn draw_legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(190, 190, 190))
        .label_font((FONT_FAMILY, 12))
        .draw()
}

/// The axes of a 3-D panel (a cube around the data, 4 % margin) and its
/// series' runs in the axes' scaled units.
fn prepare_3d(axes3d: &Axes3d) -> ([LinearAxis; 3], Vec<Prepared3d<'_>>) {
    let runs: Vec<Vec<Vec<(f64, f64, f64)>>> = axes3d.series.iter().map(split_runs_3d).collect();
    let points = || runs.iter().flatten().flatten();
    let data = [
        min_max(points().map(|p| p.0)),
        min_max(points().map(|p| p.1)),
        min_max(points().map(|p| p.2)),
    ];
    let axes = cube_ranges(data, 0.04).map(|r| LinearAxis::new(Some(r), 0.0, N_LABELS_3D));
    let scale = [axes[0].scale(), axes[1].scale(), axes[2].scale()];
    let prepared: Vec<Prepared3d> = axes3d
        .series
        .iter()
        .zip(runs)
        .map(|(series, runs)| Prepared3d {
            series,
            runs: runs
                .into_iter()
                .map(|r| {
                    r.into_iter()
                        .map(|(x, y, z)| (x * scale[0], y * scale[1], z * scale[2]))
                        .collect()
                })
                .collect(),
        })
        .collect();

    (axes, prepared)
}

/// M4-reduces a run whose x is non-decreasing, using the chart's pixel columns; other runs
/// (a path in the plane) keep the points that land on another pixel than their predecessor.
/// Either is then capped at [`MAX_TRACE_POINTS`] ([`cap_indices`]).
fn reduce_run<DB, Y>(
    chart: &ChartContext<'_, DB, Cartesian2d<RangedCoordf64, Y>>,
    run: &[(f64, f64)],
) -> Vec<(f64, f64)>
where
    DB: DrawingBackend,
    Y: Ranged<ValueType = f64>,
{
    let monotone = run.windows(2).all(|w| w[0].0 <= w[1].0);
    let (w, _) = chart.plotting_area().dim_in_pixel();
    let reduced: Vec<(f64, f64)> = if !monotone {
        let px: Vec<(i32, i32)> = run.iter().map(|pt| chart.backend_coord(pt)).collect();
        (0..run.len())
            .filter(|&i| i == 0 || i + 1 == run.len() || px[i] != px[i - 1])
            .map(|i| run[i])
            .collect()
    } else if run.len() <= 4 * w as usize {
        run.to_vec()
    } else {
        let cols: Vec<i32> = run.iter().map(|pt| chart.backend_coord(pt).0).collect();
        let ys: Vec<f64> = run.iter().map(|pt| pt.1).collect();
        m4_indices(&cols, &ys).into_iter().map(|i| run[i]).collect()
    };
    let pts: Vec<[f64; 2]> = reduced.iter().map(|p| [p.0, p.1]).collect();
    cap_indices(&pts, MAX_TRACE_POINTS)
        .into_iter()
        .map(|i| reduced[i])
        .collect()
}

/// Most points a line of a figure keeps ([`cap_indices`]): a long path (a 26-minute run at
/// 1 kHz, retracing its loop) drawn through every pixel it visits would otherwise write
/// megabytes of SVG per trace.
pub const MAX_TRACE_POINTS: usize = 2000;

/// Indices of at most `max` of `pts` (at least the two ends), in order: all of them if they
/// are few enough, else the points cut into consecutive buckets of equal count, each keeping
/// its first and last point and its lowest and highest point in every coordinate (so the
/// line keeps every extreme: its bounding box and its peaks per bucket).
pub fn cap_indices<const D: usize>(pts: &[[f64; D]], max: usize) -> Vec<usize> {
    let n = pts.len();
    let per_bucket = 2 + 2 * D;
    if n <= max.max(per_bucket) {
        return (0..n).collect();
    }
    let buckets = (max / per_bucket).max(1);
    let mut keep = Vec::with_capacity(buckets * per_bucket);
    for b in 0..buckets {
        let (lo, hi) = (b * n / buckets, (b + 1) * n / buckets);
        if lo >= hi {
            continue;
        }
        let mut group = Vec::with_capacity(per_bucket);
        group.extend([lo, hi - 1]);
        let by = |d: usize| move |i: &usize, j: &usize| pts[*i][d].total_cmp(&pts[*j][d]);
        group.extend(
            (0..D)
                .flat_map(|d| [(lo..hi).min_by(by(d)), (lo..hi).max_by(by(d))])
                .flatten(),
        );
        group.sort_unstable();
        group.dedup();
        keep.extend(group);
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(n: usize) -> Vec<f64> {
        (0..n).map(|i| i as f64 / (n - 1) as f64).collect()
    }

    #[test]
    fn linear_range_is_never_degenerate() {
        assert_eq!(linear_range(None, 0.05), (0.0, 1.0));
        assert_eq!(linear_range(Some((0.0, 0.0)), 0.05), (-1.0, 1.0));
        let (lo, hi) = linear_range(Some((2.0, 2.0)), 0.05);
        assert!((lo - 1.8).abs() < 1e-12 && (hi - 2.2).abs() < 1e-12);
        let (lo, hi) = linear_range(Some((-3.0, -3.0)), 0.05);
        assert!(lo < -3.0 && hi > -3.0);
        // Floating-point noise on a constant counts as constant.
        let (lo, hi) = linear_range(Some((1.0, 1.0 + 1e-15)), 0.05);
        assert!(hi - lo > 0.1);
        let (lo, hi) = linear_range(Some((1e-300, 1e-300)), 0.0);
        assert!(lo < hi && lo.is_finite() && hi.is_finite());
        // Normal data: padded by the given fraction.
        let (lo, hi) = linear_range(Some((0.0, 10.0)), 0.05);
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
        let (lo, hi) = linear_range(Some((-HUGE, HUGE)), 0.05);
        assert!(lo.is_finite() && hi.is_finite() && lo < hi && (hi - lo).is_finite());
        let (lo, hi) = linear_range(Some((1e-308, 3e-308)), 0.05);
        assert!(lo < 1e-308 && hi > 3e-308 && hi - lo >= TINY);
    }

    /// Checks the ticks and labels plotters will draw for an axis over `data`.
    fn check_axis(data: (f64, f64)) {
        let axis = LinearAxis::new(Some(data), 0.05, 6);
        let (lo, hi) = axis.range;
        assert!(lo < hi && lo.is_finite() && hi.is_finite(), "{data:?}");
        // The axis (in raw units) contains the data.
        let s = axis.scale();
        assert!(
            lo / s <= data.0 * (1.0 + 1e-12) + 1e-300,
            "{data:?} {axis:?}"
        );
        assert!(
            hi / s >= data.1 * (1.0 - 1e-12) - 1e-300,
            "{data:?} {axis:?}"
        );
        let keys = RangedCoordf64::from(lo..hi).key_points(axis.labels);
        assert!(
            (2..=axis.labels).contains(&keys.len()),
            "{data:?} {axis:?}: {keys:?}"
        );
        let step = keys[1] - keys[0];
        for k in &keys {
            assert!(
                *k >= lo - 1e-9 * step && *k <= hi + 1e-9 * step,
                "{k} outside {lo}..{hi}"
            );
        }
        let texts: Vec<String> = keys.iter().map(|&v| axis.format.format(v)).collect();
        assert!(
            texts.windows(2).all(|w| w[0] != w[1]),
            "{data:?}: {texts:?}"
        );
        for (t, &v) in texts.iter().zip(&keys) {
            let parsed: f64 = t.parse().unwrap();
            let raw = v / s;
            assert!(
                (parsed - raw).abs() <= 1e-3 * step / s,
                "{data:?}: label {t} for {raw:e}"
            );
            // Narrow ranges far from zero need more digits; ordinary ones stay short.
            let rel = (data.1 - data.0) / data.0.abs().max(data.1.abs());
            let limit = if rel > 1e-2 { 12 } else { 18 };
            assert!(t.len() <= limit, "label too long: {t} for {data:?}");
        }
    }

    #[test]
    fn random_ranges_give_good_ticks_quickly() {
        // Data from 1e-250 to 1e250, both signs, wide and narrow: plotters' key points must
        // exist (its loop terminates), lie on the axis, and print distinctly and accurately.
        use plotters::coord::combinators::LogCoord;
        let mut state = 99u64;
        let mut rnd = move || ofmpc::random::uniform(&mut state);
        for _ in 0..3000 {
            let a = (rnd() * 2.0 - 1.0).signum() * 10f64.powf(rnd() * 500.0 - 250.0);
            let b = if rnd() < 0.5 {
                a * (1.0 + 10f64.powf(-rnd() * 16.0))
            } else {
                (rnd() * 2.0 - 1.0).signum() * 10f64.powf(rnd() * 500.0 - 250.0)
            };
            check_axis(min_max([a, b].into_iter()).unwrap());
            let (a, b) = (
                a.abs().clamp(LOG_LIMITS.0, LOG_LIMITS.1),
                b.abs().clamp(LOG_LIMITS.0, LOG_LIMITS.1),
            );
            let (llo, lhi) = log_range(min_max([a, b].into_iter()));
            assert!(0.0 < llo && llo < lhi && lhi.is_finite(), "{a} {b}");
            let log_keys = LogCoord::from((llo..lhi).log_scale()).key_points(6);
            assert!(log_keys.iter().all(|v| v.is_finite()), "{log_keys:?}");
        }
    }

    #[test]
    fn typical_ranges_give_good_ticks() {
        for data in [
            (0.0, 1.0),
            (0.0, 10.0),
            (-1.2e-4, 3.3e-4),
            (1.5, 1.50001),
            (0.0, 12_000.0),
            (-2.0e6, 5.0e6),
            (3.0e-7, 9.0e-7),
            (-0.05, 0.05),
            (99.9, 100.4),
            (-2.47e-16, 1.18e-17),
            (-3e-15, 3e-15),
            (0.0, 5.0),
        ] {
            check_axis(data);
        }
    }

    #[test]
    fn log_range_is_never_degenerate() {
        assert_eq!(log_range(None), (1.0, 10.0));
        assert_eq!(log_range(Some((1e-6, 1e-6))), (5e-7, 2e-6));
        let (lo, hi) = log_range(Some((1e-6, 1e-2)));
        assert!(lo < 1e-6 && hi > 1e-2 && lo > 0.0);
        let (lo, hi) = log_range(Some(LOG_LIMITS));
        assert!(lo > 0.0 && lo < LOG_LIMITS.0 && hi > LOG_LIMITS.1 && (hi / lo).is_finite());
    }

    #[test]
    fn tick_format_examples() {
        let f = TickFormat::for_ticks(&[0.0, 0.5, 1.0, 1.5], 0);
        assert_eq!(f.format(1.0), "1.0");
        assert_eq!(f.format(0.0), "0");
        assert_eq!(f.format(-1e-17), "0");
        let f = TickFormat::for_ticks(&[-2.0, 0.0, 2.0, 4.0], -4);
        assert_eq!(f.format(-2.0), "-2e-4");
        assert_eq!(f.format(4.0), "4e-4");
        assert_eq!(f.format(0.0), "0");
        let f = TickFormat::for_ticks(&[0.0, 2.0, 4.0], 0);
        assert_eq!(f.format(4.0), "4");
        let axis = LinearAxis::new(Some((-5e-4, 1e-3)), 0.0, 6);
        assert_eq!(axis.exponent, -3);
        assert_eq!(axis.format.format(-0.5), "-0.5e-3");
        assert_eq!(axis.format.format(1.0), "1.0e-3");
        assert_eq!(LinearAxis::new(Some((0.0, 4e5)), 0.0, 6).exponent, 5);
        assert_eq!(LinearAxis::new(Some((0.0, 4e4)), 0.0, 6).exponent, 0);
        assert_eq!(LinearAxis::new(None, 0.0, 6).range, (0.0, 1.0));
    }

    #[test]
    fn format_general_examples() {
        assert_eq!(format_general(1e-6), "1e-6");
        assert_eq!(format_general(2.5e7), "2.5e7");
        assert_eq!(format_general(0.02), "0.02");
        assert_eq!(format_general(150.0), "150");
        assert_eq!(format_general(1.0), "1");
        assert_eq!(format_general(9.999e-5), "1e-4");
        assert_eq!(format_general(0.0), "0");
    }

    #[test]
    fn m4_keeps_extremes_and_ends_of_every_column() {
        // Pseudo-random data (LCG) over 37 columns of varying width.
        let mut state = 12345u64;
        let mut rnd = || ofmpc::random::uniform(&mut state);
        let n = 2000;
        let cols: Vec<i32> = (0..n).map(|i| (i * 37 / n) as i32).collect();
        let ys: Vec<f64> = (0..n).map(|_| rnd() * 2.0 - 1.0).collect();
        let keep = m4_indices(&cols, &ys);
        assert!(keep.windows(2).all(|w| w[0] < w[1]), "sorted, unique");
        assert!(keep.len() <= 4 * 37);
        for c in 0..37 {
            let all: Vec<usize> = (0..n).filter(|&i| cols[i] == c).collect();
            let kept: Vec<usize> = keep.iter().copied().filter(|&i| cols[i] == c).collect();
            assert_eq!(kept.first(), all.first());
            assert_eq!(kept.last(), all.last());
            let mm = |v: &[usize]| min_max(v.iter().map(|&i| ys[i])).unwrap();
            assert_eq!(mm(&kept), mm(&all));
        }
        // Fewer points than columns: nothing dropped.
        assert_eq!(m4_indices(&[0, 1, 2], &[3.0, 1.0, 2.0]), vec![0, 1, 2]);
        assert!(m4_indices(&[], &[]).is_empty());
    }

    #[test]
    fn runs_split_at_invalid_points() {
        let s = Series::line(
            "a",
            vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0, f64::NAN],
            vec![1.0, f64::NAN, 2.0, -3.0, f64::INFINITY, 4.0, 1.0],
            COLOR_FIRST,
        );
        assert_eq!(
            split_runs(&s, false),
            vec![
                vec![(0.0, 1.0)],
                vec![(2.0, 2.0), (3.0, -3.0)],
                vec![(5.0, 4.0)]
            ]
        );
        assert_eq!(
            split_runs(&s, true),
            vec![vec![(0.0, 1.0)], vec![(2.0, 2.0)], vec![(5.0, 4.0)]]
        );
    }

    #[test]
    fn validation_errors_name_the_problem() {
        let mut fig = Figure::new("Fig. 6", 2);
        assert!(matches!(validate(&fig), Err(PlotError::NoPanels { .. })));
        let mut p = Panel::new("q1", "t (s)", "e (rad)");
        p.series
            .push(Series::line("first", ramp(5), ramp(4), COLOR_FIRST));
        fig.panels.push(p);
        let e = validate(&fig).unwrap_err();
        assert!(matches!(
            e,
            PlotError::LengthMismatch {
                x_len: 5,
                y_len: 4,
                ..
            }
        ));
        let msg = e.to_string();
        assert!(
            msg.contains("q1") && msg.contains("first") && msg.contains("Fig. 6"),
            "{msg}"
        );
        fig.panels[0].series[0].y = ramp(5);
        assert!(validate(&fig).is_ok());
        fig.columns = 0;
        assert!(matches!(validate(&fig), Err(PlotError::ZeroColumns { .. })));
        fig.columns = 1;
        fig.panel_size = (50, 50);
        assert!(matches!(validate(&fig), Err(PlotError::BadSize { .. })));
        fig.panel_size = (100_000, 100_000);
        assert!(matches!(validate(&fig), Err(PlotError::BadSize { .. })));
    }

    #[test]
    fn grid_shape() {
        let mut fig = Figure::new("", 3);
        fig.panels = vec![Panel::new("", "", ""); 6];
        assert_eq!(fig.grid(), (2, 3));
        assert_eq!(fig.canvas_size(), (3 * 560, 2 * 340));
        fig.columns = 4;
        assert_eq!(fig.grid(), (2, 4));
        fig.columns = 10;
        assert_eq!(fig.grid(), (1, 6));
        fig.title = "T".into();
        assert_eq!(fig.canvas_size().1, 340 + TITLE_HEIGHT);
    }

    #[test]
    fn cube_ranges_have_equal_spans_centred_on_the_data() {
        let data = [
            Some((380.0, 780.0)),
            Some((-200.0, 200.0)),
            Some((148.0, 150.0)),
        ];
        let r = cube_ranges(data, 0.04);
        let span = r[0].1 - r[0].0;
        // The largest span (400) padded by 4 % on each side, on every axis.
        assert!((span - 400.0 * 1.08).abs() < 1e-9, "{r:?}");
        for (k, d) in data.iter().enumerate() {
            let (lo, hi) = d.unwrap();
            assert!((r[k].1 - r[k].0 - span).abs() < 1e-9);
            assert!(((r[k].0 + r[k].1) - (lo + hi)).abs() < 1e-9);
            assert!(r[k].0 < lo && r[k].1 > hi);
        }
        // Degenerate data: never a zero span, always finite.
        assert_eq!(cube_ranges([None; 3], 0.04), [(0.0, 1.0); 3]);
        let r = cube_ranges([Some((0.0, 0.0)); 3], 0.04);
        assert_eq!(r, [(-1.0, 1.0); 3]);
        let r = cube_ranges(
            [Some((5.0, 5.0)), Some((0.0, 0.0)), Some((-5.0, -5.0))],
            0.04,
        );
        assert_eq!(r, [(4.5, 5.5), (-0.5, 0.5), (-5.5, -4.5)]);
        let r = cube_ranges([Some((-HUGE, HUGE)), None, Some((1e12, 1e12 + 1e-3))], 0.04);
        for (lo, hi) in r {
            assert!(lo.is_finite() && hi.is_finite() && lo < hi, "{r:?}");
        }
        // A tiny span far from zero is widened to 2e-6 of the magnitude, not shown as noise.
        let r = cube_ranges(
            [Some((1e6, 1e6 + 0.01)), Some((0.0, 0.0)), Some((0.0, 0.0))],
            0.0,
        );
        assert!(
            (r[0].1 - r[0].0 - 2e-6 * (1e6 + 0.01)).abs() < 1e-9,
            "{r:?}"
        );
    }

    #[test]
    fn view_basis_is_right_handed_and_orthonormal() {
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for (yaw, pitch) in [(-60.0, 30.0), (0.0, 0.0), (123.0, -80.0), (-90.0, 90.0)] {
            let (r, u, v) = view_basis(View3d {
                yaw_deg: yaw,
                pitch_deg: pitch,
            });
            for (a, b, want) in [
                (r, r, 1.0),
                (u, u, 1.0),
                (v, v, 1.0),
                (r, u, 0.0),
                (r, v, 0.0),
            ] {
                assert!((dot(a, b) - want).abs() < 1e-12);
            }
            let rxu = cross(r, u);
            assert!(
                (0..3).all(|i| (rxu[i] - v[i]).abs() < 1e-12),
                "{yaw} {pitch}"
            );
            // z never points down on screen when seen from above or level.
            if pitch >= 0.0 {
                assert!(u[2] >= -1e-12);
            }
        }
        // Default view: x to the right and towards the viewer, y to the right and away.
        let (r, _, v) = view_basis(View3d::default());
        assert!(r[0] > 0.0 && v[0] > 0.0 && r[1] > 0.0 && v[1] < 0.0);
    }

    #[test]
    fn validation_of_3d_panels() {
        let mut fig = Figure::new("F", 1);
        let mut p = Panel::new_3d("P", "x", "y", "z");
        p.series_3d()
            .push(Series3d::line("s", ramp(3), ramp(3), ramp(3), 1));
        fig.panels.push(p);
        assert!(validate(&fig).is_ok());
        fig.panels[0].log_y = true;
        assert!(matches!(validate(&fig), Err(PlotError::Mixed3d { .. })));
        fig.panels[0].log_y = false;
        fig.panels[0].series_3d()[0].y.push(1.0);
        let e = validate(&fig).unwrap_err();
        assert!(matches!(
            e,
            PlotError::LengthMismatch3d {
                x_len: 3,
                y_len: 4,
                z_len: 3,
                ..
            }
        ));
        // series_3d on a 2-D panel turns it into a 3-D one.
        let mut q = Panel::new("Q", "x", "y");
        assert!(q.three_d.is_none());
        q.series_3d();
        assert_eq!(q.three_d.map(|a| a.view), Some(View3d::default()));
    }

    #[test]
    fn capping_keeps_the_ends_and_every_extreme_within_the_bound() {
        let mut state = 777u64;
        let mut rnd = || ofmpc::random::uniform(&mut state);
        let n = 100_000;
        let pts: Vec<[f64; 2]> = (0..n).map(|_| [rnd(), rnd() * 3.0 - 1.0]).collect();
        let keep = cap_indices(&pts, MAX_TRACE_POINTS);
        assert!(keep.len() <= MAX_TRACE_POINTS, "{}", keep.len());
        assert!(keep.windows(2).all(|w| w[0] < w[1]), "sorted, unique");
        assert_eq!((keep[0], *keep.last().unwrap()), (0, n - 1));
        for d in 0..2 {
            let all = min_max(pts.iter().map(|p| p[d])).unwrap();
            let kept = min_max(keep.iter().map(|&i| pts[i][d])).unwrap();
            assert_eq!(all, kept, "coordinate {d}");
        }
        // Few points: all kept.
        assert_eq!(
            cap_indices(&pts[..10], MAX_TRACE_POINTS),
            (0..10).collect::<Vec<_>>()
        );
    }

    /// A 26-minute path at 1 kHz (1.56 million points: a loop retraced 140 times with a
    /// drift, so that nearly every point lands on a new pixel), as a path in the plane, as a
    /// time series and in 3-D: each line of the SVG has at most [`MAX_TRACE_POINTS`] points and
    /// the document stays under 400 kB (without the cap the path alone wrote megabytes).
    #[test]
    fn long_paths_write_a_bounded_svg() {
        let n = 1_560_000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let phase = |k: usize| k as f64 * 2.0 * std::f64::consts::PI / 11_000.0;
        let drift = |k: usize| 1.0 + 0.3 * k as f64 / n as f64;
        let x: Vec<f64> = (0..n).map(|k| drift(k) * phase(k).cos()).collect();
        let y: Vec<f64> = (0..n).map(|k| drift(k) * phase(k).sin()).collect();
        let mut fig = Figure::new("long", 3);
        let mut plane = Panel::new("path", "x", "y");
        plane.equal_aspect = true;
        plane
            .series
            .push(Series::line("p", x.clone(), y.clone(), 1));
        let mut time = Panel::new("x(t)", "t", "x");
        time.series.push(Series::line("x", t, x.clone(), 2));
        let mut space = Panel::new_3d("3-D", "x", "y", "z");
        space
            .series_3d()
            .push(Series3d::line("p", x.clone(), y, x, 3));
        fig.panels = vec![plane, time, space];
        let svg = render_svg(&fig).unwrap();
        assert!(svg.len() < 400_000, "{} bytes", svg.len());
        for line in svg.lines().filter(|l| l.contains("<polyline")) {
            let points = line.matches(',').count();
            assert!(points <= MAX_TRACE_POINTS, "{points} points");
        }
    }

    #[test]
    fn palette_roles_are_distinct() {
        let roles = [COLOR_REFERENCE, COLOR_USUAL, COLOR_FIRST, COLOR_SECOND];
        for (i, a) in roles.iter().enumerate() {
            for b in &roles[i + 1..] {
                assert_ne!(color(*a), color(*b));
            }
        }
        assert_eq!(color(PALETTE.len() + 2), color(2));
    }

    /// A monospace measure: 0.5 × size px per character.
    fn mono(t: &str, size: f64) -> u32 {
        (t.chars().count() as f64 * size * 0.5).ceil() as u32
    }

    #[test]
    fn titles_fit_by_shrinking_then_wrapping_then_shortening() {
        let sizes = FIGURE_TITLE_SIZES;
        // Fits at the largest size.
        let f = fit_text(&mono, "short", 100, &sizes);
        assert_eq!((f.size, f.lines.clone()), (22.0, vec!["short".to_string()]));
        // 40 chars: 440 px at 22, 360 px at 18: one line at the first size that fits.
        let t = "a".repeat(19) + " " + &"b".repeat(20);
        let f = fit_text(&mono, &t, 380, &sizes);
        assert_eq!(f.size, 19.0);
        assert!(mono(&f.lines[0], f.size) <= 380);
        // Too long for one line even at 18: two lines, broken at the space, each fitting.
        let f = fit_text(&mono, &t, 200, &sizes);
        assert_eq!(f.lines, vec!["a".repeat(19), "b".repeat(20)]);
        assert!(f.lines.iter().all(|l| mono(l, f.size) <= 200));
        assert_eq!(f.lines.join(" "), t);
        // No space and too long: shortened with an ellipsis, within the width.
        let long = "x".repeat(200);
        let f = fit_text(&mono, &long, 300, &sizes);
        assert_eq!(f.lines.len(), 1);
        assert!(f.lines[0].ends_with('…') && mono(&f.lines[0], f.size) <= 300);
        assert!(
            mono(&(f.lines[0].clone() + "x"), f.size) > 300,
            "shortened too much"
        );
    }

    #[test]
    fn legend_rows_wrap_and_never_exceed_the_width() {
        let widths = [100, 120, 90, 300, 50];
        let (pos, rows) = legend_rows(&widths, 400);
        assert_eq!(rows, 2); // 100 + 120 + 90 (+ gaps) = 342; then 300 + 50
        for (i, &(row, x)) in pos.iter().enumerate() {
            assert!(x + widths[i] <= 400, "entry {i} at {x}");
            // Entries on one row do not overlap.
            for (j, &(row2, x2)) in pos.iter().enumerate().skip(i + 1) {
                if row == row2 {
                    assert!(x + widths[i] + LEGEND_GAP <= x2, "{i} and {j}");
                }
            }
        }
        assert_eq!(legend_rows(&[], 400).1, 0);
        // An entry wider than the strip gets a row of its own.
        assert_eq!(legend_rows(&[500, 10], 400).1, 2);
    }
}
