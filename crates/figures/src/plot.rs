//! What every plot of the project shares: the one font, registered with plotters, and PNG
//! encoding of a drawn RGB buffer.

use std::path::Path;

use mesh_core::font::DEJAVU_SANS as FONT;
use mesh_core::{Error, Result};

/// Registers the embedded DejaVu Sans as plotters' "sans-serif" (once).
pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is compiled in: registration cannot fail on a valid TTF.
        let _ = plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
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
