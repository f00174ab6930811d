//! Figures, each written as SVG and PNG: line plots, log–log plots, journal orbits.
//!
//! ```text
//! line_plot(stem, axes, series)     y against x, linear axes          → stem.svg, stem.png
//! loglog_plot(stem, axes, series)   y against x, log10 axes (x, y > 0)
//! orbit_plot(stem, title, ex, ey)   (e_x/c, e_y/c) inside the unit clearance circle ε = 1,
//!                                   equal aspect: x_span / width_px = y_span / height_px
//! orbits_plot(stem, title, series)  several orbits in one circle
//! series i: colour COLORS[i mod 10]; with markers (LinePoints, DashedPoints) marker
//!          MARKERS[i mod 8], so no two of the first 40 series look alike; Dashed and
//!          DashedPoints dashed, every other line solid
//! legend:  outside the data: a column right of the plot (line plots, log–log plots, panels),
//!          a row under the circle (orbits); each entry shows the series' line and marker
//! text:    no underscore (the bitmap text renderer leaves a gap before it): names are
//!          written out in words ([`plain`] turns identifiers such as case names into text)
//! PNG: 8-bit palette of the 256 most frequent colours of the rendered image, every other
//!      colour (anti-aliasing shades) mapped to its nearest palette entry (RGB distance);
//!      deflate at best compression: a quarter of the true-colour file or less
//! ```
//!
//! Text is drawn with DejaVu Sans, shipped in `assets/` (Bitstream Vera licence, see
//! `assets/DejaVuSans-LICENSE.txt`) and registered with plotters' `ab_glyph` renderer, so no
//! system font library is needed. Both files are written atomically. Source:
//! docs/outputs.md ("`lash run CASE`", "`lash work-precision CASE`", "`lash plot RUN_DIR
//! COLUMN…`").

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::register_font;

use crate::error::Error;
use crate::store::io;

/// The font all text is drawn with.
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Font family name every text style of this module uses.
const FAMILY: &str = "sans-serif";

/// Size of line and log–log figures, px.
pub const FIGURE_SIZE: (u32, u32) = (1000, 650);
/// Size of orbit figures, px.
pub const ORBIT_SIZE: (u32, u32) = (760, 760);

/// Tableau 10 colours, given to series in order.
const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Registers the shipped font with plotters once.
fn ensure_font() -> Result<(), Error> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(Error::Internal(
            "plot: the shipped font does not load".into(),
        ))
    }
}

/// How a series is drawn.
///
/// ```text
/// Line ──   Dashed - -   Points ·   LinePoints ▪─▲─◆ (its own marker)   DashedPoints ▪ - ▲
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeriesStyle {
    /// A solid line.
    Line,
    /// A dashed line (a reference, such as the ideal mechanism).
    Dashed,
    /// Markers only.
    Points,
    /// A line with markers, each series its own marker (work–precision curves).
    LinePoints,
    /// A dashed line with markers, each series its own marker (work–precision curves of a
    /// second family, such as the stiff methods).
    DashedPoints,
}

impl SeriesStyle {
    fn dashed(self) -> bool {
        matches!(self, SeriesStyle::Dashed | SeriesStyle::DashedPoints)
    }

    fn marked(self) -> bool {
        matches!(self, SeriesStyle::LinePoints | SeriesStyle::DashedPoints)
    }

    fn line(self) -> bool {
        !matches!(self, SeriesStyle::Points)
    }
}

/// Number of marker shapes: filled circle, square, triangle, diamond; open circle, square;
/// cross; downward triangle.
pub const MARKERS: usize = 8;

/// An identifier (a case name, a file stem) as text for a figure: underscores become spaces.
pub fn plain(name: &str) -> String {
    name.replace('_', " ")
}

/// One named series of a figure.
///
/// ```text
/// points (x_i, y_i), i = 0..n, equal lengths, finite (and > 0 on log axes)
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug)]
pub struct Series<'a> {
    /// Legend entry.
    pub name: &'a str,
    /// Abscissae.
    pub x: &'a [f64],
    /// Ordinates.
    pub y: &'a [f64],
    /// Line, dashed, points.
    pub style: SeriesStyle,
}

/// Title and axis labels.
///
/// ```text
/// title above; x_label below the x axis; y_label left of the y axis
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug)]
pub struct Axes<'a> {
    /// Figure title.
    pub title: &'a str,
    /// x axis label (with unit).
    pub x_label: &'a str,
    /// y axis label (with unit).
    pub y_label: &'a str,
}

/// The two files a figure function wrote.
///
/// ```text
/// stem → (stem.svg, stem.png)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq)]
pub struct Written {
    /// The SVG file.
    pub svg: PathBuf,
    /// The PNG file.
    pub png: PathBuf,
}

