//! Shared drawing plumbing: the bundled font, an in-memory RGB canvas,
//! PNG encoding, axis ranges and tick formatting, and the legend column.

use crate::viz::VizError;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// DejaVu Sans (Bitstream Vera licence, see `assets/fonts/LICENSE-DejaVu.txt`),
/// bundled so plots need no system font library.
static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Font family name every plot uses.
pub(crate) const FAMILY: &str = "sans-serif";

/// Registers the bundled font with plotters once per process.
pub(crate) fn ensure_font() {
    REGISTER.call_once(|| {
        // The bytes are a valid TrueType file compiled into the binary; a
        // failure here could only come from a corrupt build.
        plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
            .map_err(|_| ())
            .expect("bundled DejaVu Sans must parse");
    });
}

/// A rendered picture: `width × height` pixels, RGB8, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb {
    /// Width (px).
    pub width: u32,
    /// Height (px).
    pub height: u32,
    /// `3 · width · height` bytes.
    pub data: Vec<u8>,
}

impl Rgb {
    /// Encodes as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>, VizError> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().map_err(plot_err)?;
            w.write_image_data(&self.data).map_err(plot_err)?;
            w.finish().map_err(plot_err)?;
        }
        Ok(out)
    }

    /// Stacks pictures top to bottom on white, left-aligned (one PNG of
    /// several figures); an error for none.
    pub fn stack(parts: &[Rgb]) -> Result<Rgb, VizError> {
        let width = parts.iter().map(|p| p.width).max().unwrap_or(0);
        let height: u32 = parts.iter().map(|p| p.height).sum();
        if width == 0 || height == 0 {
            return Err(VizError::Input("nothing to stack".into()));
        }
        let mut data = vec![255u8; 3 * width as usize * height as usize];
        let mut row0 = 0usize;
        for p in parts {
            let line = 3 * p.width as usize;
            for (r, src) in p.data.chunks_exact(line).enumerate() {
                let at = 3 * width as usize * (row0 + r);
                data[at..at + line].copy_from_slice(src);
            }
            row0 += p.height as usize;
        }
        Ok(Rgb {
            width,
            height,
            data,
        })
    }

    /// Writes the PNG to `path` atomically.
    pub fn save_png(&self, path: &Path) -> Result<(), VizError> {
        let bytes = self.to_png()?;
        crate::io::atomic::write_bytes_atomic(path, &bytes).map_err(|e| VizError::io(path, e))
    }
}

pub(crate) fn plot_err(e: impl std::fmt::Display) -> VizError {
    VizError::Plot(e.to_string())
}

/// Renders with `draw` on a white `size` canvas.
pub(crate) fn render<F>(size: (u32, u32), draw: F) -> Result<Rgb, VizError>
where
    F: FnOnce(&DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<(), VizError>,
{
    ensure_font();
    let (w, h) = size;
    if w < 200 || h < 150 || w > 8000 || h > 8000 {
        return Err(VizError::Input(format!(
            "plot size {w}x{h} px out of range"
        )));
    }
    let mut data = vec![255u8; 3 * w as usize * h as usize];
    {
        let root = BitMapBackend::with_buffer(&mut data, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        draw(&root)?;
        root.present().map_err(plot_err)?;
    }
    Ok(Rgb {
        width: w,
        height: h,
        data,
    })
}

/// `[lo, hi]` of the finite values, padded by `pad` of the span; a flat or
/// empty range is widened so the axis stays readable.
pub(crate) fn padded_range(values: impl Iterator<Item = f64>, pad: f64) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if lo > hi {
        return None;
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(1.0) {
        let d = (lo.abs() * 0.01).max(1e-6);
        return Some((lo - d, hi + d));
    }
    Some((lo - pad * span, hi + pad * span))
}

/// Tick label with as many decimals as the axis span needs (≈ 5 ticks).
pub(crate) fn tick_formatter(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let step = ((hi - lo) / 5.0).abs().max(1e-12);
    let decimals = (-step.log10().floor()).clamp(0.0, 8.0) as usize;
    move |v: &f64| {
        let v = if v.abs() < step * 1e-6 { 0.0 } else { *v };
        format!("{v:.decimals$}")
    }
}

/// Colour of the `i`-th series when none is given (Tableau 10).
pub(crate) fn palette(i: usize) -> RGBColor {
    const C: [(u8, u8, u8); 10] = [
        (31, 119, 180),
        (255, 127, 14),
        (44, 160, 44),
        (214, 39, 40),
        (148, 103, 189),
        (140, 86, 75),
        (227, 119, 194),
        (127, 127, 127),
        (188, 189, 34),
        (23, 190, 207),
    ];
    let (r, g, b) = C[i % C.len()];
    RGBColor(r, g, b)
}

/// A series' own sRGB colour, else the `i`-th palette colour.
pub(crate) fn own_or_palette(color: Option<[u8; 3]>, i: usize) -> RGBColor {
    match color {
        Some([r, g, b]) => RGBColor(r, g, b),
        None => palette(i),
    }
}

/// One legend entry: colour, whether dashed, whether drawn as a box (bars).
pub(crate) struct LegendEntry<'a> {
    pub name: &'a str,
    pub color: RGBColor,
    pub dashed: bool,
    pub boxed: bool,
}

/// Width (px) of the legend column for these names.
pub(crate) fn legend_width(names: &[&str]) -> u32 {
    let longest = names.iter().map(|n| n.chars().count()).max().unwrap_or(0) as u32;
    (60 + 9 * longest).clamp(120, 360)
}

/// Draws the legend entries top-down in `area` (a column beside the plot).
pub(crate) fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    entries: &[LegendEntry<'_>],
    top: i32,
) -> Result<(), VizError> {
    let font = (FAMILY, 16).into_font().color(&BLACK);
    for (k, e) in entries.iter().enumerate() {
        let y = top + 26 * k as i32;
        if e.boxed {
            area.draw(&Rectangle::new([(8, y - 7), (32, y + 7)], e.color.filled()))
                .map_err(plot_err)?;
        } else if e.dashed {
            for x in [8, 20] {
                area.draw(&PathElement::new(
                    vec![(x, y), (x + 8, y)],
                    e.color.stroke_width(3),
                ))
                .map_err(plot_err)?;
            }
        } else {
            area.draw(&PathElement::new(
                vec![(8, y), (32, y)],
                e.color.stroke_width(3),
            ))
            .map_err(plot_err)?;
        }
        area.draw(&Text::new(e.name.to_string(), (40, y - 9), font.clone()))
            .map_err(plot_err)?;
    }
    Ok(())
}
