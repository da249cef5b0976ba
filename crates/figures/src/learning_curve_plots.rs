//! The learning-curve plots (CVPR figs. 7-9): per direction, the curves of
//! [`transfer::learning_curves`] as PNG and SVG, training and held-out errors against the
//! training-set size, the PCA truncation floors dashed.

use std::path::Path;

use mesh_core::{Error, Result};
use transfer::learning_curves::{truncation_label, CurvePoint, CURVES};

use crate::plot::{draw_legend, legend_line, png_bytes, register_font};

/// The figures: `(file stem, title, curve labels)`; the PCA truncation floor
/// of the figure's representation(s) is drawn too.
pub fn figures() -> Vec<(&'static str, &'static str, Vec<String>)> {
    let l = |i: usize| CURVES[i].label();
    vec![
        (
            "fig7-kernels",
            "Kernels and key-pose affine baseline",
            vec![l(0), l(1), l(2), l(3), truncation_label(true)],
        ),
        (
            "fig8-dense-vs-keyposes",
            "Training subsets initialised with the key-poses",
            vec![l(4), l(5), l(6), l(7), truncation_label(true)],
        ),
        (
            "fig9-parts-vs-whole",
            "Parts vs whole body (NN kernel)",
            vec![l(0), l(8), truncation_label(true), truncation_label(false)],
        ),
    ]
}

const COLOURS: [plotters::style::RGBColor; 4] = [
    plotters::style::RGBColor(31, 119, 180),
    plotters::style::RGBColor(255, 127, 14),
    plotters::style::RGBColor(44, 160, 44),
    plotters::style::RGBColor(214, 39, 40),
];

/// How many times the median curve's highest point the error axis reaches at most.
const CLIP_FACTOR: f64 = 3.0;

/// One series: legend name, `(n, train, test)` points, whether it is a floor.
type Series = (String, Vec<(f64, f64, f64)>, bool);

fn draw<DB: plotters::prelude::DrawingBackend>(
    root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    series: &[Series],
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let e = |x: &dyn std::fmt::Debug| format!("{x:?}");
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let all = series.iter().flat_map(|(_, p, _)| p.iter());
    let (mut x0, mut x1, mut y1) = (f64::INFINITY, 0.0f64, 0.0f64);
    for &(x, a, b) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y1 = y1.max(a).max(b);
    }
    if !x0.is_finite() {
        x0 = 0.0;
    }
    // The axis ends at CLIP_FACTOR times the median curve's highest point: a method whose error
    // explodes is drawn clipped at the top (its values held there) and its legend says so.
    let mut peaks: Vec<f64> = series
        .iter()
        .filter(|s| !s.2)
        .map(|(_, p, _)| p.iter().map(|q| q.1.max(q.2)).fold(0.0, f64::max))
        .collect();
    peaks.sort_by(f64::total_cmp);
    let median_peak = peaks.get(peaks.len() / 2).copied().unwrap_or(y1);
    let y1 = y1.min(CLIP_FACTOR * median_peak);
    let y1 = if y1 > 0.0 { y1 * 1.1 * 1000.0 } else { 1.0 };
    let top = y1 / 1.1;
    let clip = |v: f64| (v * 1000.0).min(top);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d(x0..x1.max(x0 + 1.0), 0.0..y1)
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("training pairs")
        .y_desc("RMS per-vertex error (mm)")
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(|x| e(&x))?;
    let mut colour_index = 0;
    for (name, pts, floor) in series {
        if *floor {
            let c = if name.contains("whole") {
                RGBColor(120, 120, 120)
            } else {
                BLACK
            };
            // Dashed: the held-out floor (the training floor is nearly the same).
            let (a, b) = (x0, x1.max(x0 + 1.0));
            let y = pts.first().map_or(0.0, |p| p.2) * 1000.0;
            let k = 40;
            let dashes = (0..k).step_by(2).map(move |i| {
                let (s, t) = (i as f64 / k as f64, (i + 1) as f64 / k as f64);
                PathElement::new(
                    vec![(a + (b - a) * s, y), (a + (b - a) * t, y)],
                    c.stroke_width(1),
                )
            });
            chart
                .draw_series(dashes)
                .map_err(|x| e(&x))?
                .label(name.clone())
                .legend(legend_line(c.stroke_width(1), 6));
            continue;
        }
        let c = COLOURS[colour_index % COLOURS.len()];
        colour_index += 1;
        let clipped = pts.iter().any(|p| p.1.max(p.2) * 1000.0 > top);
        let mark = if clipped { ", clipped" } else { "" };
        chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.0, clip(p.2))), c.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(format!("{name} (held out{mark})"))
            .legend(legend_line(c.stroke_width(2), 18));
        chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.0, clip(p.1))), c.mix(0.5).stroke_width(1)))
            .map_err(|x| e(&x))?
            .label(format!("{name} (training)"))
            .legend(legend_line(c.mix(0.5).stroke_width(1), 18));
        chart
            .draw_series(
                pts.iter().map(|p| Circle::new((p.0, clip(p.1)), 3, c.mix(0.5).filled())),
            )
            .map_err(|x| e(&x))?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 0.8).map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// Writes `<dir>/<direction>-<figure>.png` and `.svg` for every figure and
/// direction; `pairs` (e.g. "true pairs") goes into the titles.
pub fn plot_all(dir: &Path, points: &[CurvePoint]) -> Result<Vec<std::path::PathBuf>> {
    use plotters::prelude::*;
    register_font();
    let mut directions: Vec<&str> = points.iter().map(|p| p.direction.as_str()).collect();
    directions.dedup();
    let mut written = Vec::new();
    for d in directions {
        let pairs = points
            .iter()
            .find(|p| p.direction == d)
            .map_or("", |p| p.pairs.as_str());
        for (stem, title, labels) in figures() {
            let series: Vec<Series> = labels
                .iter()
                .map(|l| {
                    let sel: Vec<&CurvePoint> = points
                        .iter()
                        .filter(|p| p.direction == d && &p.curve == l)
                        .collect();
                    let dims = sel.first().map_or(0, |p| p.components);
                    let pts = sel
                        .iter()
                        .map(|p| (p.n_train as f64, p.train_rms_m, p.test_rms_m))
                        .collect();
                    let floor = l.starts_with("pca-truncation");
                    let name = if stem.starts_with("fig9") || floor {
                        format!("{l} ({dims} dims)")
                    } else {
                        l.clone()
                    };
                    (name, pts, floor)
                })
                .collect();
            let title = format!("{d}, {pairs} pairs: {title}");
            let name = format!("{}-{stem}", d.replace("->", "-to-"));
            let (w, h) = (800u32, 560u32);
            let png_path = dir.join(format!("{name}.png"));
            let mut pixels = vec![0u8; (w * h * 3) as usize];
            draw(
                BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area(),
                &title,
                &series,
            )
            .map_err(|m| Error::file(&png_path, format!("cannot draw the plot: {m}")))?;
            let bytes = png_bytes(&png_path, &pixels, w, h)?;
            mesh_core::atomic::write_bytes_atomic(&png_path, &bytes)?;
            written.push(png_path);
            let svg_path = dir.join(format!("{name}.svg"));
            let mut svg = String::new();
            draw(
                SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area(),
                &title,
                &series,
            )
            .map_err(|m| Error::file(&svg_path, format!("cannot draw the plot: {m}")))?;
            mesh_core::atomic::write_bytes_atomic(&svg_path, svg.as_bytes())?;
            written.push(svg_path);
        }
    }
    Ok(written)
}
