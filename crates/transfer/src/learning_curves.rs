//! Learning curves of the pose regression (paper §7, figures 7-9): RMS
//! per-vertex error on the training subset and on a held-out 30 % of the dense
//! pairs, against the training-set size.
//!
//! - Figure 7: kernels (NN, SE, linear) and the affine key-pose baseline;
//! - figure 8: dense pairs versus key-poses first (all key-pose pairs, then
//!   random dense pairs);
//! - figure 9: per-part GPs versus one whole-body GP.
//!
//! The split is seeded: the dense pairs of all training motions are shuffled
//! with ChaCha8 from `--seed`, key-pose pairs always stay on the training side,
//! and 30 % of the others are held out. Training subsets of increasing size are
//! prefixes of the shuffled training side, so they are nested.
//!
//! Error: target coefficients are compared after mapping back to vertices.
//! PCA axes are orthonormal, so `|decode(a) - decode(b)|² = |a - b|²` and the
//! per-vertex RMS is `sqrt(Σ_parts |Δc_k|² / (rows · Σ_parts n_k))` with `n_k`
//! the part's vertex count (vertices on overlap bands count once per part).
//! PCA truncation error is not included (it is the same for every method).
//! The displacement GP is not part of these curves. The key-pose affine
//! baseline is fitted on the key-poses only at every size (a flat curve).

use std::path::Path;

use gp::gpr::GprOptions;
use mesh_core::{Error, Result};
use nalgebra::DMatrix;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::gpr_model::{train, GprModel, Method, PairData, TrainingSet};

/// Which training rows a curve uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Rows {
    /// Random dense pairs.
    Dense,
    /// All key-pose pairs first, then random dense pairs.
    KeyposesFirst,
}

/// One curve of the figures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Curve {
    pub method: Method,
    pub rows: Rows,
    /// Per-part GPs (false: whole body).
    pub parts: bool,
}

impl Curve {
    pub fn label(&self) -> String {
        let rows = match self.rows {
            Rows::Dense => "dense",
            Rows::KeyposesFirst => "keyposes-first",
        };
        let body = if self.parts { "parts" } else { "whole-body" };
        format!("{} {rows} {body}", self.method.name())
    }
}

/// The curves of figures 7, 8 and 9 (the first is shared).
pub const CURVES: [Curve; 6] = [
    Curve {
        method: Method::GprNn,
        rows: Rows::Dense,
        parts: true,
    },
    Curve {
        method: Method::GprSe,
        rows: Rows::Dense,
        parts: true,
    },
    Curve {
        method: Method::GprLinear,
        rows: Rows::Dense,
        parts: true,
    },
    Curve {
        method: Method::KeyposeAffine,
        rows: Rows::Dense,
        parts: true,
    },
    Curve {
        method: Method::GprNn,
        rows: Rows::KeyposesFirst,
        parts: true,
    },
    Curve {
        method: Method::WholeBody,
        rows: Rows::Dense,
        parts: false,
    },
];

/// One point of one curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    pub direction: String,
    pub curve: String,
    pub n_train: usize,
    pub train_rms_m: f64,
    pub test_rms_m: f64,
}

/// The training data of one direction, for per-part and whole-body PCA.
pub struct DirectionData {
    pub label: String,
    pub parts: Vec<PairData>,
    pub whole: Vec<PairData>,
    /// Target vertex count of each part, and of the whole body.
    pub part_vertices: Vec<usize>,
    pub whole_vertices: usize,
    pub part_names: Vec<String>,
    pub frame_ratio: f64,
}

