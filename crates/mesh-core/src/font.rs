//! The TrueType font of every figure (DejaVu Sans, licence in `assets/DejaVuSans-LICENSE.txt`),
//! embedded so that plots need no system fonts.

/// DejaVu Sans, the TTF bytes.
pub static DEJAVU_SANS: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