/// Something that draws itself on any plotters backend.
trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Renders `fig` to `stem.svg` and `stem.png` (atomically), both of `size` pixels.
fn render<F: Figure>(stem: &Path, size: (u32, u32), fig: &F) -> Result<Written, Error> {
    ensure_font()?;
    // Appended, not set: a stem may hold dots (`plot_rod.theta`).
    let with = |ext: &str| {
        let mut name = stem.as_os_str().to_os_string();
        name.push(ext);
        PathBuf::from(name)
    };
    let (svg, png) = (with(".svg"), with(".png"));
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        fig.draw(&root).map_err(|e| plot_err(&svg, e))?;
        root.present().map_err(|e| plot_err(&svg, e.to_string()))?;
    }
    io::write_atomic(&svg, text.as_bytes())?;
    let mut rgb = vec![0u8; 3 * size.0 as usize * size.1 as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        fig.draw(&root).map_err(|e| plot_err(&png, e))?;
        root.present().map_err(|e| plot_err(&png, e.to_string()))?;
    }
    let bytes = palette_png(&rgb, size).map_err(|e| plot_err(&png, e))?;
    io::write_atomic(&png, &bytes)?;
    Ok(Written { svg, png })
}

/// Encodes an RGB image as an 8-bit palette PNG (module doc).
pub fn palette_png(rgb: &[u8], size: (u32, u32)) -> Result<Vec<u8>, String> {
    use std::collections::HashMap;
    let mut counts: HashMap<[u8; 3], u32> = HashMap::new();
    for px in rgb.chunks_exact(3) {
        *counts.entry([px[0], px[1], px[2]]).or_default() += 1;
    }
    let mut colours: Vec<([u8; 3], u32)> = counts.into_iter().collect();
    colours.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let palette: Vec<[u8; 3]> = colours.iter().take(256).map(|c| c.0).collect();
    let dist = |a: [u8; 3], b: [u8; 3]| -> u32 {
        (0..3)
            .map(|k| (i32::from(a[k]) - i32::from(b[k])).pow(2) as u32)
            .sum()
    };
    let index: HashMap<[u8; 3], u8> = colours
        .iter()
        .map(|&(c, _)| {
            let i = (0..palette.len())
                .min_by_key(|&i| dist(c, palette[i]))
                .unwrap_or(0);
            (c, i as u8)
        })
        .collect();
    let data: Vec<u8> = rgb
        .chunks_exact(3)
        .map(|px| index[&[px[0], px[1], px[2]]])
        .collect();
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, size.0, size.1);
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_palette(palette.concat());
        enc.set_compression(png::Compression::Best);
        enc.set_filter(png::FilterType::NoFilter);
        let mut w = enc.write_header().map_err(|e| e.to_string())?;
        w.write_image_data(&data).map_err(|e| e.to_string())?;
    }
    Ok(out)
}

fn plot_err(path: &Path, e: String) -> Error {
    Error::Internal(format!("plot {}: {e}", path.display()))
}

/// Checks lengths and finiteness (and positivity for log axes); returns the data bounds
/// (x_min, x_max, y_min, y_max).
fn bounds(series: &[Series<'_>], log: bool) -> Result<(f64, f64, f64, f64), Error> {
    bounds_xy(series, log, log)
}

/// [`bounds`] with the log check per axis.
fn bounds_xy(
    series: &[Series<'_>],
    log_x: bool,
    log_y: bool,
) -> Result<(f64, f64, f64, f64), Error> {
    let mut b = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for s in series {
        if s.x.len() != s.y.len() {
            return Err(Error::Internal(format!(
                "plot: series '{}' has {} x and {} y values",
                s.name,
                s.x.len(),
                s.y.len()
            )));
        }
        for (&x, &y) in s.x.iter().zip(s.y) {
            if !(x.is_finite() && y.is_finite()) {
                return Err(Error::Internal(format!(
                    "plot: series '{}' has a non-finite point ({x}, {y})",
                    s.name
                )));
            }
            if (log_x && !(x > 0.0)) || (log_y && !(y > 0.0)) {
                return Err(Error::Internal(format!(
                    "plot: series '{}' has a point ({x:e}, {y:e}) that a log axis cannot show",
                    s.name
                )));
            }
            b = (b.0.min(x), b.1.max(x), b.2.min(y), b.3.max(y));
        }
    }
    if !b.0.is_finite() {
        return Err(Error::Internal("plot: no data".into()));
    }
    Ok(b)
}

/// A linear axis range around [lo, hi] with 5 % padding (a unit-free pad for a flat one).
pub fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else if lo != 0.0 {
        0.05 * lo.abs()
    } else {
        1.0
    };
    (lo - pad, hi + pad)
}

/// A log axis range around [lo, hi] (both > 0), padded by 5 % of the decades (a factor 2 for
/// a flat one).
pub fn padded_log(lo: f64, hi: f64) -> (f64, f64) {
    let f = if hi > lo { (hi / lo).powf(0.05) } else { 2.0 };
    (lo / f, hi * f)
}

/// The axis ranges of a square-unit plot of half-width `r` in a plotting area of
/// `width_px` × `height_px`: the shorter side spans [−r, r], the longer one proportionally more.
pub fn equal_aspect(r: f64, width_px: u32, height_px: u32) -> (f64, f64) {
    let (w, h) = (width_px.max(1) as f64, height_px.max(1) as f64);
    if w >= h {
        (r * w / h, r)
    } else {
        (r, r * h / w)
    }
}

fn style_of(i: usize) -> RGBColor {
    COLORS[i % COLORS.len()]
}

/// Tick label on a linear axis spanning `span`: values below 1e-9·span print as 0 (rounding
/// noise such as −2.2e-16), others in plain form, or scientific when tiny or huge.
fn tick(v: f64, span: f64) -> String {
    let a = v.abs();
    if a <= 1e-9 * span.abs() || v == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}

/// Tick label on a log axis: `1e-4` for powers of ten, else one significant digit (`3e-4`).
fn tick_log(v: f64) -> String {
    let e = v.log10().round();
    if (v / 10f64.powf(e) - 1.0).abs() < 1e-9 {
        format!("1e{e}")
    } else {
        format!("{v:.0e}")
    }
}

struct XyFigure<'a> {
    axes: Axes<'a>,
    series: &'a [Series<'a>],
    log: bool,
    bounds: (f64, f64, f64, f64),
}

