//! A tiny built-in 5x7 bitmap font for labels (no system fonts needed).
//!
//! Covers `A-Z 0-9` and ` -_>.:/,()=+#`; lowercase letters are drawn with the
//! uppercase glyphs (small caps) and any other character as a hollow box.
//! Glyphs are drawn at an integer scale with one column of spacing.

use crate::colour::Rgb;
use crate::image::RgbImage;

/// Glyph width and height in font pixels.
pub const GLYPH_W: u32 = 5;
pub const GLYPH_H: u32 = 7;
/// Horizontal advance per character in font pixels (glyph + 1 spacing column).
pub const ADVANCE: u32 = GLYPH_W + 1;

/// (character, 7 rows of 5 bits, most significant of the 5 = leftmost).
const GLYPHS: &[(char, [u8; 7])] = &[
    ('A', rows([".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"])),
    ('B', rows(["####.", "#...#", "#...#", "####.", "#...#", "#...#", "####."])),
    ('C', rows([".###.", "#...#", "#....", "#....", "#....", "#...#", ".###."])),
    ('D', rows(["####.", "#...#", "#...#", "#...#", "#...#", "#...#", "####."])),
    ('E', rows(["#####", "#....", "#....", "####.", "#....", "#....", "#####"])),
    ('F', rows(["#####", "#....", "#....", "####.", "#....", "#....", "#...."])),
    ('G', rows([".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####"])),
    ('H', rows(["#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"])),
    ('I', rows([".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."])),
    ('J', rows(["..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##.."])),
    ('K', rows(["#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#"])),
    ('L', rows(["#....", "#....", "#....", "#....", "#....", "#....", "#####"])),
    ('M', rows(["#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"])),
    ('N', rows(["#...#", "#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#"])),
    ('O', rows([".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."])),
    ('P', rows(["####.", "#...#", "#...#", "####.", "#....", "#....", "#...."])),
    ('Q', rows([".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#"])),
    ('R', rows(["####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#"])),
    ('S', rows([".####", "#....", "#....", ".###.", "....#", "....#", "####."])),
    ('T', rows(["#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."])),
    ('U', rows(["#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."])),
    ('V', rows(["#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#.."])),
    ('W', rows(["#...#", "#...#", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#."])),
    ('X', rows(["#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#"])),
    ('Y', rows(["#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#.."])),
    ('Z', rows(["#####", "....#", "...#.", "..#..", ".#...", "#....", "#####"])),
    ('0', rows([".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."])),
    ('1', rows(["..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."])),
    ('2', rows([".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"])),
    ('3', rows(["####.", "....#", "....#", ".###.", "....#", "....#", "####."])),
    ('4', rows(["...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."])),
    ('5', rows(["#####", "#....", "####.", "....#", "....#", "#...#", ".###."])),
    ('6', rows(["..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."])),
    ('7', rows(["#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."])),
    ('8', rows([".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."])),
    ('9', rows([".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."])),
    (' ', rows([".....", ".....", ".....", ".....", ".....", ".....", "....."])),
    ('-', rows([".....", ".....", ".....", "#####", ".....", ".....", "....."])),
    ('_', rows([".....", ".....", ".....", ".....", ".....", ".....", "#####"])),
    ('>', rows(["#....", ".#...", "..#..", "...#.", "..#..", ".#...", "#...."])),
    ('.', rows([".....", ".....", ".....", ".....", ".....", ".##..", ".##.."])),
    (':', rows([".....", ".##..", ".##..", ".....", ".##..", ".##..", "....."])),
    ('/', rows(["....#", "....#", "...#.", "..#..", ".#...", "#....", "#...."])),
    (',', rows([".....", ".....", ".....", ".....", ".##..", "..#..", ".#..."])),
    ('(', rows(["...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#."])),
    (')', rows([".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#..."])),
    ('=', rows([".....", ".....", "#####", ".....", "#####", ".....", "....."])),
    ('+', rows([".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."])),
    ('#', rows([".#.#.", ".#.#.", "#####", ".#.#.", "#####", ".#.#.", ".#.#."])),
];

/// The box drawn for characters the font does not have.
const MISSING: [u8; 7] = rows(["#####", "#...#", "#...#", "#...#", "#...#", "#...#", "#####"]);

const fn rows(r: [&str; 7]) -> [u8; 7] {
    let mut out = [0u8; 7];
    let mut i = 0;
    while i < 7 {
        let b = r[i].as_bytes();
        let mut j = 0;
        while j < 5 {
            if b[j] == b'#' {
                out[i] |= 1 << (4 - j);
            }
            j += 1;
        }
        i += 1;
    }
    out
}

/// The glyph rows for `c` (lowercase mapped to uppercase).
pub fn glyph(c: char) -> [u8; 7] {
    let c = c.to_ascii_uppercase();
    GLYPHS.iter().find(|(g, _)| *g == c).map(|(_, r)| *r).unwrap_or(MISSING)
}

/// Width in pixels of `text` drawn at `scale` (no trailing spacing column).
pub fn text_width(text: &str, scale: u32) -> u32 {
    let n = text.chars().count() as u32;
    if n == 0 {
        0
    } else {
        (n * ADVANCE - 1) * scale
    }
}

/// Draws `text` with its top-left corner at `(x, y)`; clipped to the image.
pub fn draw_text(img: &mut RgbImage, x: i64, y: i64, text: &str, scale: u32, colour: Rgb) {
    let s = scale.max(1) as i64;
    for (k, c) in text.chars().enumerate() {
        let g = glyph(c);
        let gx = x + k as i64 * ADVANCE as i64 * s;
        for (row, bits) in g.iter().enumerate() {
            for col in 0..GLYPH_W as i64 {
                if bits & (1 << (4 - col)) != 0 {
                    img.fill_rect(gx + col * s, y + row as i64 * s, s, s, colour);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_are_unique_and_nonempty_except_space() {
        for (i, (c, g)) in GLYPHS.iter().enumerate() {
            if *c != ' ' {
                assert!(g.iter().any(|r| *r != 0), "{c} is blank");
            }
            for (d, h) in &GLYPHS[..i] {
                assert!(g != h, "{c} and {d} share a glyph");
            }
        }
    }

    #[test]
    fn draws_the_glyph_pixels_at_scale() {
        let mut img = RgbImage::new(40, 20, [255; 3]);
        draw_text(&mut img, 1, 2, "L-", 2, [0, 0, 0]);
        // 'L': left column set on all 7 rows, bottom row full.
        assert_eq!(img.get(1, 2), [0, 0, 0]);
        assert_eq!(img.get(2, 15), [0, 0, 0]);
        assert_eq!(img.get(3, 2), [255; 3]);
        assert_eq!(img.get(1 + 9, 15), [0, 0, 0]);
        // '-' starts 12 px later, middle row (row 3 -> y 2 + 6).
        assert_eq!(img.get(13, 8), [0, 0, 0]);
        assert_eq!(img.get(13, 6), [255; 3]);
        assert_eq!(text_width("L-", 2), 22);
        assert_eq!(glyph('a'), glyph('A'));
        assert_eq!(glyph('~'), MISSING);
    }
}
