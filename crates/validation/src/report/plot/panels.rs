//! Panels stacked on one x axis, one per quantity.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Error;

use super::axes::*;
use super::legend::*;
use super::render::*;
use super::style::*;

/// One panel of [`panels_plot`].
///
/// ```text
/// title above the panel; y against x; x linear; y linear or log10 (then every y > 0)
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Panel<'a> {
    /// The panel's title and axis labels.
    pub axes: Axes<'a>,
    /// Its series.
    pub series: &'a [Series<'a>],
    /// Whether the y axis is log10.
    pub log_y: bool,
}

/// Width of a panel figure, px.
pub(crate) const PANEL_WIDTH: u32 = 1000;
/// Height of one panel, px.
pub(crate) const PANEL_HEIGHT: u32 = 400;

pub(super) struct PanelsFigure<'a> {
    title: &'a str,
    panels: &'a [Panel<'a>],
    bounds: Vec<(f64, f64, f64, f64)>,
}

impl Figure for PanelsFigure<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: bool,
        layout: &mut Layout,
    ) -> Result<(), String> {
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
        let measure = measurer(root, PANEL_FRAME.label_font);
        for ((p, part), &(x0, x1, y0, y1)) in self.panels.iter().zip(&parts).zip(&self.bounds) {
            // The panel's title above it (not a chart caption: the chart is built twice).
            let part = part
                .titled(p.axes.title, (FAMILY, 18))
                .map_err(|e| e.to_string())?;
            let (total, _) = part.dim_in_pixel();
            let (plot, legend) = part.split_horizontally(total.saturating_sub(w) as i32);
            legend_column(&legend, &entries(p.series), PANEL_FRAME.margin as i32)?;
            layout.legends.push(rect_of(&legend));
            let b = plot_box(&plot, PANEL_FRAME)?;
            let (bw, bh) = (f64::from(b[2] - b[0]), f64::from(b[3] - b[1]));
            let xr = linear_range(x0, x1, has_marks(p.series));
            let yr = if p.log_y {
                padded_log(y0, y1)
            } else {
                padded(y0, y1)
            };
            let x = Axis::new(xr, false, bw, true, &measure);
            let y = Axis::new(yr, p.log_y, bh, false, &measure);
            axes_box(
                root,
                &plot,
                PANEL_FRAME,
                &p.axes,
                &x,
                &y,
                p.series,
                raster,
                layout,
            )?;
        }
        Ok(())
    }
}

/// Panels stacked vertically under one title, each with its own axes (x linear, y linear or
/// log10): quantities of different units against one abscissa (stiffness: |λ| and the RK4
/// step limit against crank angle). Writes `stem.svg` and `stem.png`, [`PANEL_WIDTH`] wide and
/// [`PANEL_HEIGHT`] per panel.
pub(crate) fn panels_plot(
    stem: &Path,
    title: &str,
    panels: &[Panel<'_>],
) -> Result<Written, Error> {
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