/// Row indices (in [`crate::gpr_model::training_set`] order, dense) of the
/// first occurrence of each key-pose pair.
pub fn key_rows(pairs: &[PairData]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut offset = 0;
    for p in pairs {
        for k in &p.keyposes {
            if let Some(r) = p.pairs.iter().position(|q| q == k) {
                out.push(offset + r);
            }
        }
        offset += p.pairs.len();
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Seeded split of `n` rows: `(training side, held out)`; key rows stay on
/// the training side (at its front), 30 % of the other rows are held out.
pub fn split(n: usize, keys: &[usize], seed: u64) -> (Vec<usize>, Vec<usize>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut others: Vec<usize> = (0..n).filter(|r| keys.binary_search(r).is_err()).collect();
    others.shuffle(&mut rng);
    let n_test = (others.len() as f64 * 0.3).round() as usize;
    let test = others[..n_test].to_vec();
    let mut train = keys.to_vec();
    train.shuffle(&mut rng);
    train.extend_from_slice(&others[n_test..]);
    (train, test)
}

/// About `count` sizes from `min` to `max`, geometrically spaced, distinct.
pub fn sizes(min: usize, max: usize, count: usize) -> Vec<usize> {
    let (min, max) = (min.max(2).min(max), max.max(2));
    let mut out: Vec<usize> = (0..count.max(2))
        .map(|i| {
            let t = i as f64 / (count.max(2) - 1) as f64;
            (min as f64 * (max as f64 / min as f64).powf(t)).round() as usize
        })
        .collect();
    out.dedup();
    out
}

/// Per-vertex RMS error between predicted and true target coefficients.
pub fn coefficient_rms(pred: &[DMatrix<f64>], truth: &[DMatrix<f64>], vertices: &[usize]) -> f64 {
    let rows = truth.first().map_or(0, |t| t.nrows()).max(1) as f64;
    let sq: f64 = pred
        .iter()
        .zip(truth)
        .map(|(p, t)| (p - t).norm_squared())
        .sum();
    (sq / (rows * vertices.iter().sum::<usize>().max(1) as f64)).sqrt()
}

fn part_error(model: &GprModel, data: &TrainingSet, vertices: &[usize]) -> Result<f64> {
    let pred = model
        .parts
        .iter()
        .zip(&data.x_parts)
        .map(|(r, x)| r.predict(x))
        .collect::<Result<Vec<_>>>()?;
    Ok(coefficient_rms(&pred, &data.y_parts, vertices))
}

/// All points of all [`CURVES`] for one direction. `train_sizes` larger than
/// the training side are skipped.
pub fn run_direction(
    dir: &DirectionData,
    train_sizes: &[usize],
    nn_bias: bool,
    opts: &GprOptions,
    seed: u64,
) -> Result<Vec<CurvePoint>> {
    let parts_set = crate::gpr_model::training_set(&dir.parts, dir.frame_ratio, false)?;
    let whole_set = crate::gpr_model::training_set(&dir.whole, dir.frame_ratio, false)?;
    if parts_set.len() != whole_set.len() {
        return Err(Error::invalid(
            "per-part and whole-body training sets differ in length",
        ));
    }
    let keys = key_rows(&dir.parts);
    let (train_side, held_out) = split(parts_set.len(), &keys, seed);
    let keys_first: Vec<usize> = {
        let mut k = keys.clone();
        k.extend(train_side.iter().filter(|r| keys.binary_search(r).is_err()));
        k
    };
    let dense_order: Vec<usize> = {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let mut d = train_side.clone();
        d.shuffle(&mut rng);
        d
    };
    let mut points = Vec::new();
    for curve in CURVES {
        let (set, names, vertices): (&TrainingSet, Vec<String>, Vec<usize>) = if curve.parts {
            (
                &parts_set,
                dir.part_names.clone(),
                dir.part_vertices.clone(),
            )
        } else {
            (
                &whole_set,
                vec!["body".to_string()],
                vec![dir.whole_vertices],
            )
        };
        let test = set.subset(&held_out);
        for &n in train_sizes {
            if n > train_side.len() || (curve.rows == Rows::KeyposesFirst && n < keys.len()) {
                continue;
            }
            let rows: Vec<usize> = match curve.rows {
                Rows::Dense => dense_order[..n].to_vec(),
                Rows::KeyposesFirst => keys_first[..n].to_vec(),
            };
            let train_rows = set.subset(&rows);
            let model = if curve.method == Method::KeyposeAffine {
                // Baran et al. use the key-poses only, whatever the size.
                let key_set = set.subset(&keys);
                fit_on(
                    curve.method,
                    nn_bias,
                    &names,
                    &key_set,
                    dir.frame_ratio,
                    opts,
                )?
            } else {
                fit_on(
                    curve.method,
                    nn_bias,
                    &names,
                    &train_rows,
                    dir.frame_ratio,
                    opts,
                )?
            };
            points.push(CurvePoint {
                direction: dir.label.clone(),
                curve: curve.label(),
                n_train: n,
                train_rms_m: part_error(&model, &train_rows, &vertices)?,
                test_rms_m: part_error(&model, &test, &vertices)?,
            });
        }
    }
    Ok(points)
}

/// Trains the pose regressors of `method` on the rows of `set` (every row a
/// "key-pose", so that the affine baseline uses them all).
fn fit_on(
    method: Method,
    nn_bias: bool,
    names: &[String],
    set: &TrainingSet,
    ratio: f64,
    opts: &GprOptions,
) -> Result<GprModel> {
    let n = set.len();
    let one = PairData {
        source_coeffs: set.x_parts.clone(),
        target_coeffs: set.y_parts.clone(),
        source_disp: (0..n)
            .map(|r| std::array::from_fn(|c| set.x_disp[(r, c)]))
            .collect(),
        target_disp: vec![[0.0; 6]; n],
        pairs: (0..n).map(|r| [r, r]).collect(),
        keyposes: (0..n).map(|r| [r, r]).collect(),
    };
    train(method, nn_bias, names, &[one], ratio.max(1e-9), false, opts)
}

/// Writes the points as CSV.
pub fn write_csv(path: &Path, points: &[CurvePoint]) -> Result<()> {
    let mut text = String::from("direction,curve,n_train,train_rms_m,test_rms_m\n");
    for p in points {
        text.push_str(&format!(
            "{},{},{},{:.6},{:.6}\n",
            p.direction, p.curve, p.n_train, p.train_rms_m, p.test_rms_m
        ));
    }
    mesh_core::atomic::write_bytes_atomic(path, text.as_bytes())
}

/// The figures: `(file stem, title, curve labels)`.
pub fn figures() -> Vec<(&'static str, &'static str, Vec<String>)> {
    let l = |i: usize| CURVES[i].label();
    vec![
        (
            "fig7-kernels",
            "Kernels and key-pose affine baseline",
            vec![l(0), l(1), l(2), l(3)],
        ),
        (
            "fig8-dense-vs-keyposes",
            "Dense pairs vs key-poses first",
            vec![l(0), l(4)],
        ),
        (
            "fig9-parts-vs-whole",
            "Parts vs whole body",
            vec![l(0), l(5)],
        ),
    ]
}

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is compiled in: registration cannot fail on a valid TTF.
        let _ =
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
}

const COLOURS: [plotters::style::RGBColor; 4] = [
    plotters::style::RGBColor(31, 119, 180),
    plotters::style::RGBColor(255, 127, 14),
    plotters::style::RGBColor(44, 160, 44),
    plotters::style::RGBColor(214, 39, 40),
];

fn draw<DB: plotters::prelude::DrawingBackend>(
    root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    series: &[(String, Vec<(f64, f64, f64)>)],
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let e = |x: &dyn std::fmt::Debug| format!("{x:?}");
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let all = series.iter().flat_map(|(_, p)| p.iter());
    let (mut x0, mut x1, mut y1) = (f64::INFINITY, 0.0f64, 0.0f64);
    for &(x, a, b) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y1 = y1.max(a).max(b);
    }
    if !x0.is_finite() {
        x0 = 0.0;
    }
    let y1 = if y1 > 0.0 { y1 * 1.1 * 1000.0 } else { 1.0 };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
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
    for (i, (name, pts)) in series.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|p| (p.0, p.2 * 1000.0)),
                c.stroke_width(2),
            ))
            .map_err(|x| e(&x))?
            .label(format!("{name} (held out)"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|p| (p.0, p.1 * 1000.0)),
                c.mix(0.5).stroke_width(1),
            ))
            .map_err(|x| e(&x))?
            .label(format!("{name} (training)"))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], c.mix(0.5).stroke_width(1))
            });
        chart
            .draw_series(
                pts.iter()
                    .map(|p| Circle::new((p.0, p.1 * 1000.0), 3, c.mix(0.5).filled())),
            )
            .map_err(|x| e(&x))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// Writes `<dir>/<direction>-<figure>.png` and `.svg` for every figure and direction.
