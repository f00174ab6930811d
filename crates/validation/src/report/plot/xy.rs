//! Line plots and log–log plots: y against x with a legend column.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Error;

use super::axes::*;
use super::legend::*;
use super::render::*;
use super::style::*;

pub(super) struct XyFigure<'a> {
    axes: Axes<'a>,
    series: &'a [Series<'a>],
    log: bool,
    bounds: (f64, f64, f64, f64),
}

impl Figure for XyFigure<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: bool,
        layout: &mut Layout,
    ) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let titled = root
            .margin(10, 0, 0, 0)
            .titled(self.axes.title, (FAMILY, 22))
            .map_err(|e| e.to_string())?;
        let plot = with_legend_column(&titled, self.series, 15, layout)?;
        let (x0, x1, y0, y1) = self.bounds;
        let b = plot_box(&plot, XY_FRAME)?;
        let (w, h) = (f64::from(b[2] - b[0]), f64::from(b[3] - b[1]));
        let measure = measurer(root, XY_FRAME.label_font);
        let (xr, yr) = if self.log {
            (padded_log(x0, x1), padded_log(y0, y1))
        } else {
            (linear_range(x0, x1, has_marks(self.series)), padded(y0, y1))
        };
        let x = Axis::new(xr, self.log, w, true, &measure);
        let y = Axis::new(yr, self.log, h, false, &measure);
        axes_box(
            root,
            &plot,
            XY_FRAME,
            &self.axes,
            &x,
            &y,
            self.series,
            raster,
            layout,
        )
    }
}

/// Several named series against one x axis (for example crank angle in degrees), linear axes.
/// Writes `stem.svg` and `stem.png`.
pub(crate) fn line_plot(
    stem: &Path,
    axes: &Axes<'_>,
    series: &[Series<'_>],
) -> Result<Written, Error> {
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
pub(crate) fn loglog_plot(
    stem: &Path,
    axes: &Axes<'_>,
    series: &[Series<'_>],
) -> Result<Written, Error> {
    let fig = XyFigure {
        axes: *axes,
        series,
        log: true,
        bounds: bounds(series, true)?,
    };
    render(stem, FIGURE_SIZE, &fig)
}
