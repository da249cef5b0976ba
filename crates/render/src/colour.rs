//! Colours: 8-bit sRGB triples, the overlay palette and colour parsing.

/// An 8-bit RGB colour.
pub type Rgb = [u8; 3];

/// Distinct, medium-light colours for overlaid sequences (the variation
/// paper shows several generated motions overlapped, one colour each).
/// Light enough that Lambert shading keeps them recognisable.
pub const PALETTE: [Rgb; 8] = [
    [72, 132, 204],  // blue
    [232, 128, 48],  // orange
    [84, 172, 92],   // green
    [212, 76, 76],   // red
    [156, 116, 204], // purple
    [150, 110, 86],  // brown
    [222, 124, 190], // pink
    [128, 128, 128], // grey
];

/// White background.
pub const WHITE: Rgb = [255, 255, 255];
/// Light-grey background.
pub const LIGHT_GREY: Rgb = [236, 236, 236];
/// Dark text colour.
pub const TEXT: Rgb = [40, 40, 40];

/// The `i`-th palette colour (cycles after 8).
pub fn palette(i: usize) -> Rgb {
    PALETTE[i % PALETTE.len()]
}

/// Parses `#rrggbb`, `rrggbb` or a palette name (blue, orange, green, red,
/// purple, brown, pink, grey, white, lightgrey). `None` when unknown.
pub fn parse(s: &str) -> Option<Rgb> {
    let names = [
        "blue", "orange", "green", "red", "purple", "brown", "pink", "grey",
    ];
    let l = s.trim().to_ascii_lowercase();
    if let Some(i) = names.iter().position(|n| *n == l) {
        return Some(PALETTE[i]);
    }
    match l.as_str() {
        "gray" => return Some(PALETTE[7]),
        "white" => return Some(WHITE),
        "lightgrey" | "lightgray" | "light-grey" => return Some(LIGHT_GREY),
        _ => {}
    }
    let hex = l.strip_prefix('#').unwrap_or(&l);
    if hex.len() != 6 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let v = u32::from_str_radix(hex, 16).ok()?;
    Some([(v >> 16) as u8, (v >> 8) as u8, v as u8])
}

/// Linear blend `a*(1-t) + b*t`.
pub fn mix(a: Rgb, b: Rgb, t: f32) -> Rgb {
    let f = |x: u8, y: u8| {
        (x as f32 * (1.0 - t) + y as f32 * t)
            .round()
            .clamp(0.0, 255.0) as u8
    };
    [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_hex_and_names() {
        assert_eq!(parse("#ff8000"), Some([255, 128, 0]));
        assert_eq!(parse("00ff01"), Some([0, 255, 1]));
        assert_eq!(parse("Orange"), Some(PALETTE[1]));
        assert_eq!(parse("#ff80"), None);
        assert_eq!(parse("nope"), None);
    }

    #[test]
    fn palette_colours_are_distinct() {
        for i in 0..PALETTE.len() {
            for j in 0..i {
                let d: i32 = (0..3)
                    .map(|k| (PALETTE[i][k] as i32 - PALETTE[j][k] as i32).abs())
                    .sum();
                assert!(d > 60, "palette {i} and {j} too close");
            }
        }
    }
}
