//! The look of a figure: the font, the sizes, the colours and markers of the series, and what
//! a figure is given (series, axes).

use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::register_font;

use crate::error::Error;

/// The font all text is drawn with.
pub(super) static FONT: &[u8] = include_bytes!("../../../assets/DejaVuSans.ttf");

/// Font family name every text style of this module uses.
pub(super) const FAMILY: &str = "sans-serif";

/// Size of line and log–log figures, px.
pub(crate) const FIGURE_SIZE: (u32, u32) = (1000, 650);
/// Size of orbit figures, px.
pub(crate) const ORBIT_SIZE: (u32, u32) = (760, 760);

/// Tableau 10 colours, given to series in order.
pub(super) const COLORS: [RGBColor; 10] = [
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
pub(super) fn ensure_font() -> Result<(), Error> {
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
pub(crate) enum SeriesStyle {
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
    pub(super) fn dashed(self) -> bool {
        matches!(self, SeriesStyle::Dashed | SeriesStyle::DashedPoints)
    }

    pub(super) fn marked(self) -> bool {
        matches!(self, SeriesStyle::LinePoints | SeriesStyle::DashedPoints)
    }

    pub(super) fn line(self) -> bool {
        !matches!(self, SeriesStyle::Points)
    }
}

/// Number of marker shapes: filled circle, square, triangle, diamond; open circle, square;
/// cross; downward triangle.
pub(crate) const MARKERS: usize = 8;

/// An identifier (a case name, a file stem) as text for a figure: underscores become spaces.
pub(crate) fn plain(name: &str) -> String {
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
pub(crate) struct Series<'a> {
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
pub(crate) struct Axes<'a> {
    /// Figure title.
    pub title: &'a str,
    /// x axis label (with unit).
    pub x_label: &'a str,
    /// y axis label (with unit).
    pub y_label: &'a str,
}

pub(super) fn style_of(i: usize) -> RGBColor {
    COLORS[i % COLORS.len()]
}