/// Draws marker `kind` (mod [`MARKERS`]) of colour `c` at `at`, in any coordinates.
fn draw_marker<DB, CT>(
    area: &DrawingArea<DB, CT>,
    at: CT::From,
    kind: usize,
    c: RGBColor,
) -> Result<(), String>
where
    DB: DrawingBackend,
    CT: plotters::coord::CoordTranslate,
    CT::From: Clone,
{
    let r = 5i32;
    let (fill, open) = (c.filled(), c.stroke_width(2));
    let res = match kind % MARKERS {
        0 => area.draw(&(EmptyElement::at(at) + Circle::new((0, 0), r, fill))),
        1 => area.draw(
            &(EmptyElement::at(at) + Rectangle::new([(-r + 1, -r + 1), (r - 1, r - 1)], fill)),
        ),
        2 => area.draw(
            &(EmptyElement::at(at)
                + Polygon::new(vec![(0, -r - 1), (r + 1, r), (-r - 1, r)], fill)),
        ),
        3 => area.draw(
            &(EmptyElement::at(at)
                + Polygon::new(vec![(0, -r - 1), (r + 1, 0), (0, r + 1), (-r - 1, 0)], fill)),
        ),
        4 => area.draw(&(EmptyElement::at(at) + Circle::new((0, 0), r, open))),
        5 => area.draw(
            &(EmptyElement::at(at)
                + PathElement::new(vec![(-r, -r), (r, -r), (r, r), (-r, r), (-r, -r)], open)),
        ),
        6 => area.draw(&(EmptyElement::at(at) + Cross::new((0, 0), r, open))),
        _ => area.draw(
            &(EmptyElement::at(at)
                + Polygon::new(vec![(0, r + 1), (r + 1, -r), (-r - 1, -r)], fill)),
        ),
    };
    res.map_err(|e| e.to_string())
}

/// One entry of a legend: the name and how its series looks.
struct Entry {
    name: String,
    color: RGBColor,
    dashed: bool,
    line: bool,
    /// The marker kind, if the series has markers.
    marker: Option<usize>,
    /// Small dots (Points).
    dots: bool,
    width: u32,
}

fn entries(series: &[Series<'_>]) -> Vec<Entry> {
    series
        .iter()
        .enumerate()
        .map(|(i, s)| Entry {
            name: s.name.to_string(),
            color: style_of(i),
            dashed: s.style.dashed(),
            line: s.style.line(),
            marker: s.style.marked().then_some(i),
            dots: s.style == SeriesStyle::Points,
            width: 2,
        })
        .collect()
}

/// Legend font size, px.
const LEGEND_FONT: u32 = 15;
/// Height of one legend entry, px.
const LEGEND_ROW: i32 = 24;
/// Length of the line sample of a legend entry, px.
const LEGEND_SAMPLE: i32 = 40;

/// Width of a legend column for these entries, px (0 without entries).
fn legend_width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, entries: &[Entry]) -> u32 {
    let font: TextStyle<'_> = (FAMILY, LEGEND_FONT).into_font().into();
    entries
        .iter()
        .map(|e| {
            area.estimate_text_size(&e.name, &font)
                .map_or(8 * e.name.len() as u32, |s| s.0)
        })
        .max()
        .map_or(0, |w| w + LEGEND_SAMPLE as u32 + 36)
}

/// Draws one legend entry with its sample starting at pixel (x, y) (y the line's middle).
fn draw_entry<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    e: &Entry,
    x: i32,
    y: i32,
) -> Result<(), String> {
    let style = e.color.stroke_width(e.width);
    if e.line {
        if e.dashed {
            for k in 0..3 {
                let a = x + k * 15;
                area.draw(&PathElement::new(
                    vec![(a, y), ((a + 9).min(x + LEGEND_SAMPLE), y)],
                    style,
                ))
                .map_err(|e| e.to_string())?;
            }
        } else {
            area.draw(&PathElement::new(
                vec![(x, y), (x + LEGEND_SAMPLE, y)],
                style,
            ))
            .map_err(|e| e.to_string())?;
        }
    }
    if let Some(k) = e.marker {
        draw_marker(area, (x + LEGEND_SAMPLE / 2, y), k, e.color)?;
    }
    if e.dots {
        area.draw(&Circle::new(
            (x + LEGEND_SAMPLE / 2, y),
            3,
            e.color.filled(),
        ))
        .map_err(|e| e.to_string())?;
    }
    area.draw(&Text::new(
        e.name.clone(),
        (x + LEGEND_SAMPLE + 8, y - LEGEND_FONT as i32 / 2 - 1),
        (FAMILY, LEGEND_FONT).into_font(),
    ))
    .map_err(|e| e.to_string())
}

