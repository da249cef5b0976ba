//! Z-buffered rasterization of triangles and lines into a colour + depth target.
//!
//! Coverage uses edge functions evaluated at pixel centres with the top-left
//! fill rule, so triangles sharing an edge cover each pixel exactly once.
//! Depth keys are affine in screen space and larger = nearer (see
//! [`crate::camera::Camera`]); colours are interpolated linearly in screen
//! space (Gouraud) from the per-vertex shaded colours.

use crate::colour::Rgb;
use crate::image::RgbImage;

/// A screen-space vertex: pixel x, pixel y, depth key (larger = nearer).
pub type ScreenVertex = [f32; 3];

/// Colour and depth buffers, `width * height` pixels.
pub struct Target {
    pub width: u32,
    pub height: u32,
    /// RGB bytes, row-major, top row first.
    pub colour: Vec<u8>,
    pub depth: Vec<f32>,
}

impl Target {
    pub fn new(width: u32, height: u32, background: Rgb) -> Self {
        let img = RgbImage::new(width, height, background);
        Target {
            width,
            height,
            colour: img.data,
            depth: vec![f32::NEG_INFINITY; width as usize * height as usize],
        }
    }

    /// Draws a triangle with per-vertex colours (0..255). Degenerate,
    /// non-finite or off-screen triangles draw nothing, nor do triangles with
    /// a vertex more than 2^20 pixels off the image (guard band).
    ///
    /// Vertices are snapped to 1/16 pixel and edge functions evaluated
    /// exactly in integers, stepped incrementally along each row; depth and
    /// colour are interpolated with barycentric weights from the same edge values.
    pub fn fill_triangle(&mut self, v: [ScreenVertex; 3], c: [[f32; 3]; 3]) {
        const SUB: i64 = 16;
        const LIMIT: f32 = (1 << 20) as f32;
        if !v
            .iter()
            .all(|p| p[0].abs() < LIMIT && p[1].abs() < LIMIT && p[2].is_finite())
        {
            return;
        }
        let snap = |p: &ScreenVertex| {
            [
                (p[0] * SUB as f32).round() as i64,
                (p[1] * SUB as f32).round() as i64,
            ]
        };
        let (mut q, mut z, mut col) = (
            [snap(&v[0]), snap(&v[1]), snap(&v[2])],
            [v[0][2], v[1][2], v[2][2]],
            c,
        );
        let mut area =
            (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
        if area == 0 {
            return;
        }
        if area < 0 {
            q.swap(1, 2);
            z.swap(1, 2);
            col.swap(1, 2);
            area = -area;
        }
        // Pixel x is sampled at 16x + 8 (its centre) in fixed point.
        let half = SUB / 2;
        let lo = |m: i64| -((half - m).div_euclid(SUB)); // ceil((m - half) / SUB)
        let hi = |m: i64| (m - half).div_euclid(SUB);
        let xmin = lo(q[0][0].min(q[1][0]).min(q[2][0])).max(0);
        let xmax = hi(q[0][0].max(q[1][0]).max(q[2][0])).min(self.width as i64 - 1);
        let ymin = lo(q[0][1].min(q[1][1]).min(q[2][1])).max(0);
        let ymax = hi(q[0][1].max(q[1][1]).max(q[2][1])).min(self.height as i64 - 1);
        if xmin > xmax || ymin > ymax {
            return;
        }
        // Edge a->b: E(p) = dx (py - ay) - dy (px - ax), positive inside for this
        // winding. Top-left rule (y down): top edge dy == 0 && dx > 0, left edge
        // dy < 0; other edges exclude E == 0 through a bias of -1.
        struct Edge {
            w: i64,
            step_x: i64,
            step_y: i64,
            bias: i64,
        }
        let (px0, py0) = (xmin * SUB + half, ymin * SUB + half);
        let edge = |a: [i64; 2], b: [i64; 2]| {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let bias = if (dy == 0 && dx > 0) || dy < 0 { 0 } else { -1 };
            Edge {
                w: dx * (py0 - a[1]) - dy * (px0 - a[0]) + bias,
                step_x: -dy * SUB,
                step_y: dx * SUB,
                bias,
            }
        };
        let mut e0 = edge(q[1], q[2]); // weight of vertex 0
        let mut e1 = edge(q[2], q[0]); // weight of vertex 1
        let mut e2 = edge(q[0], q[1]); // weight of vertex 2
        let inv = 1.0 / area as f32;
        let dz = [z[1] - z[0], z[2] - z[0]];
        let dc: [[f32; 2]; 3] =
            std::array::from_fn(|k| [col[1][k] - col[0][k], col[2][k] - col[0][k]]);
        let width = self.width as usize;
        for y in ymin..=ymax {
            let (mut w0, mut w1, mut w2) = (e0.w, e1.w, e2.w);
            let row = y as usize * width;
            let mut entered = false;
            for x in xmin..=xmax {
                if (w0 | w1 | w2) >= 0 {
                    entered = true;
                    let l1 = (w1 - e1.bias) as f32 * inv;
                    let l2 = (w2 - e2.bias) as f32 * inv;
                    let d = z[0] + l1 * dz[0] + l2 * dz[1];
                    let i = row + x as usize;
                    if d > self.depth[i] {
                        self.depth[i] = d;
                        let k = 3 * i;
                        for ch in 0..3 {
                            let val = col[0][ch] + l1 * dc[ch][0] + l2 * dc[ch][1];
                            self.colour[k + ch] = (val + 0.5).clamp(0.0, 255.0) as u8;
                        }
                    }
                } else if entered {
                    break; // convex: the row's span is over
                }
                w0 += e0.step_x;
                w1 += e1.step_x;
                w2 += e2.step_x;
            }
            e0.w += e0.step_y;
            e1.w += e1.step_y;
            e2.w += e2.step_y;
        }
    }

    /// Draws a depth-tested 1-pixel line (DDA) clipped to the target.
    pub fn draw_line(&mut self, a: ScreenVertex, b: ScreenVertex, colour: Rgb) {
        let Some((a, b)) = clip_segment(a, b, self.width as f32, self.height as f32) else {
            return;
        };
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let steps = dx.abs().max(dy.abs()).ceil().max(1.0) as usize;
        let width = self.width as usize;
        for s in 0..=steps {
            let t = s as f32 / steps as f32;
            let x = (a[0] + dx * t).floor() as i64;
            let y = (a[1] + dy * t).floor() as i64;
            if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
                continue;
            }
            let z = a[2] + (b[2] - a[2]) * t;
            let i = y as usize * width + x as usize;
            if z > self.depth[i] {
                self.depth[i] = z;
                self.colour[3 * i..3 * i + 3].copy_from_slice(&colour);
            }
        }
    }

