//! Data bounds and axis ranges, the frames around plot areas, and the axes drawn with their
//! ticks and labels.

use plotters::coord::combinators::LogCoord;
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Error;

use super::draw::*;
use super::render::*;
use super::style::*;
use super::ticks::*;

/// Checks lengths and finiteness (and positivity for log axes); returns the data bounds
/// (x_min, x_max, y_min, y_max).
pub(super) fn bounds(series: &[Series<'_>], log: bool) -> Result<(f64, f64, f64, f64), Error> {
    bounds_xy(series, log, log)
}

/// [`bounds`] with the log check per axis.
pub(super) fn bounds_xy(
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
pub(crate) fn padded(lo: f64, hi: f64) -> (f64, f64) {
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
pub(crate) fn padded_log(lo: f64, hi: f64) -> (f64, f64) {
    let f = if hi > lo { (hi / lo).powf(0.05) } else { 2.0 };
    (lo / f, hi * f)
}

/// The axis ranges of a square-unit plot of half-width `r` in a plotting area of
/// `width_px` × `height_px`: the shorter side spans [−r, r], the longer one proportionally more.
pub(crate) fn equal_aspect(r: f64, width_px: u32, height_px: u32) -> (f64, f64) {
    let (w, h) = (width_px.max(1) as f64, height_px.max(1) as f64);
    if w >= h {
        (r * w / h, r)
    } else {
        (r, r * h / w)
    }
}

/// How an axes box is laid out: margin, label areas, fonts, line width.
#[derive(Clone, Copy)]
pub(super) struct Frame {
    pub(super) margin: u32,
    pub(super) x_area: u32,
    pub(super) y_area: u32,
    pub(super) label_font: u32,
    pub(super) desc_font: u32,
    pub(super) width: u32,
}

pub(super) const XY_FRAME: Frame = Frame {
    margin: 15,
    x_area: 50,
    y_area: 85,
    label_font: 15,
    desc_font: 17,
    width: 2,
};

pub(super) const PANEL_FRAME: Frame = Frame {
    margin: 12,
    x_area: 45,
    y_area: 85,
    label_font: 14,
    desc_font: 16,
    width: 2,
};

/// The pixel box the plot area of a chart on `area` with `f` gets (a chart built and
/// dropped: building draws nothing without a caption).
pub(super) fn plot_box<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    f: Frame,
) -> Result<PixelRect, String> {
    let probe = ChartBuilder::on(area)
        .margin(f.margin)
        .x_label_area_size(f.x_area)
        .y_label_area_size(f.y_area)
        .build_cartesian_2d(0f64..1f64, 0f64..1f64)
        .map_err(|e| e.to_string())?;
    Ok(rect_of(probe.plotting_area()))
}

/// An axis: its range, whether log10, and its ticks.
pub(super) struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
    ticks: Vec<f64>,
    light: Vec<f64>,
    /// Linear labels with this spacing (None: log labels).
    step: Option<f64>,
}

/// A coordinate with the ticks of this module: `inner` maps values to pixels, `ticks` are
/// its labelled key points and `light` its light grid lines (plotters' own choice of key
/// points is what overlapped and skipped decades).
pub(super) struct Ticked<R: Ranged<ValueType = f64>> {
    inner: R,
    ticks: Vec<f64>,
    light: Vec<f64>,
}

impl<R: Ranged<ValueType = f64>> Ranged for Ticked<R> {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }

    fn axis_pixel_range(&self, limit: (i32, i32)) -> std::ops::Range<i32> {
        self.inner.axis_pixel_range(limit)
    }
}

impl<R: Ranged<ValueType = f64>> ValueFormatter<f64> for Ticked<R> {
    fn format(value: &f64) -> String {
        format!("{value}")
    }
}

impl Axis {
    pub(super) fn linear(&self) -> Ticked<RangedCoordf64> {
        Ticked {
            inner: (self.lo..self.hi).into(),
            ticks: self.ticks.clone(),
            light: self.light.clone(),
        }
    }

    pub(super) fn logarithmic(&self) -> Ticked<LogCoord<f64>> {
        Ticked {
            inner: (self.lo..self.hi).log_scale().into(),
            ticks: self.ticks.clone(),
            light: self.light.clone(),
        }
    }

    pub(super) fn new(
        (lo, hi): (f64, f64),
        log: bool,
        len: f64,
        horizontal: bool,
        measure: &dyn Fn(&str) -> (u32, u32),
    ) -> Axis {
        let (ticks, light, step) = if log {
            log_ticks(lo, hi, len, horizontal, measure)
        } else {
            let (t, l, s) = linear_ticks(lo, hi, len, horizontal, measure);
            (t, l, Some(s))
        };
        Axis {
            lo,
            hi,
            log,
            ticks,
            light,
            step,
        }
    }

    pub(super) fn label(&self, v: f64) -> String {
        if self.log {
            log_label(v, self.step)
        } else {
            tick_at(v, self.step.unwrap_or(self.hi - self.lo))
        }
    }
}

/// One axes box on `area`: the mesh with the ticks of `x` and `y`, the axis labels of
/// `axes`, then `series` drawn into it; its plot area goes into `layout`.
#[allow(clippy::too_many_arguments)]
pub(super) fn axes_box<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    area: &DrawingArea<DB, Shift>,
    f: Frame,
    axes: &Axes<'_>,
    x: &Axis,
    y: &Axis,
    series: &[Series<'_>],
    raster: bool,
    layout: &mut Layout,
) -> Result<(), String> {
    let fx = |v: &f64| x.label(*v);
    let fy = |v: &f64| y.label(*v);
    macro_rules! go {
        ($xr:expr, $yr:expr) => {{
            let mut chart = ChartBuilder::on(area)
                .margin(f.margin)
                .x_label_area_size(f.x_area)
                .y_label_area_size(f.y_area)
                .build_cartesian_2d($xr, $yr)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc(axes.x_label)
                .y_desc(axes.y_label)
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .label_style((FAMILY, f.label_font))
                .axis_desc_style((FAMILY, f.desc_font))
                .draw()
                .map_err(|e| e.to_string())?;
            let r = rect_of(chart.plotting_area());
            layout.plots.push(r);
            let px = to_pixels(&chart, series);
            draw_data(root, r, series, px, f.width, raster)
        }};
    }
    match (x.log, y.log) {
        (false, false) => go!(x.linear(), y.linear()),
        (false, true) => go!(x.linear(), y.logarithmic()),
        (true, false) => go!(x.logarithmic(), y.linear()),
        (true, true) => go!(x.logarithmic(), y.logarithmic()),
    }
}

/// A measure of label text in pixels with the figure's tick font.
pub(super) fn measurer<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    size: u32,
) -> impl Fn(&str) -> (u32, u32) + 'a {
    move |s: &str| {
        let font: TextStyle<'_> = (FAMILY, size).into_font().into();
        area.estimate_text_size(s, &font)
            .unwrap_or((8 * s.chars().count() as u32, size))
    }
}

/// The range of a linear axis over data [lo, hi]: exact ends for lines (x), 5 % padding
/// otherwise or when points or markers sit on the ends (they must fit whole).
pub(super) fn linear_range(lo: f64, hi: f64, pad: bool) -> (f64, f64) {
    if hi > lo && !pad {
        (lo, hi)
    } else {
        padded(lo, hi)
    }
}

pub(super) fn has_marks(series: &[Series<'_>]) -> bool {
    series.iter().any(|s| !s.style.line() || s.style.marked())
}