/// A legend column in `area` (entries top down, from `top` px).
fn legend_column<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    top: i32,
) -> Result<(), String> {
    for (k, e) in entries.iter().enumerate() {
        draw_entry(area, e, 10, top + LEGEND_ROW / 2 + k as i32 * LEGEND_ROW)?;
    }
    Ok(())
}

/// Splits `area` into the plot (left) and a legend column (right) wide enough for `series`;
/// draws the legend, aligned with the plot's top at `top` px; returns the plot's area.
fn with_legend_column<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    series: &[Series<'_>],
    top: i32,
) -> Result<DrawingArea<DB, Shift>, String> {
    let es = entries(series);
    let w = legend_width(area, &es);
    if w == 0 {
        return Ok(area.clone());
    }
    let (total, _) = area.dim_in_pixel();
    let (plot, legend) = area.split_horizontally(total.saturating_sub(w) as i32);
    legend_column(&legend, &es, top)?;
    Ok(plot)
}

fn draw_series<'a, DB, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    series: &[Series<'_>],
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: plotters::coord::ranged1d::Ranged<ValueType = f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>,
{
    for (i, s) in series.iter().enumerate() {
        let c = style_of(i);
        let pts: Vec<(f64, f64)> = s.x.iter().copied().zip(s.y.iter().copied()).collect();
        let line = ShapeStyle::from(&c).stroke_width(2);
        if s.style.line() {
            if s.style.dashed() {
                chart
                    .draw_series(DashedLineSeries::new(pts.clone(), 10, 6, line))
                    .map_err(|e| e.to_string())?;
            } else {
                chart
                    .draw_series(LineSeries::new(pts.clone(), line))
                    .map_err(|e| e.to_string())?;
            }
        } else {
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(|e| e.to_string())?;
        }
        if s.style.marked() {
            let area = chart.plotting_area();
            for &p in &pts {
                draw_marker(area, p, i, c)?;
            }
        }
    }
    Ok(())
}

impl Figure for XyFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let titled = root
            .margin(10, 0, 0, 0)
            .titled(self.axes.title, (FAMILY, 22))
            .map_err(|e| e.to_string())?;
        let plot = with_legend_column(&titled, self.series, 15)?;
        let (x0, x1, y0, y1) = self.bounds;
        let mut b = ChartBuilder::on(&plot);
        b.margin(15).x_label_area_size(50).y_label_area_size(85);
        if self.log {
            let fmt = |v: &f64| tick_log(*v);
            let (xa, xb) = padded_log(x0, x1);
            let (ya, yb) = padded_log(y0, y1);
            let mut chart = b
                .build_cartesian_2d((xa..xb).log_scale(), (ya..yb).log_scale())
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc(self.axes.x_label)
                .y_desc(self.axes.y_label)
                .x_label_formatter(&fmt)
                .y_label_formatter(&fmt)
                .label_style((FAMILY, 15))
                .axis_desc_style((FAMILY, 17))
                .draw()
                .map_err(|e| e.to_string())?;
            draw_series(&mut chart, self.series)
        } else {
            let (xa, xb) = if x1 > x0 { (x0, x1) } else { padded(x0, x1) };
            let (ya, yb) = padded(y0, y1);
            let fx = |v: &f64| tick(*v, xb - xa);
            let fy = |v: &f64| tick(*v, yb - ya);
            let mut chart = b
                .build_cartesian_2d(xa..xb, ya..yb)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc(self.axes.x_label)
                .y_desc(self.axes.y_label)
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .label_style((FAMILY, 15))
                .axis_desc_style((FAMILY, 17))
                .draw()
                .map_err(|e| e.to_string())?;
            draw_series(&mut chart, self.series)
        }
    }
}

/// Several named series against one x axis (for example crank angle in degrees), linear axes.
/// Writes `stem.svg` and `stem.png`.
pub fn line_plot(stem: &Path, axes: &Axes<'_>, series: &[Series<'_>]) -> Result<Written, Error> {
    let fig = XyFigure {
        axes: *axes,
        series,
        log: false,
        bounds: bounds(series, false)?,
    };
    render(stem, FIGURE_SIZE, &fig)
}

/// Several named series on log–log axes (work–precision: error against cost). Every x and y
/// must be > 0. Writes `stem.svg` and `stem.png`.
pub fn loglog_plot(stem: &Path, axes: &Axes<'_>, series: &[Series<'_>]) -> Result<Written, Error> {
    let fig = XyFigure {
        axes: *axes,
        series,
        log: true,
        bounds: bounds(series, true)?,
    };
    render(stem, FIGURE_SIZE, &fig)
}

/// One panel of [`panels_plot`].
///
/// ```text
/// title above the panel; y against x; x linear; y linear or log10 (then every y > 0)
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug)]
pub struct Panel<'a> {
    /// The panel's title and axis labels.
    pub axes: Axes<'a>,
    /// Its series.
    pub series: &'a [Series<'a>],
    /// Whether the y axis is log10.
    pub log_y: bool,
}