    /// Box-filters `s x s` blocks down to an image (`s = 1` copies).
    pub fn resolve(&self, s: u32) -> RgbImage {
        let s = s.max(1);
        let (ow, oh) = (self.width / s, self.height / s);
        if s == 1 {
            return RgbImage {
                width: ow,
                height: oh,
                data: self.colour.clone(),
            };
        }
        if s == 2 {
            return self.resolve_2x2();
        }
        let (s, w) = (s as usize, self.width as usize);
        let (ow, oh) = (ow as usize, oh as usize);
        let n = (s * s) as u32;
        let mut data = vec![0u8; 3 * ow * oh];
        let mut acc = vec![0u32; 3 * ow];
        for oy in 0..oh {
            acc.iter_mut().for_each(|a| *a = 0);
            for dy in 0..s {
                let src = &self.colour[3 * (oy * s + dy) * w..3 * (oy * s + dy + 1) * w];
                for (ox, a) in acc.chunks_exact_mut(3).enumerate() {
                    let block = &src[3 * ox * s..3 * (ox + 1) * s];
                    for px in block.chunks_exact(3) {
                        a[0] += px[0] as u32;
                        a[1] += px[1] as u32;
                        a[2] += px[2] as u32;
                    }
                }
            }
            for (d, a) in data[3 * oy * ow..3 * (oy + 1) * ow].iter_mut().zip(&acc) {
                *d = ((a + n / 2) / n) as u8;
            }
        }
        let (ow, oh) = (ow as u32, oh as u32);
        RgbImage {
            width: ow,
            height: oh,
            data,
        }
    }
}

impl Target {
    /// [`Target::resolve`] for 2x2 blocks (the default anti-aliasing).
    fn resolve_2x2(&self) -> RgbImage {
        let (w, ow, oh) = (
            self.width as usize,
            self.width as usize / 2,
            self.height as usize / 2,
        );
        let mut data = vec![0u8; 3 * ow * oh];
        for (oy, out) in data.chunks_exact_mut(3 * ow).enumerate() {
            let r0 = &self.colour[3 * (2 * oy) * w..][..6 * ow];
            let r1 = &self.colour[3 * (2 * oy + 1) * w..][..6 * ow];
            for ((o, a), b) in out
                .chunks_exact_mut(3)
                .zip(r0.chunks_exact(6))
                .zip(r1.chunks_exact(6))
            {
                for k in 0..3 {
                    o[k] = ((a[k] as u16 + a[k + 3] as u16 + b[k] as u16 + b[k + 3] as u16 + 2)
                        >> 2) as u8;
                }
            }
        }
        RgbImage {
            width: ow as u32,
            height: oh as u32,
            data,
        }
    }
}

