//! The paper's illustrations that are not learning curves (`paper-figure`):
//!
//! - CVPR figure 3, [`CostFigure`]: the association cost matrix `-log P_ij`
//!   of one training pair (eqs. 1-6, `gp::blr::cost_matrix`, summed over
//!   parts) as an image, source frames along x and target frames along y,
//!   with the DTW path (eq. 7, `gp::dtw::dtw_path`, as `dtw-densify`), the
//!   key-poses and, when the set has them, the true correspondences overlaid.
//!   Colours are `ln(1 + cost)` on a viridis-like ramp, clipped to the 2nd-98th
//!   percentiles (the cost spans many orders of magnitude).
//! - CVPR figure 5, [`CorrectionFigure`]: one predicted part mesh before and
//!   after the §6.1 correction, and the `M` nearest training meshes it was
//!   corrected with (`surface::correct::Corrector`), drawn side by side with
//!   one camera by the `render` crate; optionally the true part, rigidly
//!   aligned onto the corrected one.

use std::path::Path;

use gp::blr::{cost_matrix, PartFrames};
use gp::dtw::{dtw_path, DtwOptions};
use mesh_core::{Error, Result};
use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};

use crate::learning_curves::{png_bytes, register_font};

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

/// The cost matrix of eqs. 1-6 and the DTW path of eq. 7 through the
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
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], rgb(TRUTH_COLOUR).stroke_width(2))
                });
        }
        chart
            .draw_series(LineSeries::new(
                self.path.iter().map(centre),
                rgb(PATH_COLOUR).stroke_width(3),
            ))
            .map_err(|x| e(&x))?
            .label("DTW path (eq. 7)")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(2))
            });
        chart
            .draw_series(
                self.keyposes
                    .iter()
                    .map(|k| Circle::new(centre(k), 6, rgb(KEY_COLOUR).stroke_width(2))),
            )
            .map_err(|x| e(&x))?
            .label("key-poses")
            .legend(move |(x, y)| Circle::new((x + 9, y), 5, rgb(KEY_COLOUR).stroke_width(2)));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(|x| e(&x))?;
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

/// Figure 5's data: one part, one frame.
#[derive(Clone, Debug)]
pub struct CorrectionFigure {
    pub title: String,
    /// The part's faces (local vertex indices).
    pub faces: Vec<[u32; 3]>,
    pub before: Vec<Vector3<f64>>,
    pub after: Vec<Vector3<f64>>,
    /// Nearest training meshes and their RMS vertex distance to `before`.
    pub nearest: Vec<(Vec<Vector3<f64>>, f64)>,
    pub truth: Option<Vec<Vector3<f64>>>,
}

/// Numbers of figure 5 (`--report`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrectionReport {
    pub part: String,
    pub frame: usize,
    pub nearest_distance_m: Vec<f64>,
    /// RMS vertex distance before / after the correction to the true part
    /// (rigidly aligned onto each), when the truth is given.
    pub truth_rms_before_m: Option<f64>,
    pub truth_rms_after_m: Option<f64>,
    /// Mean relative edge-length error to the truth before / after.
    pub truth_edge_error_before: Option<f64>,
    pub truth_edge_error_after: Option<f64>,
}

/// `src` rigidly moved onto `dst` (Procrustes, same vertex order).
pub fn aligned_onto(src: &[Vector3<f64>], dst: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    mesh_core::rigid::procrustes(src, dst, None).apply_all(src)
}

/// Mean `| |e| / |e_truth| - 1 |` over the faces' edges.
pub fn edge_error(mesh: &[Vector3<f64>], truth: &[Vector3<f64>], faces: &[[u32; 3]]) -> f64 {
    let mut sum = 0.0;
    let mut n = 0usize;
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
            let t = (truth[a] - truth[b]).norm();
            if t > 0.0 {
                sum += ((mesh[a] - mesh[b]).norm() / t - 1.0).abs();
                n += 1;
            }
        }
    }
    sum / n.max(1) as f64
}

