//! What every plot of the project shares: the one font, registered with plotters, the legend's
//! style, and PNG encoding of a drawn RGB buffer.

use std::path::Path;

use mesh_core::font::DEJAVU_SANS as FONT;
use mesh_core::{Error, Result};
use plotters::chart::{ChartContext, SeriesLabelPosition};
use plotters::coord::CoordTranslate;
use plotters::drawing::DrawingAreaErrorKind;
use plotters::element::PathElement;
use plotters::prelude::DrawingBackend;
use plotters::style::{Color, ShapeStyle, BLACK, WHITE};

/// Registers the embedded DejaVu Sans as plotters' "sans-serif" (once).
pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is compiled in: registration cannot fail on a valid TTF.
        let _ = plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
}

/// Draws the legend of `chart`'s labelled series at `position`: the font at 12 px, a black
/// border, on white of `opacity` (the plot shows through the rest).
pub fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    opacity: f64,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(opacity))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .position(position)
        .draw()
}

/// A series' mark in the legend: a horizontal line `length` pixels long in `style`, from the
/// entry's anchor (for `.legend(...)`).
pub fn legend_line(style: ShapeStyle, length: i32) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + length, y)], style)
}

/// Encodes an RGB buffer as PNG bytes (`path` for messages).
pub fn png_bytes(path: &Path, pixels: &[u8], w: u32, h: u32) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| Error::file(path, e.to_string()))?;
        writer.write_image_data(pixels).map_err(|e| Error::file(path, e.to_string()))?;
    }
    Ok(bytes)
}
