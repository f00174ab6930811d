//! The data drawn inside the plot area: lines clipped to it (piece by piece on a bitmap),
//! dashes, markers, one point per pixel column.

use plotters::coord::ranged1d::Ranged;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::render::*;
use super::style::*;

/// Draws marker `kind` (mod [`MARKERS`]) of colour `c` at `at`, in any coordinates.
pub(super) fn draw_marker<DB, CT>(
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

/// A point in backend pixels.
pub(super) type Px = (f64, f64);

/// Pixels between a stroke's centre line and the plot area's edge: the half width of the
/// widest line (2 px), rounded up.
pub(super) const STROKE_INSET: f64 = 1.0;

/// The inclusive pixel box `r` shrunk by `by` on every side, as floats.
pub(super) fn inset(r: PixelRect, by: f64) -> [f64; 4] {
    [
        f64::from(r[0]) + by,
        f64::from(r[1]) + by,
        f64::from(r[2] - 1) - by,
        f64::from(r[3] - 1) - by,
    ]
}

pub(super) fn within(p: Px, r: [f64; 4]) -> bool {
    p.0 >= r[0] && p.0 <= r[2] && p.1 >= r[1] && p.1 <= r[3]
}

/// The part of the segment a → b inside the box `r` = [x0, y0, x1, y1] (Liang–Barsky), if any.
pub(super) fn clip(a: Px, b: Px, r: [f64; 4]) -> Option<(Px, Px)> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - r[0]),
        (dx, r[2] - a.0),
        (-dy, a.1 - r[1]),
        (dy, r[3] - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                if t > t1 {
                    return None;
                }
                t0 = t0.max(t);
            } else {
                if t < t0 {
                    return None;
                }
                t1 = t1.min(t);
            }
        }
    }
    Some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

pub(super) fn whole(p: Px) -> (i32, i32) {
    (p.0.round() as i32, p.1.round() as i32)
}

/// The visible runs of a polyline inside the box `r`: each segment clipped to it, the points
/// as whole pixels, a point repeating the one before dropped (plotters' thick-line polygon
/// has no direction for a piece of zero length and throws spikes across the figure).
pub(super) fn visible_runs(pts: &[Px], r: [f64; 4]) -> Vec<Vec<(i32, i32)>> {
    let mut runs = Vec::new();
    let mut cur: Vec<(i32, i32)> = Vec::new();
    let mut end = |cur: &mut Vec<(i32, i32)>| {
        if cur.len() > 1 {
            runs.push(std::mem::take(cur));
        } else {
            cur.clear();
        }
    };
    for w in pts.windows(2) {
        match clip(w[0], w[1], r) {
            Some((a, b)) => {
                let (a, b) = (whole(a), whole(b));
                if cur.last() != Some(&a) {
                    end(&mut cur);
                    cur.push(a);
                }
                if cur.last() != Some(&b) {
                    cur.push(b);
                }
            }
            None => end(&mut cur),
        }
    }
    end(&mut cur);
    runs
}

/// Dashes of `on` px with `off` px gaps along each run, the pattern carried across its
/// vertices.
pub(super) fn dashes(runs: &[Vec<(i32, i32)>], on: f64, off: f64) -> Vec<Vec<(i32, i32)>> {
    let mut out = Vec::new();
    for run in runs {
        let mut pos = 0.0;
        let mut dash: Vec<Px> = Vec::new();
        let mut flush = |dash: &mut Vec<Px>| {
            let mut d: Vec<(i32, i32)> = Vec::new();
            for p in dash.drain(..) {
                let q = whole(p);
                if d.last() != Some(&q) {
                    d.push(q);
                }
            }
            if d.len() > 1 {
                out.push(d);
            }
        };
        for w in run.windows(2) {
            let (a, b) = (
                (f64::from(w[0].0), f64::from(w[0].1)),
                (f64::from(w[1].0), f64::from(w[1].1)),
            );
            let len = (b.0 - a.0).hypot(b.1 - a.1);
            let at = |s: f64| (a.0 + (b.0 - a.0) * s / len, a.1 + (b.1 - a.1) * s / len);
            let mut s = 0.0;
            while s < len {
                if pos < on {
                    let take = (on - pos).min(len - s);
                    if dash.is_empty() {
                        dash.push(at(s));
                    }
                    dash.push(at(s + take));
                    s += take;
                    pos += take;
                    if pos >= on {
                        flush(&mut dash);
                    }
                } else {
                    let take = (on + off - pos).min(len - s);
                    s += take;
                    pos += take;
                    if pos >= on + off {
                        pos = 0.0;
                    }
                }
            }
        }
        flush(&mut dash);
    }
    out
}