pub fn plot_all(dir: &Path, points: &[CurvePoint]) -> Result<Vec<std::path::PathBuf>> {
    use plotters::prelude::*;
    register_font();
    let mut directions: Vec<&str> = points.iter().map(|p| p.direction.as_str()).collect();
    directions.dedup();
    let mut written = Vec::new();
    for d in directions {
        for (stem, title, labels) in figures() {
            let series: Vec<(String, Vec<(f64, f64, f64)>)> = labels
                .iter()
                .map(|l| {
                    let pts = points
                        .iter()
                        .filter(|p| p.direction == d && &p.curve == l)
                        .map(|p| (p.n_train as f64, p.train_rms_m, p.test_rms_m))
                        .collect();
                    (l.clone(), pts)
                })
                .collect();
            let title = format!("{d}: {title}");
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
            let mut bytes = Vec::new();
            {
                let mut enc = png::Encoder::new(&mut bytes, w, h);
                enc.set_color(png::ColorType::Rgb);
                enc.set_depth(png::BitDepth::Eight);
                let mut writer = enc
                    .write_header()
                    .map_err(|e| Error::file(&png_path, e.to_string()))?;
                writer
                    .write_image_data(&pixels)
                    .map_err(|e| Error::file(&png_path, e.to_string()))?;
            }
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
