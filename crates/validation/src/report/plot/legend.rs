//! Legends outside the data: a column right of the plot or a row under the circle, each
//! entry with its series' line and marker.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::draw::*;
use super::render::*;
use super::style::*;

/// One entry of a legend: the name and how its series looks.
pub(super) struct Entry {
    pub(super) name: String,
    pub(super) color: RGBColor,
    pub(super) dashed: bool,
    pub(super) line: bool,
    /// The marker kind, if the series has markers.
    pub(super) marker: Option<usize>,
    /// Small dots (Points).
    pub(super) dots: bool,
    pub(super) width: u32,
}

pub(super) fn entries(series: &[Series<'_>]) -> Vec<Entry> {
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
pub(super) const LEGEND_FONT: u32 = 15;
/// Height of one legend entry, px.
pub(super) const LEGEND_ROW: i32 = 24;
/// Length of the line sample of a legend entry, px.
pub(super) const LEGEND_SAMPLE: i32 = 40;

/// Width of a legend column for these entries, px (0 without entries).
pub(super) fn legend_width<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
) -> u32 {
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
pub(super) fn draw_entry<DB: DrawingBackend>(
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
pub(super) fn legend_column<DB: DrawingBackend>(
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
pub(super) fn with_legend_column<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    series: &[Series<'_>],
    top: i32,
    layout: &mut Layout,
) -> Result<DrawingArea<DB, Shift>, String> {
    let es = entries(series);
    let w = legend_width(area, &es);
    if w == 0 {
        return Ok(area.clone());
    }
    let (total, _) = area.dim_in_pixel();
    let (plot, legend) = area.split_horizontally(total.saturating_sub(w) as i32);
    legend_column(&legend, &es, top)?;
    layout.legends.push(rect_of(&legend));
    Ok(plot)
}

// ---------------------------------------------------------------------------------------------
// Data in pixels: clipped, without repeated points, a raster drawn piece by piece
// ---------------------------------------------------------------------------------------------
