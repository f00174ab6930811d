//! The drawing backend: a figure drawn on SVG and on a bitmap, the PNG as an 8-bit palette,
//! both files written atomically; the plot areas and legends of the bitmap (`Layout`).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Error;
use crate::store::io;

use super::style::*;

/// The two files a figure function wrote.
///
/// ```text
/// stem → (stem.svg, stem.png)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Written {
    /// The SVG file.
    pub svg: PathBuf,
    /// The PNG file.
    pub png: PathBuf,
    /// Where the PNG's plot areas and legends are.
    pub layout: Layout,
}

/// A rectangle of pixels `[x0, y0, x1, y1]`, `x1` and `y1` excluded.
pub(crate) type PixelRect = [i32; 4];

/// Where a figure put its parts, in the PNG's pixels: every pixel of a data series lies in one
/// of the `plots`; the `legends` hold samples of the series' lines and markers.
///
/// ```text
/// plots: one per panel (the orbit's square, the line plot's axes box); legends: likewise
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Layout {
    /// The plot areas.
    pub plots: Vec<PixelRect>,
    /// The legends.
    pub legends: Vec<PixelRect>,
}

/// The pixel rectangle of a drawing area (backend coordinates).
pub(super) fn rect_of<DB: DrawingBackend, CT: plotters::coord::CoordTranslate>(
    area: &DrawingArea<DB, CT>,
) -> PixelRect {
    let (x, y) = area.get_pixel_range();
    [x.start, y.start, x.end, y.end]
}

/// Something that draws itself on any plotters backend.
pub(super) trait Figure {
    /// Draws on `root`; `raster`: on a bitmap (lines drawn piece by piece, module doc); the
    /// plot areas and legends go into `layout`.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: bool,
        layout: &mut Layout,
    ) -> Result<(), String>;
}

/// Renders `fig` to `stem.svg` and `stem.png` (atomically), both of `size` pixels.
pub(super) fn render<F: Figure>(stem: &Path, size: (u32, u32), fig: &F) -> Result<Written, Error> {
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
        fig.draw(&root, false, &mut Layout::default())
            .map_err(|e| plot_err(&svg, e))?;
        root.present().map_err(|e| plot_err(&svg, e.to_string()))?;
    }
    io::write_atomic(&svg, text.as_bytes())?;
    let mut rgb = vec![0u8; 3 * size.0 as usize * size.1 as usize];
    let mut layout = Layout::default();
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        fig.draw(&root, true, &mut layout)
            .map_err(|e| plot_err(&png, e))?;
        root.present().map_err(|e| plot_err(&png, e.to_string()))?;
    }
    let bytes = palette_png(&rgb, size).map_err(|e| plot_err(&png, e))?;
    io::write_atomic(&png, &bytes)?;
    Ok(Written { svg, png, layout })
}

/// Encodes an RGB image as an 8-bit palette PNG (module doc).
pub(crate) fn palette_png(rgb: &[u8], size: (u32, u32)) -> Result<Vec<u8>, String> {
    use std::collections::HashMap;
    // Runs of one colour (the background, a filled band) are counted with one lookup each:
    // a plot is mostly runs, and a lookup per pixel was most of a run's figure time.
    let mut counts: HashMap<[u8; 3], u32> = HashMap::new();
    let mut run: Option<([u8; 3], u32)> = None;
    for px in rgb.chunks_exact(3) {
        let c = [px[0], px[1], px[2]];
        match run.as_mut() {
            Some((rc, n)) if *rc == c => *n += 1,
            _ => {
                if let Some((rc, n)) = run {
                    *counts.entry(rc).or_default() += n;
                }
                run = Some((c, 1));
            }
        }
    }
    if let Some((rc, n)) = run {
        *counts.entry(rc).or_default() += n;
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
    let mut last = ([0u8; 3], None::<u8>);
    let data: Vec<u8> = rgb
        .chunks_exact(3)
        .map(|px| {
            let c = [px[0], px[1], px[2]];
            match last {
                (lc, Some(i)) if lc == c => i,
                _ => {
                    let i = index[&c];
                    last = (c, Some(i));
                    i
                }
            }
        })
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

pub(super) fn plot_err(path: &Path, e: String) -> Error {
    Error::Internal(format!("plot {}: {e}", path.display()))
}
