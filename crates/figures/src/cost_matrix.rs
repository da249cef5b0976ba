//! CVPR figure 3: the association cost matrix of one training pair with its DTW path, key-poses
//! and true correspondences.

use std::path::Path;

use gp::blr::{cost_matrix, PartFrames};
use gp::dtw::{dtw_path, DtwOptions};
use mesh_core::{Error, Result};
use nalgebra::DMatrix;

use crate::plot::{draw_legend, legend_line, png_bytes, register_font};

/// Figure 3's data: the cost matrix (`F_s x F_t`), the DTW path, the
/// key-poses and optionally the true correspondences.
#[derive(Clone, Debug)]
pub struct CostFigure {
    pub title: String,
    pub cost: DMatrix<f64>,
    pub path: Vec<[usize; 2]>,
    pub keyposes: Vec<[usize; 2]>,
    pub truth: Option<Vec<[usize; 2]>>,
}

/// Where cell `(i, j)` of the matrix lands in the image: pixel
/// `(x0 + (i + 0.5) · cell_w, y0 - (j + 0.5) · cell_h)` is its centre
/// (`y0` is the bottom edge of the plotting area).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostLayout {
    pub x0: f64,
    pub y0: f64,
    pub cell_w: f64,
    pub cell_h: f64,
}

impl CostLayout {
    pub fn centre(&self, i: usize, j: usize) -> (u32, u32) {
        (
            (self.x0 + (i as f64 + 0.5) * self.cell_w).round() as u32,
            (self.y0 - (j as f64 + 0.5) * self.cell_h).round() as u32,
        )
    }
}

/// Colour of the DTW path.
pub const PATH_COLOUR: [u8; 3] = [255, 255, 255];
/// Colour of the true correspondences.
pub const TRUTH_COLOUR: [u8; 3] = [255, 64, 160];
/// Colour of the key-pose markers.
pub const KEY_COLOUR: [u8; 3] = [230, 30, 30];

/// The cost matrix of CVPR eqs. 1-6 and the DTW path of eq. 7 through the
/// key-poses, from per-part coefficients of both motions (as `dtw-densify`).
pub fn cost_and_path(
    source_parts: &[DMatrix<f64>],
    target_parts: &[DMatrix<f64>],
    keyposes: &[[usize; 2]],
    sigma2: f64,
) -> Result<(DMatrix<f64>, Vec<[usize; 2]>)> {
    if source_parts.len() != target_parts.len() {
        return Err(Error::invalid(format!(
            "the source has {} parts and the target {}",
            source_parts.len(),
            target_parts.len()
        )));
    }
    let parts: Vec<PartFrames> = source_parts
        .iter()
        .zip(target_parts)
        .map(|(s, t)| PartFrames {
            source: s,
            target: t,
        })
        .collect();
    let keys: Vec<(usize, usize)> = keyposes.iter().map(|k| (k[0], k[1])).collect();
    let cost = cost_matrix(&parts, &keys, sigma2).map_err(|e| Error::invalid(e.to_string()))?;
    let path = dtw_path(&cost, &keys, &DtwOptions::default())
        .map_err(|e| Error::invalid(e.to_string()))?;
    Ok((cost, path.into_iter().map(|(i, j)| [i, j]).collect()))
}

/// Viridis-like ramp, `t` in `[0, 1]`.
fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let k = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - k as f64;
    std::array::from_fn(|c| (STOPS[k][c] * (1.0 - f) + STOPS[k + 1][c] * f).round() as u8)
}

impl CostFigure {
    /// `ln(1 + cost)` clipped to its 2nd-98th percentiles, mapped to `[0, 1]`.
    fn normalised(&self) -> DMatrix<f64> {
        let v = self.cost.map(|c| (1.0 + c.max(0.0)).ln());
        let mut sorted: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        sorted.sort_by(f64::total_cmp);
        let q = |p: f64| {
            sorted
                .get(((sorted.len().max(1) - 1) as f64 * p).round() as usize)
                .copied()
                .unwrap_or(0.0)
        };
        let (lo, hi) = (q(0.02), q(0.98));
        let span = (hi - lo).max(1e-12);
        v.map(|x| if x.is_finite() { (x - lo) / span } else { 1.0 })
    }