impl CorrectionFigure {
    /// The panels, left to right: `(label, vertices, colour)`.
    fn panels(&self) -> Vec<(String, &[Vector3<f64>], [u8; 3])> {
        let mut out: Vec<(String, &[Vector3<f64>], [u8; 3])> = vec![
            ("prediction".into(), &self.before, [200, 120, 80]),
            ("corrected".into(), &self.after, [84, 172, 92]),
        ];
        for (k, (m, d)) in self.nearest.iter().enumerate() {
            out.push((
                format!("nearest {} ({:.0} mm)", k + 1, d * 1000.0),
                m,
                [150, 150, 150],
            ));
        }
        if let Some(t) = &self.truth {
            out.push(("truth".into(), t, [72, 132, 204]));
        }
        out
    }

    /// Renders the panels side by side (`cell` pixels square each), each
    /// framed on its own centre at one common scale (the largest panel's
    /// extent), labels under each and the title above.
    pub fn render(&self, cell: u32, view: &render::camera::View) -> render::image::RgbImage {
        use render::camera::{Aabb, Axis, ProjectionKind};
        use render::scene::{Layer, Renderer, Style};
        let panels = self.panels();
        let boxes: Vec<Aabb> = panels
            .iter()
            .map(|(_, v, _)| Aabb::from_points(v.iter()))
            .collect();
        let half = boxes
            .iter()
            .map(|b| (b.max - b.min) / 2.0)
            .fold(Vector3::zeros(), |a: Vector3<f64>, h| a.sup(&h));
        let style = Style {
            floor: false,
            ..Style::default()
        };
        let renderers: Vec<Renderer> = boxes
            .iter()
            .map(|b| {
                let c = b.center();
                let framed = Aabb {
                    min: c - half,
                    max: c + half,
                };
                Renderer::new(
                    &framed,
                    view,
                    &Axis::PLUS_Y,
                    ProjectionKind::Orthographic,
                    cell,
                    cell,
                    style,
                )
            })
            .collect();
        let (title_h, label_h) = (28u32, 24u32);
        let mut img = render::image::RgbImage::new(
            cell * panels.len() as u32,
            cell + title_h + label_h,
            render::colour::WHITE,
        );
        render::font::draw_text(&mut img, 8, 8, &self.title, 2, render::colour::TEXT);
        for (k, (label, v, colour)) in panels.iter().enumerate() {
            let tile = renderers[k].render(&[Layer {
                vertices: v,
                faces: &self.faces,
                colour: *colour,
                vertex_colours: None,
            }]);
            let x = (k as u32 * cell) as i64;
            img.blit(&tile, x, title_h as i64);
            let tw = render::font::text_width(label, 2) as i64;
            render::font::draw_text(
                &mut img,
                x + ((cell as i64 - tw) / 2).max(0),
                (title_h + cell + 4) as i64,
                label,
                2,
                render::colour::TEXT,
            );
        }
        img
    }
}