/// Strokes runs: on a raster each segment alone (no joins to miter past the data) with a
/// round dot at each inner vertex; in SVG each run as one polyline.
pub(super) fn stroke<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    runs: &[Vec<(i32, i32)>],
    color: RGBColor,
    width: u32,
    raster: bool,
) -> Result<(), String> {
    let style = color.stroke_width(width);
    for run in runs {
        if raster {
            for w in run.windows(2) {
                root.draw(&PathElement::new(vec![w[0], w[1]], style))
                    .map_err(|e| e.to_string())?;
            }
            if width > 1 {
                for &p in &run[1..run.len() - 1] {
                    root.draw(&Circle::new(p, width / 2, color.filled()))
                        .map_err(|e| e.to_string())?;
                }
            }
        } else {
            root.draw(&PathElement::new(run.clone(), style))
                .map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

/// A line's points reduced for the pixels they fall on: of each run of points in one pixel
/// column, the first, the lowest, the highest and the last, in order (what a stroke of them
/// covers is unchanged). Only for more than four points per column.
pub(super) fn per_column(pts: Vec<Px>, columns: f64) -> Vec<Px> {
    if (pts.len() as f64) <= 4.0 * columns {
        return pts;
    }
    let mut out = Vec::with_capacity(4 * columns as usize + 4);
    let mut i = 0;
    while i < pts.len() {
        let col = pts[i].0.round();
        let mut j = i;
        let (mut lo, mut hi) = (i, i);
        while j < pts.len() && pts[j].0.round() == col {
            if pts[j].1 < pts[lo].1 {
                lo = j;
            }
            if pts[j].1 > pts[hi].1 {
                hi = j;
            }
            j += 1;
        }
        let mut keep = vec![i, lo, hi, j - 1];
        keep.sort_unstable();
        keep.dedup();
        out.extend(keep.into_iter().map(|k| pts[k]));
        i = j;
    }
    out
}

/// Draws the series (their points already in pixels) inside the plot area `plot`: lines
/// clipped one stroke's half width inside it, points and markers only where they fit whole.
pub(super) fn draw_data<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plot: PixelRect,
    series: &[Series<'_>],
    pixels: Vec<Vec<Px>>,
    width: u32,
    raster: bool,
) -> Result<(), String> {
    let columns = f64::from(plot[2] - plot[0]);
    for (i, (s, px)) in series.iter().zip(pixels).enumerate() {
        let c = style_of(i);
        if s.style.line() {
            let line = per_column(px.clone(), columns);
            let runs = visible_runs(&line, inset(plot, STROKE_INSET));
            let runs = if s.style.dashed() {
                dashes(&runs, 10.0, 6.0)
            } else {
                runs
            };
            stroke(root, &runs, c, width, raster)?;
        } else {
            for &p in px.iter().filter(|&&p| within(p, inset(plot, 4.0))) {
                root.draw(&Circle::new(whole(p), 3, c.filled()))
                    .map_err(|e| e.to_string())?;
            }
        }
        if s.style.marked() {
            for &p in px.iter().filter(|&&p| within(p, inset(plot, 7.0))) {
                draw_marker(root, whole(p), i, c)?;
            }
        }
    }
    Ok(())
}

/// The series' points in the chart's pixels.
pub(super) fn to_pixels<DB, X, Y>(
    chart: &ChartContext<'_, DB, Cartesian2d<X, Y>>,
    series: &[Series<'_>],
) -> Vec<Vec<Px>>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    series
        .iter()
        .map(|s| {
            s.x.iter()
                .zip(s.y)
                .map(|(&x, &y)| {
                    let p = chart.backend_coord(&(x, y));
                    (f64::from(p.0), f64::from(p.1))
                })
                .collect()
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Ticks: chosen so that their labels fit, every decade of a log axis labelled
// ---------------------------------------------------------------------------------------------
