//! Journal orbits: (e_x/c, e_y/c) inside the unit clearance circle, equal aspect.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Error;

use super::axes::*;
use super::draw::*;
use super::legend::*;
use super::render::*;
use super::style::*;

pub(super) struct OrbitFigure<'a> {
    title: &'a str,
    /// (label, e_x/c, e_y/c) per orbit.
    orbits: &'a [Series<'a>],
    r: f64,
}

pub(super) const ORBIT_FRAME: Frame = Frame {
    margin: 15,
    x_area: 50,
    y_area: 80,
    label_font: 15,
    desc_font: 17,
    width: 1,
};

impl Figure for OrbitFigure<'_> {
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
        layout.legends.push(rect_of(&legend));
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
        let b = plot_box(&area, ORBIT_FRAME)?;
        let (pw, ph) = ((b[2] - b[0]).max(1) as u32, (b[3] - b[1]).max(1) as u32);
        let (rx, ry) = equal_aspect(self.r, pw, ph);
        let measure = measurer(root, ORBIT_FRAME.label_font);
        let x = Axis::new((-rx, rx), false, f64::from(pw), true, &measure);
        let y = Axis::new((-ry, ry), false, f64::from(ph), false, &measure);
        // The circle first (black, 2 px), then the orbits (1 px) and sections (dots).
        let circle: (Vec<f64>, Vec<f64>) = (0..=360)
            .map(|k| {
                let a = (k as f64).to_radians();
                (a.cos(), a.sin())
            })
            .unzip();
        let mut chart = ChartBuilder::on(&area)
            .margin(ORBIT_FRAME.margin)
            .x_label_area_size(ORBIT_FRAME.x_area)
            .y_label_area_size(ORBIT_FRAME.y_area)
            .build_cartesian_2d(x.linear(), y.linear())
            .map_err(|e| e.to_string())?;
        let (fx, fy) = (|v: &f64| x.label(*v), |v: &f64| y.label(*v));
        chart
            .configure_mesh()
            .x_desc("eccentricity e/c, x component")
            .y_desc("eccentricity e/c, y component")
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .label_style((FAMILY, ORBIT_FRAME.label_font))
            .axis_desc_style((FAMILY, ORBIT_FRAME.desc_font))
            .draw()
            .map_err(|e| e.to_string())?;
        let r = rect_of(chart.plotting_area());
        layout.plots.push(r);
        let ring = [Series {
            name: "",
            x: &circle.0,
            y: &circle.1,
            style: SeriesStyle::Line,
        }];
        let px = to_pixels(&chart, &ring);
        let runs = visible_runs(&px[0], inset(r, STROKE_INSET));
        stroke(root, &runs, BLACK, 2, raster)?;
        let px = to_pixels(&chart, self.orbits);
        draw_data(root, r, self.orbits, px, ORBIT_FRAME.width, raster)
    }
}

/// The journal centre's orbit (e_x/c, e_y/c) inside the unit clearance circle, equal aspect.
/// The view shows at least |e|/c ≤ 1.08, more if the journal penetrates further.
/// Writes `stem.svg` and `stem.png`.
pub(crate) fn orbit_plot(
    stem: &Path,
    title: &str,
    ex: &[f64],
    ey: &[f64],
) -> Result<Written, Error> {
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
pub(crate) fn orbits_plot(
    stem: &Path,
    title: &str,
    orbits: &[Series<'_>],
) -> Result<Written, Error> {
    bounds(orbits, false)?;
    let r = orbits
        .iter()
        .flat_map(|o| o.x.iter().zip(o.y).map(|(x, y)| x.hypot(*y)))
        .fold(1.0, f64::max)
        * 1.08;
    render(stem, ORBIT_SIZE, &OrbitFigure { title, orbits, r })
}