/// Width of a panel figure, px.
pub const PANEL_WIDTH: u32 = 1000;
/// Height of one panel, px.
pub const PANEL_HEIGHT: u32 = 400;

struct PanelsFigure<'a> {
    title: &'a str,
    panels: &'a [Panel<'a>],
    bounds: Vec<(f64, f64, f64, f64)>,
}

impl Figure for PanelsFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let area = root
            .margin(10, 0, 0, 0)
            .titled(self.title, (FAMILY, 24))
            .map_err(|e| e.to_string())?;
        let parts = area.split_evenly((self.panels.len(), 1));
        // One legend width for every panel, so that their x axes line up.
        let all: Vec<Series<'_>> = self
            .panels
            .iter()
            .flat_map(|p| p.series.iter().copied())
            .collect();
        let w = legend_width(root, &entries(&all));
        for ((p, part), &(x0, x1, y0, y1)) in self.panels.iter().zip(&parts).zip(&self.bounds) {
            let (xa, xb) = if x1 > x0 { (x0, x1) } else { padded(x0, x1) };
            let fx = |v: &f64| tick(*v, xb - xa);
            let (total, _) = part.dim_in_pixel();
            let (plot, legend) = part.split_horizontally(total.saturating_sub(w) as i32);
            legend_column(&legend, &entries(p.series), 40)?;
            let mut b = ChartBuilder::on(&plot);
            b.caption(p.axes.title, (FAMILY, 18))
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(85);
            if p.log_y {
                let (ya, yb) = padded_log(y0, y1);
                let fy = |v: &f64| tick_log(*v);
                let mut chart = b
                    .build_cartesian_2d(xa..xb, (ya..yb).log_scale())
                    .map_err(|e| e.to_string())?;
                chart
                    .configure_mesh()
                    .x_desc(p.axes.x_label)
                    .y_desc(p.axes.y_label)
                    .x_label_formatter(&fx)
                    .y_label_formatter(&fy)
                    .label_style((FAMILY, 14))
                    .axis_desc_style((FAMILY, 16))
                    .draw()
                    .map_err(|e| e.to_string())?;
                draw_series(&mut chart, p.series)?;
            } else {
                let (ya, yb) = padded(y0, y1);
                let fy = |v: &f64| tick(*v, yb - ya);
                let mut chart = b
                    .build_cartesian_2d(xa..xb, ya..yb)
                    .map_err(|e| e.to_string())?;
                chart
                    .configure_mesh()
                    .x_desc(p.axes.x_label)
                    .y_desc(p.axes.y_label)
                    .x_label_formatter(&fx)
                    .y_label_formatter(&fy)
                    .label_style((FAMILY, 14))
                    .axis_desc_style((FAMILY, 16))
                    .draw()
                    .map_err(|e| e.to_string())?;
                draw_series(&mut chart, p.series)?;
            }
        }
        Ok(())
    }
}

/// Panels stacked vertically under one title, each with its own axes (x linear, y linear or
/// log10): quantities of different units against one abscissa (stiffness: |λ| and the RK4
/// step limit against crank angle). Writes `stem.svg` and `stem.png`, [`PANEL_WIDTH`] wide and
/// [`PANEL_HEIGHT`] per panel.
pub fn panels_plot(stem: &Path, title: &str, panels: &[Panel<'_>]) -> Result<Written, Error> {
    if panels.is_empty() {
        return Err(Error::Internal("plot: no panels".into()));
    }
    let bounds = panels
        .iter()
        .map(|p| bounds_xy(p.series, false, p.log_y))
        .collect::<Result<Vec<_>, Error>>()?;
    let fig = PanelsFigure {
        title,
        panels,
        bounds,
    };
    let h = PANEL_HEIGHT * panels.len() as u32 + 40;
    render(stem, (PANEL_WIDTH, h), &fig)
}

struct OrbitFigure<'a> {
    title: &'a str,
    /// (label, e_x/c, e_y/c) per orbit.
    orbits: &'a [Series<'a>],
    r: f64,
}

