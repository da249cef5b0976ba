//! The 3DV paper's plots, PNG written atomically: latent trajectories (the training sequences of
//! one part, paper fig. 3; sampled variations of one sequence, fig. 5; pre-blends, figs. 6 and
//! 7a; projected on the first two latent coordinates) and values against an index (errors per
//! part, fig. 4; per frame, fig. 7b), and all of `variation-eval`'s figures
//! ([`write_eval_plots`]).

use std::path::Path;

use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use variation::evaluate::{EvalFigures, EvalReport, ReconstructionError};

use crate::plot::{draw_legend, legend_line, png_bytes, register_font};

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
                .legend(legend_line(c.stroke_width(2), 18));
            if let Some(&p) = line.first() {
                chart
                    .draw_series(std::iter::once(Circle::new(p, 4, c.filled())))
                    .map_err(|x| e(&x))?;
            }
        }
        if series.len() <= 8 {
            draw_legend(&mut chart, SeriesLabelPosition::MiddleRight, 0.8).map_err(|x| e(&x))?;
        }
        root.present().map_err(|x| e(&x))?;
    }
    write_png(path, w, h, &pixels)
}

/// Encodes RGB `pixels` (`w × h`) as PNG and writes it atomically.
fn write_png(path: &Path, w: u32, h: u32, pixels: &[u8]) -> Result<()> {
    mesh_core::atomic::write_bytes_atomic(path, &png_bytes(path, pixels, w, h)?)
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
                .legend(legend_line(c.stroke_width(2), 18));
            if ticks.is_some() || pts.len() <= 40 {
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled()))).map_err(|x| e(&x))?;
            }
        }
        draw_legend(&mut chart, SeriesLabelPosition::MiddleRight, 0.8).map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
    }
    write_png(path, w, h, &pixels)
}

/// `variation-eval`'s figures drawn into `dir`: the latent plots of `figures` (figs. 3, 6, 7a),
/// fig. 4 and fig. 7b from `report`, then fig. 5; returns the files written, in that order.
pub fn write_eval_plots(dir: &Path, report: &EvalReport, figures: &EvalFigures) -> Result<Vec<String>> {
    let mut written = Vec::new();
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for (file, title, series) in &figures.latent {
        let p = dir.join(file);
        latent_plot(&p, title, series)?;
        written.push(p.display().to_string());
    }
    // Fig. 4: training-mesh reconstruction per part, GPDM against PCA of the same dimension.
    let (group, d) = (&report.group, report.latent_dim);
    let parts: Vec<String> = report.reconstruction.iter().map(|r| r.part.clone()).collect();
    let mm = |f: &dyn Fn(&ReconstructionError) -> f64| report.reconstruction.iter().map(|r| 1e3 * f(r)).collect::<Vec<f64>>();
    let p = dir.join("fig4-reconstruction.png");
    series_plot(
        &p,
        &format!("{group}: training-mesh reconstruction, mean per vertex (d = {d})"),
        ("part", "error (mm)"),
        Some(&parts),
        &[(format!("GPDM (d = {d})"), mm(&|r| r.gpdm_m)), (format!("PCA ({d} components)"), mm(&|r| r.pca_m))],
    )?;
    written.push(p.display().to_string());
    // Fig. 7b: per frame, the latent interpolation guided by the learned pre-blends and the
    // unguided one against the non-linear mesh blend.
    for b in &report.latent_blend {
        let p = dir.join(format!("fig7b-blend-{}.png", b.w));
        let to_mm = |v: &[f64]| v.iter().map(|x| 1e3 * x).collect::<Vec<f64>>();
        series_plot(
            &p,
            &format!("{group}: interpolation at w = {} against the non-linear blend", b.w),
            ("frame", "mean vertex distance (mm)"),
            None,
            &[("guided".to_string(), to_mm(&b.guided_per_frame_m)), ("unguided".to_string(), to_mm(&b.unguided_per_frame_m))],
        )?;
        written.push(p.display().to_string());
    }
    let (file, title, series) = &figures.variations;
    let p = dir.join(file);
    latent_plot(&p, title, series)?;
    written.push(p.display().to_string());
    Ok(written)
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

    /// Every figure of `variation-eval` is written as a PNG, in the report's order: the latent
    /// plots, fig. 4, fig. 7b per blend weight, fig. 5.
    #[test]
    fn the_evaluation_figures_are_written_in_order() {
        use variation::evaluate::LatentBlendError;
        let dir = tempfile::tempdir().unwrap();
        let rec = |part: &str, g: f64| ReconstructionError { part: part.into(), vertices: 10, gpdm_m: g, pca_m: 2.0 * g };
        let blend = |w: f64| LatentBlendError {
            w,
            guided_from: (0.0, 0.5),
            guided_per_frame_m: vec![0.001, 0.002, 0.0015],
            unguided_per_frame_m: vec![0.002, 0.003, 0.0025],
            guided_m: 0.0015,
            unguided_m: 0.0025,
        };
        let report = EvalReport {
            group: "walk".into(),
            latent_dim: 3,
            reconstruction: vec![rec("torso", 0.001), rec("arm", 0.002)],
            reconstruction_gpdm_m: 0.0015,
            reconstruction_pca_m: 0.003,
            latent_blend: vec![blend(0.25), blend(0.75)],
            mean_prediction: Vec::new(),
            plots: Vec::new(),
        };
        let circle = DMatrix::from_fn(30, 3, |t, c| ((t as f64) * 0.2 + c as f64).sin());
        let figures = EvalFigures {
            latent: vec![("fig3-latent-torso.png".into(), "fig 3".into(), vec![("walk".into(), circle.clone())])],
            variations: ("fig5-variations-walk-torso.png".into(), "fig 5".into(), vec![("var0".into(), circle)]),
        };
        let written = write_eval_plots(dir.path(), &report, &figures).unwrap();
        let names: Vec<String> = written.iter().map(|p| Path::new(p).file_name().unwrap().to_string_lossy().into_owned()).collect();
        assert_eq!(
            names,
            ["fig3-latent-torso.png", "fig4-reconstruction.png", "fig7b-blend-0.25.png", "fig7b-blend-0.75.png", "fig5-variations-walk-torso.png"]
        );
        for p in &written {
            assert!(count(Path::new(p), COLOURS[0]) > 100, "{p}: the first series is not drawn");
        }
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