    fn draw<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<CostLayout, String> {
        use plotters::prelude::*;
        let e = |x: &dyn std::fmt::Debug| format!("{x:?}");
        let (fs, ft) = (self.cost.nrows(), self.cost.ncols());
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(56)
            .build_cartesian_2d(0f64..fs as f64, 0f64..ft as f64)
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("source frame i")
            .y_desc("target frame j")
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(|x| e(&x))?;
        let norm = self.normalised();
        chart
            .draw_series((0..fs).flat_map(|i| {
                let norm = &norm;
                (0..ft).map(move |j| {
                    let [r, g, b] = ramp(norm[(i, j)]);
                    Rectangle::new(
                        [(i as f64, j as f64), ((i + 1) as f64, (j + 1) as f64)],
                        RGBColor(r, g, b).filled(),
                    )
                })
            }))
            .map_err(|x| e(&x))?;
        let centre = |p: &[usize; 2]| (p[0] as f64 + 0.5, p[1] as f64 + 0.5);
        let rgb = |c: [u8; 3]| RGBColor(c[0], c[1], c[2]);
        if let Some(truth) = &self.truth {
            chart
                .draw_series(LineSeries::new(
                    truth.iter().map(centre),
                    rgb(TRUTH_COLOUR).stroke_width(3),
                ))
                .map_err(|x| e(&x))?
                .label("true correspondences")
                .legend(legend_line(rgb(TRUTH_COLOUR).stroke_width(2), 18));
        }
        chart
            .draw_series(LineSeries::new(
                self.path.iter().map(centre),
                rgb(PATH_COLOUR).stroke_width(3),
            ))
            .map_err(|x| e(&x))?
            .label("DTW path (eq. 7)")
            .legend(legend_line(BLACK.stroke_width(2), 18));
        chart
            .draw_series(
                self.keyposes
                    .iter()
                    .map(|k| Circle::new(centre(k), 6, rgb(KEY_COLOUR).stroke_width(2))),
            )
            .map_err(|x| e(&x))?
            .label("key-poses")
            .legend(move |(x, y)| Circle::new((x + 9, y), 5, rgb(KEY_COLOUR).stroke_width(2)));
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight, 0.85).map_err(|x| e(&x))?;
        let (a, b) = (
            chart.backend_coord(&(0.0, 0.0)),
            chart.backend_coord(&(fs as f64, ft as f64)),
        );
        root.present().map_err(|x| e(&x))?;
        Ok(CostLayout {
            x0: a.0 as f64,
            y0: a.1 as f64,
            cell_w: (b.0 - a.0) as f64 / fs as f64,
            cell_h: (a.1 - b.1) as f64 / ft as f64,
        })
    }

    /// Image size: about 4 pixels per frame, within 480..1400.
    pub fn size(&self) -> (u32, u32) {
        let s = |n: usize| ((n * 4 + 140) as u32).clamp(480, 1400);
        (s(self.cost.nrows()), s(self.cost.ncols()))
    }

    /// Writes the PNG at `png` (and, with `svg`, the SVG); returns the layout.
    pub fn write(&self, png: &Path, svg: Option<&Path>) -> Result<CostLayout> {
        use plotters::prelude::*;
        register_font();
        if self.cost.is_empty() {
            return Err(Error::file(png, "empty cost matrix"));
        }
        let (w, h) = self.size();
        let mut pixels = vec![0u8; (w * h * 3) as usize];
        let layout = self
            .draw(BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area())
            .map_err(|m| Error::file(png, format!("cannot draw the figure: {m}")))?;
        mesh_core::atomic::write_bytes_atomic(png, &png_bytes(png, &pixels, w, h)?)?;
        if let Some(svg) = svg {
            let mut text = String::new();
            self.draw(SVGBackend::with_string(&mut text, (w, h)).into_drawing_area())
                .map_err(|m| Error::file(svg, format!("cannot draw the figure: {m}")))?;
            mesh_core::atomic::write_bytes_atomic(svg, text.as_bytes())?;
        }
        Ok(layout)
    }
}