impl Figure for OrbitFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let area = root
            .margin(10, 0, 0, 0)
            .titled(self.title, (FAMILY, 24))
            .map_err(|e| e.to_string())?;
        // The legend: a row under the plot, outside the circle.
        let mut es = vec![Entry {
            name: "clearance circle, ε = 1".into(),
            color: BLACK,
            dashed: false,
            line: true,
            marker: None,
            dots: false,
            width: 2,
        }];
        for (k, o) in self.orbits.iter().enumerate() {
            es.push(Entry {
                name: o.name.to_string(),
                color: style_of(k),
                dashed: false,
                line: o.style != SeriesStyle::Points,
                marker: None,
                dots: o.style == SeriesStyle::Points,
                width: 2,
            });
        }
        let (_, full_h) = area.dim_in_pixel();
        let rows = es.len().div_ceil(2) as u32;
        let (area, legend) =
            area.split_vertically(full_h.saturating_sub(rows * LEGEND_ROW as u32 + 8) as i32);
        let (lw, _) = legend.dim_in_pixel();
        for (k, e) in es.iter().enumerate() {
            let col = (k % 2) as i32;
            let row = (k / 2) as i32;
            draw_entry(
                &legend,
                e,
                20 + col * (lw as i32 / 2),
                LEGEND_ROW / 2 + row * LEGEND_ROW,
            )?;
        }
        let (margin, x_area, y_area) = (15u32, 50u32, 80u32);
        let (w, h) = area.dim_in_pixel();
        let pw = w.saturating_sub(2 * margin + y_area);
        let ph = h.saturating_sub(2 * margin + x_area);
        let (rx, ry) = equal_aspect(self.r, pw, ph);
        let mut chart = ChartBuilder::on(&area)
            .margin(margin)
            .x_label_area_size(x_area)
            .y_label_area_size(y_area)
            .build_cartesian_2d(-rx..rx, -ry..ry)
            .map_err(|e| e.to_string())?;
        let (fx, fy) = (|v: &f64| tick(*v, 2.0 * rx), |v: &f64| tick(*v, 2.0 * ry));
        chart
            .configure_mesh()
            .x_desc("eccentricity e/c, x component")
            .y_desc("eccentricity e/c, y component")
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .label_style((FAMILY, 15))
            .axis_desc_style((FAMILY, 17))
            .draw()
            .map_err(|e| e.to_string())?;
        let circle: Vec<(f64, f64)> = (0..=360)
            .map(|k| {
                let a = (k as f64).to_radians();
                (a.cos(), a.sin())
            })
            .collect();
        chart
            .draw_series(LineSeries::new(circle, BLACK.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        for (k, o) in self.orbits.iter().enumerate() {
            let c = style_of(k);
            let orbit: Vec<(f64, f64)> = o.x.iter().copied().zip(o.y.iter().copied()).collect();
            match o.style {
                SeriesStyle::Points => chart
                    .draw_series(orbit.iter().map(|&p| Circle::new(p, 3, c.filled())))
                    .map_err(|e| e.to_string())?,
                _ => chart
                    .draw_series(LineSeries::new(orbit, ShapeStyle::from(&c).stroke_width(1)))
                    .map_err(|e| e.to_string())?,
            };
        }
        Ok(())
    }
}

/// The journal centre's orbit (e_x/c, e_y/c) inside the unit clearance circle, equal aspect.
/// The view shows at least |e|/c ≤ 1.08, more if the journal penetrates further.
/// Writes `stem.svg` and `stem.png`.
pub fn orbit_plot(stem: &Path, title: &str, ex: &[f64], ey: &[f64]) -> Result<Written, Error> {
    orbits_plot(
        stem,
        title,
        &[Series {
            name: "journal centre",
            x: ex,
            y: ey,
            style: SeriesStyle::Line,
        }],
    )
}

