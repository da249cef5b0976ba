//! Plots, PNG written atomically: latent trajectories (the training sequences of one part, paper
//! fig. 3; sampled variations of one sequence, fig. 5; projected on the first two latent
//! coordinates) and values against an index (errors per part, fig. 4; per frame, fig. 7b).

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
    write_png(path, w, h, &pixels)
}

/// Encodes RGB `pixels` (`w × h`) as PNG and writes it atomically.
fn write_png(path: &Path, w: u32, h: u32, pixels: &[u8]) -> Result<()> {
    let e = |x: &dyn std::fmt::Debug| Error::file(path, format!("plot: {x:?}"));
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|x| e(&x))?;
        writer.write_image_data(pixels).map_err(|x| e(&x))?;
    }
    mesh_core::atomic::write_bytes_atomic(path, &bytes)
}

/// Plots each `(label, values)` against its index (0, 1, ...) as a polyline with a marker per
/// value, from 0 up; `ticks` names the indices (e.g. the parts) when given. Non-finite values
/// are left out.
pub fn series_plot(
    path: &Path,
    title: &str,
    axes: (&str, &str),
    ticks: Option<&[String]>,
    series: &[(String, Vec<f64>)],
) -> Result<()> {
    use plotters::prelude::*;
    register_font();
    let e = |x: &dyn std::fmt::Debug| Error::file(path, format!("plot: {x:?}"));
    let (w, h) = (720u32, 480u32);
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let n = series.iter().map(|(_, v)| v.len()).max().unwrap_or(0).max(1);
        let top = series.iter().flat_map(|(_, v)| v.iter().copied()).filter(|v| v.is_finite()).fold(0.0, f64::max);
        let top = if top > 0.0 { 1.1 * top } else { 1.0 };
        let x_max = (n - 1).max(1) as f64;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(-0.05 * x_max..1.05 * x_max, 0.0..top)
            .map_err(|x| e(&x))?;
        let names = ticks.map(<[String]>::to_vec);
        let tick = move |x: &f64| match &names {
            Some(t) if (x - x.round()).abs() < 1e-9 && x.round() >= 0.0 => {
                t.get(x.round() as usize).cloned().unwrap_or_default()
            }
            Some(_) => String::new(),
            None => format!("{x:.0}"),
        };
        chart
            .configure_mesh()
            .x_desc(axes.0)
            .y_desc(axes.1)
            .x_labels(ticks.map_or(10, |t| t.len().max(2)))
            .x_label_formatter(&tick)
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(|x| e(&x))?;
        for (i, (label, v)) in series.iter().enumerate() {
            let (r, g, b) = COLOURS[i % COLOURS.len()];
            let c = RGBColor(r, g, b);
            let pts: Vec<(f64, f64)> =
                v.iter().enumerate().filter(|(_, y)| y.is_finite()).map(|(x, &y)| (x as f64, y)).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
                .map_err(|x| e(&x))?
                .label(label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
            if ticks.is_some() || pts.len() <= 40 {
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled()))).map_err(|x| e(&x))?;
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .draw()
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
    }
    write_png(path, w, h, &pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The decoded image's pixels of exactly `colour`.
    fn count(path: &Path, colour: (u8, u8, u8)) -> usize {
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf[..info.buffer_size()].chunks(3).filter(|p| (p[0], p[1], p[2]) == colour).count()
    }

    #[test]
    fn a_series_plot_draws_each_series_in_its_colour_and_skips_values_that_are_not_finite() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.png");
        let ticks = vec!["torso".to_string(), "arm".to_string(), "leg".to_string()];
        let three = [("a".into(), vec![1.0, f64::NAN, 3.0]), ("b".into(), vec![2.0, 2.5, 1.0]), ("c".into(), vec![0.5, 0.7, 0.6])];
        series_plot(&p, "t", ("part", "mm"), Some(&ticks), &three).unwrap();
        assert!(count(&p, COLOURS[0]) > 100 && count(&p, COLOURS[2]) > 100);
        // Without the third series its colour is gone.
        series_plot(&p, "t", ("part", "mm"), None, &three[..2]).unwrap();
        assert_eq!(count(&p, COLOURS[2]), 0);
        assert!(count(&p, COLOURS[0]) > 100);
    }
}
