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

mod axes;
mod draw;
mod legend;
mod orbit;
mod panels;
mod render;
mod style;
mod ticks;
mod xy;

pub(crate) use orbit::{orbit_plot, orbits_plot};
pub(crate) use panels::{panels_plot, Panel};
pub(crate) use render::Written;
pub(crate) use style::{plain, Axes, Series, SeriesStyle};
pub(crate) use xy::{line_plot, loglog_plot};

#[cfg(test)]
mod tests;
