//! Latent trajectory plots: the training sequences of one part (paper fig. 3) and sampled
//! variations of one sequence (fig. 5), projected on the first two latent coordinates; PNG
//! written atomically.

use std::path::Path;

use mesh_core::{Error, Result};
use nalgebra::DMatrix;

use mesh_core::font::DEJAVU_SANS as FONT;

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ =
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
}

/// Distinct colours (cycled).
pub const COLOURS: [(u8, u8, u8); 8] = [
    (31, 119, 180),
    (0, 0, 0),
    (23, 190, 207),
    (214, 39, 140),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
];

/// Plots each `(label, trajectory)` (T × d, d ≥ 2) as a polyline in the (x₁, x₂) plane.
pub fn latent_plot(path: &Path, title: &str, series: &[(String, DMatrix<f64>)]) -> Result<()> {
    use plotters::prelude::*;
    register_font();
    let e = |x: &dyn std::fmt::Debug| Error::file(path, format!("plot: {x:?}"));
    let (w, h) = (720u32, 560u32);
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let pts = series.iter().flat_map(|(_, m)| {
            (0..m.nrows()).map(move |t| (m[(t, 0)], m[(t, 1.min(m.ncols() - 1))]))
        });
        let (mut x0, mut x1, mut y0, mut y1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for (x, y) in pts {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        if !x0.is_finite() {
            (x0, x1, y0, y1) = (-1.0, 1.0, -1.0, 1.0);
        }
        let (px, py) = (0.05 * (x1 - x0).max(1e-9), 0.05 * (y1 - y0).max(1e-9));
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(48)
            .build_cartesian_2d(x0 - px..x1 + px, y0 - py..y1 + py)
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc("x1")
            .y_desc("x2")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(|x| e(&x))?;
        for (i, (label, m)) in series.iter().enumerate() {
            let (r, g, b) = COLOURS[i % COLOURS.len()];
            let c = RGBColor(r, g, b);
            let line: Vec<(f64, f64)> = (0..m.nrows())
                .map(|t| (m[(t, 0)], m[(t, 1.min(m.ncols() - 1))]))
                .collect();
            chart
                .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
                .map_err(|x| e(&x))?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
            if let Some(&p) = line.first() {
                chart
                    .draw_series(std::iter::once(Circle::new(p, 4, c.filled())))
                    .map_err(|x| e(&x))?;
            }
        }
        if series.len() <= 8 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 12))
                .draw()
                .map_err(|x| e(&x))?;
        }
        root.present().map_err(|x| e(&x))?;
    }
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|x| e(&x))?;
        writer.write_image_data(&pixels).map_err(|x| e(&x))?;
    }
    mesh_core::atomic::write_bytes_atomic(path, &bytes)
}