/// Builds figure 5: `model` maps `source` (aligned, encoded with
/// `source_pca`) onto the target; the part meshes decoded with `target_pca`
/// are corrected against the target's `training` motions with the `m`
/// nearest meshes (§6.1). `part` and `frame` choose the example; by default
/// the (part, frame) whose prediction is farthest from every training mesh
/// (where the correction has most to do). `truth`: the target's true frames
/// of the same motion (whole meshes, any placement).
#[allow(clippy::too_many_arguments)]
pub fn correction_example(
    model: &crate::gpr_model::GprModel,
    source_pca: &crate::part_pca::PcaModel,
    target_pca: &crate::part_pca::PcaModel,
    seg: &mesh_core::segmentation::Segmentation,
    training: &[&crate::align::AlignedMotion],
    source: &crate::align::AlignedMotion,
    part: Option<&str>,
    frame: Option<usize>,
    m: usize,
    truth: Option<&[Vec<Vector3<f64>>]>,
) -> Result<(CorrectionFigure, CorrectionReport)> {
    use surface::correct::Corrector;
    if training.is_empty() {
        return Err(Error::invalid("no target training motions for the correction"));
    }
    if seg.parts.len() != target_pca.parts.len()
        || seg
            .parts
            .iter()
            .zip(&target_pca.parts)
            .any(|(s, p)| s.name != p.name || s.vertices != p.vertices)
    {
        return Err(Error::invalid(
            "the segmentation's parts differ from the target PCA model's",
        ));
    }
    let coeffs = source_pca.encode(source)?;
    let disp = crate::predict::displacement_matrix(&source.displacements);
    let pred = crate::predict::predict(model, &coeffs, &disp, false)?;
    let decoded = target_pca.decode(&pred.coeffs)?;
    let n_frames = source.n_frames();
    if let Some(f) = frame.filter(|&f| f >= n_frames) {
        return Err(Error::invalid(format!(
            "frame {f}: the source motion has {n_frames} frames"
        )));
    }
    let parts: Vec<usize> = match part {
        Some(name) => vec![seg
            .parts
            .iter()
            .position(|p| p.name == name)
            .ok_or_else(|| {
                Error::invalid(format!(
                    "no part '{name}' (parts: {:?})",
                    seg.parts.iter().map(|p| &p.name).collect::<Vec<_>>()
                ))
            })?],
        None => (0..seg.parts.len()).collect(),
    };
    let correctors: Vec<(usize, Corrector)> = parts
        .iter()
        .map(|&k| {
            let mut meshes = Vec::new();
            for t in training {
                let rows = target_pca.part_rows(t);
                meshes.extend(crate::reconstruct::rows_to_meshes(&rows[k]));
            }
            Ok((k, Corrector::new(seg.parts[k].faces.clone(), meshes)?))
        })
        .collect::<Result<_>>()?;
    let frames: Vec<usize> = match frame {
        Some(f) => vec![f],
        None => (0..n_frames).collect(),
    };
    let mut best: Option<(f64, usize, usize)> = None;
    for (c, (k, corrector)) in correctors.iter().enumerate() {
        for &f in &frames {
            let d = corrector
                .nearest(&decoded[*k][f], 1)
                .first()
                .map_or(0.0, |x| x.1);
            if best.is_none_or(|b| d > b.0) {
                best = Some((d, c, f));
            }
        }
    }
    let (_, c, f) = best.ok_or_else(|| Error::invalid("no frame to show"))?;
    let (k, corrector) = &correctors[c];
    let before = decoded[*k][f].clone();
    let after = corrector.correct(&before, m)?;
    let near = corrector.nearest(&before, m);
    let mut all_training = Vec::new();
    for t in training {
        all_training.extend(crate::reconstruct::rows_to_meshes(
            &target_pca.part_rows(t)[*k],
        ));
    }
    let nearest: Vec<(Vec<Vector3<f64>>, f64)> = near
        .iter()
        .map(|&(i, d)| (all_training[i].clone(), d))
        .collect();
    let faces = seg.parts[*k].faces.clone();
    let name = seg.parts[*k].name.clone();
    let mut report = CorrectionReport {
        part: name.clone(),
        frame: f,
        nearest_distance_m: near.iter().map(|x| x.1).collect(),
        truth_rms_before_m: None,
        truth_rms_after_m: None,
        truth_edge_error_before: None,
        truth_edge_error_after: None,
    };
    let truth_part = match truth {
        Some(frames) => {
            let full = frames.get(f).ok_or_else(|| {
                Error::invalid(format!("the truth has {} frames, frame {f} asked", frames.len()))
            })?;
            if full.len() != seg.n_vertices {
                return Err(Error::invalid(format!(
                    "the truth has {} vertices, the target {}",
                    full.len(),
                    seg.n_vertices
                )));
            }
            let t: Vec<Vector3<f64>> = seg.parts[*k]
                .vertices
                .iter()
                .map(|&v| full[v as usize])
                .collect();
            let (tb, ta) = (aligned_onto(&t, &before), aligned_onto(&t, &after));
            report.truth_rms_before_m = Some(surface::correct::vertex_distance(&before, &tb));
            report.truth_rms_after_m = Some(surface::correct::vertex_distance(&after, &ta));
            report.truth_edge_error_before = Some(edge_error(&before, &t, &faces));
            report.truth_edge_error_after = Some(edge_error(&after, &t, &faces));
            Some(ta)
        }
        None => None,
    };
    Ok((
        CorrectionFigure {
            title: format!("{name}, frame {f}: body part correction (CVPR 6.1, M = {m})"),
            faces,
            before,
            after,
            nearest,
            truth: truth_part,
        },
        report,
    ))
}
