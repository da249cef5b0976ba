//! Animated GIF output with one global 256-colour palette.
//!
//! The palette is learnt once, by median cut over a 5-bit-per-channel colour
//! histogram of a few sample frames (images with at most 256 distinct
//! histogram cells keep their exact colours), then every frame is mapped
//! through a 32x32x32 nearest-colour lookup table, so colours do not flicker
//! between frames and mapping is one table lookup per pixel.

use crate::image::RgbImage;

/// A learnt palette and its colour lookup table.
pub struct GifPalette {
    /// 256 RGB entries, flattened.
    pub colours: Vec<u8>,
    lut: Vec<u8>,
}

/// One occupied histogram cell: 5-bit colour, pixel count, 8-bit channel sums.
#[derive(Clone, Copy)]
struct Cell {
    key: [u8; 3],
    count: u64,
    sum: [u64; 3],
}

#[inline]
fn cell_index(p: &[u8]) -> usize {
    ((p[0] as usize >> 3) << 10) | ((p[1] as usize >> 3) << 5) | (p[2] as usize >> 3)
}

impl GifPalette {
    /// Learns up to 256 colours from the pixels of `samples` (median cut:
    /// split the cell box with the widest channel range at its pixel-weighted
    /// median until there are 256 boxes; each colour is its box's mean).
    pub fn learn(samples: &[&RgbImage]) -> GifPalette {
        let mut hist = vec![(0u64, [0u64; 3]); 32 * 32 * 32];
        for img in samples {
            for p in img.data.chunks_exact(3) {
                let h = &mut hist[cell_index(p)];
                h.0 += 1;
                for k in 0..3 {
                    h.1[k] += p[k] as u64;
                }
            }
        }
        let cells: Vec<Cell> = hist
            .iter()
            .enumerate()
            .filter(|(_, h)| h.0 > 0)
            .map(|(i, h)| Cell {
                key: [(i >> 10) as u8, ((i >> 5) & 31) as u8, (i & 31) as u8],
                count: h.0,
                sum: h.1,
            })
            .collect();
        let mut boxes: Vec<Vec<Cell>> = if cells.is_empty() {
            Vec::new()
        } else {
            vec![cells]
        };
        while boxes.len() < 256 {
            // The box with the widest channel range (ties: more pixels, then lower index).
            let pick = boxes
                .iter()
                .enumerate()
                .filter(|(_, b)| b.len() > 1)
                .map(|(i, b)| {
                    let (axis, range) = widest(b);
                    (
                        range,
                        b.iter().map(|c| c.count).sum::<u64>(),
                        std::cmp::Reverse(i),
                        axis,
                    )
                })
                .max();
            let Some((_, total, std::cmp::Reverse(i), axis)) = pick else {
                break;
            };
            let mut b = std::mem::take(&mut boxes[i]);
            b.sort_by_key(|c| (c.key[axis], c.key));
            let mut acc = 0;
            let mut cut = 1;
            for (k, c) in b.iter().enumerate() {
                acc += c.count;
                if 2 * acc >= total {
                    cut = (k + 1).clamp(1, b.len() - 1);
                    break;
                }
            }
            let rest = b.split_off(cut);
            boxes[i] = b;
            boxes.push(rest);
        }
        let mut colours: Vec<u8> = boxes
            .iter()
            .flat_map(|b| {
                let n: u64 = b.iter().map(|c| c.count).sum();
                (0..3).map(move |k| ((b.iter().map(|c| c.sum[k]).sum::<u64>() + n / 2) / n) as u8)
            })
            .collect();
        if colours.is_empty() {
            colours.extend_from_slice(&[255, 255, 255]);
        }
        let n_pal = colours.len() / 3;
        colours.resize(256 * 3, 0);
        let mut lut = vec![0u8; 32 * 32 * 32];
        for (k, slot) in lut.iter_mut().enumerate() {
            let ch = |s: usize| {
                let v = ((k >> s) & 31) as i32;
                (v << 3) | (v >> 2)
            };
            let q = [ch(10), ch(5), ch(0)];
            let mut best = (i32::MAX, 0usize);
            for j in 0..n_pal {
                let d: i32 = (0..3)
                    .map(|c| (colours[3 * j + c] as i32 - q[c]).pow(2))
                    .sum();
                if d < best.0 {
                    best = (d, j);
                }
            }
            *slot = best.1 as u8;
        }
        GifPalette { colours, lut }
    }

    /// Palette indices for every pixel.
    pub fn map(&self, img: &RgbImage) -> Vec<u8> {
        img.data
            .chunks_exact(3)
            .map(|p| self.lut[cell_index(p)])
            .collect()
    }
}