/// Liang-Barsky clip of a segment to `[0,w] x [0,h]`, depth interpolated.
fn clip_segment(
    a: ScreenVertex,
    b: ScreenVertex,
    w: f32,
    h: f32,
) -> Option<(ScreenVertex, ScreenVertex)> {
    if !(a.iter().chain(b.iter()).all(|v| v.is_finite())) {
        return None;
    }
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [(-dx, a[0]), (dx, w - a[0]), (-dy, a[1]), (dy, h - a[1])] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f32| [a[0] + dx * t, a[1] + dy * t, a[2] + (b[2] - a[2]) * t];
    Some((at(t0), at(t1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn covered(t: &Target) -> usize {
        t.depth.iter().filter(|d| d.is_finite()).count()
    }

    #[test]
    fn axis_aligned_square_covers_exactly_its_pixels() {
        let mut t = Target::new(20, 20, [255; 3]);
        let c = [[0.0; 3]; 3];
        let (a, b, cc, d) = (
            [2.0, 3.0, 0.0],
            [12.0, 3.0, 0.0],
            [12.0, 9.0, 0.0],
            [2.0, 9.0, 0.0],
        );
        t.fill_triangle([a, b, cc], c);
        t.fill_triangle([a, cc, d], c);
        // 10 x 6 pixels, shared diagonal counted once (top-left rule).
        assert_eq!(covered(&t), 60);
        assert_eq!(t.colour[3 * (5 * 20 + 5)], 0);
    }

    #[test]
    fn shared_edges_leave_no_gaps_or_double_cover() {
        // A fan of triangles around an off-grid centre covers a polygon;
        // count how often each pixel is written using depth increments.
        let mut t = Target::new(64, 64, [255; 3]);
        let centre = [31.3f32, 30.7];
        let n = 17;
        let mut writes = vec![0u32; 64 * 64];
        for k in 0..n {
            let a0 = k as f32 / n as f32 * std::f32::consts::TAU;
            let a1 = (k + 1) as f32 / n as f32 * std::f32::consts::TAU;
            let p = |a: f32| [centre[0] + 25.0 * a.cos(), centre[1] + 25.0 * a.sin(), 0.0];
            let mut single = Target::new(64, 64, [255; 3]);
            single.fill_triangle([[centre[0], centre[1], 0.0], p(a0), p(a1)], [[0.0; 3]; 3]);
            for (i, d) in single.depth.iter().enumerate() {
                if d.is_finite() {
                    writes[i] += 1;
                }
            }
            t.fill_triangle([[centre[0], centre[1], 0.0], p(a0), p(a1)], [[0.0; 3]; 3]);
        }
        assert!(writes.iter().all(|&w| w <= 1), "a pixel was covered twice");
        // Polygon area = n/2 r^2 sin(2 pi / n).
        let area = n as f32 / 2.0 * 625.0 * (std::f32::consts::TAU / n as f32).sin();
        assert!(
            (covered(&t) as f32 - area).abs() / area < 0.02,
            "{} vs {area}",
            covered(&t)
        );
    }

    #[test]
    fn nearer_wins_regardless_of_order() {
        for order in [false, true] {
            let mut t = Target::new(10, 10, [255; 3]);
            let near = (
                [[0.0, 0.0, 2.0], [10.0, 0.0, 2.0], [0.0, 10.0, 2.0]],
                [[255.0, 0.0, 0.0]; 3],
            );
            let far = (
                [[0.0, 0.0, 1.0], [10.0, 0.0, 1.0], [0.0, 10.0, 1.0]],
                [[0.0, 0.0, 255.0]; 3],
            );
            let (first, second) = if order { (near, far) } else { (far, near) };
            t.fill_triangle(first.0, first.1);
            t.fill_triangle(second.0, second.1);
            assert_eq!(&t.colour[0..3], &[255, 0, 0]);
        }
    }

    #[test]
    fn resolve_averages_blocks() {
        let mut t = Target::new(4, 2, [0; 3]);
        t.colour[0..3].copy_from_slice(&[255, 255, 255]);
        t.colour[3..6].copy_from_slice(&[255, 255, 255]);
        let img = t.resolve(2);
        assert_eq!((img.width, img.height), (2, 1));
        assert_eq!(img.get(0, 0), [128, 128, 128]);
        assert_eq!(img.get(1, 0), [0, 0, 0]);
    }

    #[test]
    fn resolve_3x3_averages_blocks() {
        let mut t = Target::new(6, 3, [0; 3]);
        for k in 0..3 {
            // Three of nine pixels of the first block are 90: mean 30.
            let i = 3 * (k * 6 + k % 3);
            t.colour[i..i + 3].copy_from_slice(&[90, 90, 90]);
        }
        t.colour[3 * 5..3 * 5 + 3].copy_from_slice(&[255, 0, 9]);
        let img = t.resolve(3);
        assert_eq!((img.width, img.height), (2, 1));
        assert_eq!(img.get(0, 0), [30, 30, 30]);
        assert_eq!(img.get(1, 0), [28, 0, 1]);
    }

    #[test]
    fn lines_are_clipped_and_depth_tested() {
        let mut t = Target::new(10, 10, [255; 3]);
        t.draw_line([-100.0, 5.5, 0.0], [100.0, 5.5, 0.0], [0, 0, 0]);
        assert_eq!(covered(&t), 10);
        t.fill_triangle(
            [[0.0, 0.0, 1.0], [10.0, 0.0, 1.0], [0.0, 10.0, 1.0]],
            [[9.0; 3]; 3],
        );
        t.draw_line([0.0, 2.5, 0.5], [10.0, 2.5, 0.5], [0, 0, 0]);
        assert_eq!(
            &t.colour[3 * (2 * 10 + 1)..3 * (2 * 10 + 1) + 3],
            &[9, 9, 9]
        );
    }
}