/// Several orbits (series x = e_x/c, y = e_y/c, named in the legend) in one clearance circle,
/// as [`orbit_plot`]. A series of style [`SeriesStyle::Points`] is drawn as markers (a
/// Poincaré section), every other style as a thin line.
pub fn orbits_plot(stem: &Path, title: &str, orbits: &[Series<'_>]) -> Result<Written, Error> {
    bounds(orbits, false)?;
    let r = orbits
        .iter()
        .flat_map(|o| o.x.iter().zip(o.y).map(|(x, y)| x.hypot(*y)))
        .fold(1.0, f64::max)
        * 1.08;
    render(stem, ORBIT_SIZE, &OrbitFigure { title, orbits, r })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decodes a PNG; returns (width, height, RGB(A) bytes, bytes per pixel).
    fn decode(p: &Path) -> (u32, u32, Vec<u8>, usize) {
        let mut dec = png::Decoder::new(std::fs::File::open(p).unwrap());
        dec.set_transformations(png::Transformations::EXPAND);
        let mut r = dec.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size()];
        let info = r.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf, info.color_type.samples())
    }

    #[test]
    fn palette_png_keeps_the_frequent_colours_exactly() {
        // 60 frequent colours (10 pixels each) and 300 rare shades one step off them (more
        // colours than a palette holds): the frequent ones survive exactly, each rare one maps
        // to a colour at most one step away.
        let (w, h) = (900u32, 1u32);
        let base = |k: usize| [(4 * k) as u8, (255 - 4 * k) as u8, 100];
        let mut rgb = Vec::new();
        for k in 0..60 {
            for _ in 0..10 {
                rgb.extend_from_slice(&base(k));
            }
        }
        for j in 0..300 {
            let mut c = base(j % 60);
            c[2] = 101 + (j / 60) as u8 % 2;
            c[0] += (j / 120) as u8;
            rgb.extend_from_slice(&c);
        }
        assert_eq!(rgb.len(), (3 * w * h) as usize);
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("p.png");
        std::fs::write(&p, palette_png(&rgb, (w, h)).unwrap()).unwrap();
        let img = decode(&p);
        assert_eq!((img.0, img.1, img.3), (w, h, 3));
        assert_eq!(&img.2[..1800], &rgb[..1800], "frequent colours exact");
        let worst = img.2[1800..]
            .chunks(3)
            .zip(rgb[1800..].chunks(3))
            .map(|(a, b)| {
                (0..3)
                    .map(|k| (i32::from(a[k]) - i32::from(b[k])).abs())
                    .sum::<i32>()
            })
            .max()
            .unwrap();
        assert!(worst <= 3, "{worst}");
    }

    /// Number of pixels darker than light grey in rows [y0, y1).
    fn dark_pixels(img: &(u32, u32, Vec<u8>, usize), y0: u32, y1: u32) -> usize {
        let (w, _, buf, bpp) = img;
        (y0..y1)
            .flat_map(|y| (0..*w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let i = ((y * w + x) as usize) * bpp;
                buf[i..i + 3].iter().map(|&v| v as u32).sum::<u32>() < 3 * 160
            })
            .count()
    }

    fn demo_series() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let deg: Vec<f64> = (0..=360).map(|k| k as f64).collect();
        let a: Vec<f64> = deg.iter().map(|d| -3.86 * d.to_radians().cos()).collect();
        let ideal: Vec<f64> = deg.iter().map(|d| -3.80 * d.to_radians().cos()).collect();
        (deg, a, ideal)
    }

    #[test]
    fn line_plot_writes_svg_and_png_with_text() {
        let d = tempfile::tempdir().unwrap();
        let (deg, a, ideal) = demo_series();
        let w = line_plot(
            &d.path().join("slider_acc"),
            &Axes {
                title: "Slider acceleration, 150 rpm",
                x_label: "crank angle θ, °",
                y_label: "ẍ, m/s²",
            },
            &[
                Series {
                    name: "lash",
                    x: &deg,
                    y: &a,
                    style: SeriesStyle::Line,
                },
                Series {
                    name: "ideal",
                    x: &deg,
                    y: &ideal,
                    style: SeriesStyle::Dashed,
                },
            ],
        )
        .unwrap();
        let svg = std::fs::read_to_string(&w.svg).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("Slider acceleration, 150 rpm"));
        assert!(svg.contains("crank angle θ, °") && svg.contains("\nideal\n"));
        let img = decode(&w.png);
        assert_eq!((img.0, img.1), FIGURE_SIZE);
        // The title band (above the plot) holds the caption's glyphs and nothing else.
        assert!(dark_pixels(&img, 0, 40) > 200, "no title text rendered");
        // The curves: many dark or coloured pixels overall.
        assert!(dark_pixels(&img, 40, FIGURE_SIZE.1) > 5000);
        // No temporary file left behind.
        let n = std::fs::read_dir(d.path()).unwrap().count();
        assert_eq!(n, 2);
    }

    #[test]
    fn loglog_plot_accepts_positive_data_only() {
        let d = tempfile::tempdir().unwrap();
        let cost = [1e3, 1e4, 1e5];
        let err = [1e-3, 1e-6, 1e-9];
        let w = loglog_plot(
            &d.path().join("wp"),
            &Axes {
                title: "Work–precision",
                x_label: "RHS evaluations",
                y_label: "error",
            },
            &[Series {
                name: "dopri54",
                x: &cost,
                y: &err,
                style: SeriesStyle::LinePoints,
            }],
        )
        .unwrap();
        let img = decode(&w.png);
        assert_eq!((img.0, img.1), FIGURE_SIZE);
        assert!(std::fs::read_to_string(&w.svg).unwrap().contains("dopri54"));
        let zero = [0.0, 1e-6, 1e-9];
        let e = loglog_plot(
            &d.path().join("bad"),
            &Axes {
                title: "",
                x_label: "",
                y_label: "",
            },
            &[Series {
                name: "s",
                x: &cost,
                y: &zero,
                style: SeriesStyle::Points,
            }],
        )
        .unwrap_err();
        assert!(e.to_string().contains("log axis"), "{e}");
        assert!(!d.path().join("bad.png").exists() && !d.path().join("bad.svg").exists());
    }

    #[test]
    fn orbit_plot_is_square_and_shows_the_circle() {
        let d = tempfile::tempdir().unwrap();
        let th: Vec<f64> = (0..2001).map(|k| k as f64 * 0.01).collect();
        let ex: Vec<f64> = th
            .iter()
            .map(|t| 0.6 * t.cos() + 0.1 * (3.0 * t).sin())
            .collect();
        let ey: Vec<f64> = th.iter().map(|t| 0.6 * t.sin()).collect();
        let w = orbit_plot(&d.path().join("orbit"), "Journal orbit", &ex, &ey).unwrap();
        let img = decode(&w.png);
        assert_eq!((img.0, img.1), ORBIT_SIZE);
        assert!(dark_pixels(&img, 0, 35) > 150, "no title text rendered");
        assert!(std::fs::read_to_string(&w.svg)
            .unwrap()
            .contains("clearance circle"));
    }

    #[test]
    fn panels_plot_stacks_log_and_linear_panels() {
        let d = tempfile::tempdir().unwrap();
        let x: Vec<f64> = (0..=72).map(|k| 10.0 * k as f64).collect();
        let rho: Vec<f64> = x
            .iter()
            .map(|a| 1e3 * (2.0 + a.to_radians().cos()))
            .collect();
        let h: Vec<f64> = rho.iter().map(|r| 2.785 / r).collect();
        let a = Axes {
            title: "spectral radius",
            x_label: "crank angle, °",
            y_label: "|λ|, 1/s",
        };
        let b = Axes {
            title: "RK4 limit",
            x_label: "crank angle, °",
            y_label: "h, s",
        };
        let s1 = [Series {
            name: "|λ|max",
            x: &x,
            y: &rho,
            style: SeriesStyle::Line,
        }];
        let s2 = [Series {
            name: "2.785/|λ|",
            x: &x,
            y: &h,
            style: SeriesStyle::Line,
        }];
        let w = panels_plot(
            &d.path().join("st"),
            "Stiffness",
            &[
                Panel {
                    axes: a,
                    series: &s1,
                    log_y: true,
                },
                Panel {
                    axes: b,
                    series: &s2,
                    log_y: false,
                },
            ],
        )
        .unwrap();
        let img = decode(&w.png);
        assert_eq!((img.0, img.1), (PANEL_WIDTH, 2 * PANEL_HEIGHT + 40));
        assert!(dark_pixels(&img, 0, 40) > 100, "no title text rendered");
        // Each panel draws its own axes, labels and curve.
        assert!(dark_pixels(&img, 40, 40 + PANEL_HEIGHT) > 3000);
        assert!(dark_pixels(&img, 40 + PANEL_HEIGHT, 40 + 2 * PANEL_HEIGHT) > 3000);
        let svg = std::fs::read_to_string(&w.svg).unwrap();
        assert!(svg.contains("spectral radius") && svg.contains("RK4 limit"));
        // A log panel refuses y ≤ 0, a linear x axis accepts x = 0.
        let zero = [0.0; 73];
        let bad = [Series {
            name: "z",
            x: &x,
            y: &zero,
            style: SeriesStyle::Line,
        }];
        let e = panels_plot(
            &d.path().join("bad"),
            "t",
            &[Panel {
                axes: a,
                series: &bad,
                log_y: true,
            }],
        )
        .unwrap_err();
        assert!(e.to_string().contains("log axis"), "{e}");
        assert!(panels_plot(&d.path().join("none"), "t", &[]).is_err());
    }

    #[test]
    fn orbits_plot_draws_points_as_markers() {
        let d = tempfile::tempdir().unwrap();
        let ex = [0.1, 0.5, -0.3];
        let ey = [0.2, -0.4, 0.6];
        let w = orbits_plot(
            &d.path().join("sec"),
            "Poincaré section",
            &[Series {
                name: "once per revolution",
                x: &ex,
                y: &ey,
                style: SeriesStyle::Points,
            }],
        )
        .unwrap();
        let svg = std::fs::read_to_string(&w.svg).unwrap();
        // One marker per point, and one in the legend.
        assert_eq!(svg.matches("<circle").count(), 4, "one marker per point");
    }

    #[test]
    fn bad_data_is_refused() {
        let d = tempfile::tempdir().unwrap();
        let ax = Axes {
            title: "t",
            x_label: "x",
            y_label: "y",
        };
        let e = line_plot(
            &d.path().join("a"),
            &ax,
            &[Series {
                name: "s",
                x: &[1.0, 2.0],
                y: &[1.0],
                style: SeriesStyle::Line,
            }],
        )
        .unwrap_err();
        assert!(e.to_string().contains("2 x and 1 y"));
        let e = line_plot(
            &d.path().join("a"),
            &ax,
            &[Series {
                name: "s",
                x: &[1.0],
                y: &[f64::NAN],
                style: SeriesStyle::Line,
            }],
        )
        .unwrap_err();
        assert!(e.to_string().contains("non-finite"));
        assert!(line_plot(&d.path().join("a"), &ax, &[]).is_err());
        assert!(orbit_plot(&d.path().join("o"), "t", &[0.1], &[]).is_err());
    }

    #[test]
    fn ranges() {
        assert_eq!(padded(0.0, 10.0), (-0.5, 10.5));
        assert_eq!(padded(2.0, 2.0), (1.9, 2.1));
        assert_eq!(padded(0.0, 0.0), (-1.0, 1.0));
        let (a, b) = padded_log(1e-8, 1e-4);
        assert!((a.log10() + 8.2).abs() < 1e-12 && (b.log10() + 3.8).abs() < 1e-12);
        // Equal aspect: data units per pixel equal in x and y.
        let (rx, ry) = equal_aspect(1.2, 600, 400);
        assert!((2.0 * rx / 600.0 - 2.0 * ry / 400.0).abs() < 1e-15 && ry == 1.2);
        let (rx, ry) = equal_aspect(1.2, 300, 500);
        assert!((2.0 * rx / 300.0 - 2.0 * ry / 500.0).abs() < 1e-15 && rx == 1.2);
        assert_eq!(tick(0.5, 2.0), "0.5");
        assert_eq!(tick(-2.2e-16, 2.0), "0");
        assert_eq!(tick(1e-6, 1e-5), "1.0e-6");
        assert_eq!(tick(-120.0, 400.0), "-120");
        assert_eq!(tick_log(1e-4), "1e-4");
        assert_eq!(tick_log(1000.0), "1e3");
        assert_eq!(tick_log(3e-4), "3e-4");
    }
}