/// The channel with the widest range of cell keys in a box, and that range.
fn widest(b: &[Cell]) -> (usize, u8) {
    (0..3)
        .map(|k| {
            let lo = b.iter().map(|c| c.key[k]).min().unwrap_or(0);
            let hi = b.iter().map(|c| c.key[k]).max().unwrap_or(0);
            (k, hi - lo)
        })
        .max_by_key(|&(k, r)| (r, std::cmp::Reverse(k)))
        .unwrap_or((0, 0))
}

/// Streams frames into an in-memory GIF that loops forever.
pub struct GifBuilder {
    enc: gif::Encoder<Vec<u8>>,
    palette: GifPalette,
    delay_cs: u16,
    width: u16,
    height: u16,
}

impl GifBuilder {
    /// `fps` is rounded to GIF's centisecond delays (at least 2 cs: browsers
    /// slow down faster GIFs).
    pub fn new(width: u32, height: u32, fps: f64, palette: GifPalette) -> Result<Self, String> {
        let (w, h) = (
            u16::try_from(width).map_err(|_| "GIF too wide")?,
            u16::try_from(height).map_err(|_| "GIF too tall")?,
        );
        let mut enc =
            gif::Encoder::new(Vec::new(), w, h, &palette.colours).map_err(|e| e.to_string())?;
        enc.set_repeat(gif::Repeat::Infinite)
            .map_err(|e| e.to_string())?;
        let fps = if fps.is_finite() && fps > 0.0 {
            fps
        } else {
            25.0
        };
        let delay_cs = (100.0 / fps).round().clamp(2.0, 65535.0) as u16;
        Ok(GifBuilder {
            enc,
            palette,
            delay_cs,
            width: w,
            height: h,
        })
    }

    pub fn delay_cs(&self) -> u16 {
        self.delay_cs
    }

    /// Appends a frame (must have the GIF's size).
    pub fn push(&mut self, img: &RgbImage) -> Result<(), String> {
        if img.width != self.width as u32 || img.height != self.height as u32 {
            return Err(format!(
                "frame is {}x{}, GIF is {}x{}",
                img.width, img.height, self.width, self.height
            ));
        }
        let mut frame = gif::Frame::default();
        frame.width = self.width;
        frame.height = self.height;
        frame.delay = self.delay_cs;
        frame.buffer = std::borrow::Cow::Owned(self.palette.map(img));
        self.enc.write_frame(&frame).map_err(|e| e.to_string())
    }

    /// The finished GIF bytes.
    pub fn finish(self) -> Result<Vec<u8>, String> {
        self.enc.into_inner().map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gif_round_trip_has_frames_size_and_close_colours() {
        let mut a = RgbImage::new(16, 8, [255, 255, 255]);
        a.fill_rect(2, 2, 5, 4, [72, 132, 204]);
        let mut b = RgbImage::new(16, 8, [255, 255, 255]);
        b.fill_rect(8, 1, 6, 6, [232, 128, 48]);
        let pal = GifPalette::learn(&[&a, &b]);
        let mut g = GifBuilder::new(16, 8, 10.0, pal).unwrap();
        assert_eq!(g.delay_cs(), 10);
        for img in [&a, &b, &a] {
            g.push(img).unwrap();
        }
        assert!(g.push(&RgbImage::new(3, 3, [0; 3])).is_err());
        let bytes = g.finish().unwrap();
        let mut opts = gif::DecodeOptions::new();
        opts.set_color_output(gif::ColorOutput::RGBA);
        let mut d = opts.read_info(std::io::Cursor::new(bytes)).unwrap();
        let mut n = 0;
        while let Some(f) = d.read_next_frame().unwrap() {
            assert_eq!((f.width, f.height, f.delay), (16, 8, 10));
            let src = if n == 1 { &b } else { &a };
            for (q, p) in f.buffer.chunks_exact(4).zip(src.data.chunks_exact(3)) {
                // Fewer than 256 distinct colours: exact.
                assert_eq!(&q[..3], p);
            }
            n += 1;
        }
        assert_eq!(n, 3);
    }

    #[test]
    fn median_cut_keeps_many_colours_close() {
        // A smooth 64x64 gradient (4096 colours, 1024 histogram cells) into 256
        // boxes of ~2x2 cells (16 levels a side): error within one box width.
        let mut img = RgbImage::new(64, 64, [0; 3]);
        for y in 0..64 {
            for x in 0..64 {
                img.put(x, y, [(x * 4) as u8, (y * 4) as u8, 128]);
            }
        }
        let pal = GifPalette::learn(&[&img]);
        let idx = pal.map(&img);
        let mut worst = 0;
        for (i, p) in img.data.chunks_exact(3).enumerate() {
            let q = &pal.colours[3 * idx[i] as usize..3 * idx[i] as usize + 3];
            worst = worst.max(
                (0..3)
                    .map(|k| (p[k] as i32 - q[k] as i32).abs())
                    .max()
                    .unwrap(),
            );
        }
        assert!(worst <= 16, "worst channel error {worst}");
    }
}
