//! The paper's illustrations that are not learning curves (`paper-figure`):
//!
//! - CVPR figure 3, [`CostFigure`]: the association cost matrix `-log P_ij`
//!   of one training pair (CVPR eqs. 1-6, `gp::blr::cost_matrix`, summed over
//!   parts) as an image, source frames along x and target frames along y,
//!   with the DTW path (CVPR eq. 7, `gp::dtw::dtw_path`, as `dtw-densify`), the
//!   key-poses and, when the set has them, the true correspondences overlaid.
//!   Colours are `ln(1 + cost)` on a viridis-like ramp, clipped to the 2nd-98th
//!   percentiles (the cost spans many orders of magnitude).
//! - CVPR figure 5, [`CorrectionFigure`]: one predicted part mesh before and
//!   after the §6.1 correction, and the `M` nearest training meshes it was
//!   corrected with (`surface::correct::Corrector`), drawn side by side with
//!   one camera by the `render` crate; optionally the true part, rigidly
//!   aligned onto the corrected one.
//! - The per-frame confidence figure, [`ConfidenceFigure`] (not in the
//!   paper): for one transferred motion, the normalised nearest distance and
//!   the GP variance ratio of every part (`crate::confidence`) and, with an
//!   `transfer-eval` record, the pose error, frame by frame; frames where a body
//!   part is at least [`DEFAULT_EXTRAPOLATION_THRESHOLD`] from its training
//!   inputs are shaded, and the Pearson correlation of the per-frame maximum
//!   distance with the error is reported.

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
    source_pca: &capture::part_pca::PcaModel,
    target_pca: &capture::part_pca::PcaModel,
    seg: &mesh_core::segmentation::Segmentation,
    training: &[&capture::align::AlignedMotion],
    source: &capture::align::AlignedMotion,
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
                let rows = target_pca.part_rows(t)?;
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
            &target_pca.part_rows(t)?[*k],
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

/// Default `--threshold` of the confidence figure: a frame is shaded as
/// extrapolating when some body part's normalised nearest distance reaches
/// 1, i.e. the part is as far from its nearest training pose as a typical
/// training pose is from the mean pose (`crate::confidence`).
pub const DEFAULT_EXTRAPOLATION_THRESHOLD: f64 = 1.0;

/// Name of the non-body-part entry of [`crate::confidence::Confidence`].
pub const DISPLACEMENT: &str = "displacement";

/// Colour of the extrapolating frames' background.
pub const EXTRAPOLATING_COLOUR: [u8; 3] = [255, 221, 170];

/// Reads a `gpr-predict --confidence` JSON file and checks it: at least one
/// frame, every listed part present in both maps, every non-null series
/// `frames` long and finite. Errors name the file.
pub fn load_confidence(path: &Path) -> Result<crate::confidence::Confidence> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let c: crate::confidence::Confidence = serde_json::from_str(&text).map_err(|e| {
        Error::file(path, format!("not a confidence file (gpr-predict --confidence): {e}"))
    })?;
    if c.frames == 0 {
        return Err(Error::file(path, "0 frames"));
    }
    if c.parts.is_empty() {
        return Err(Error::file(path, "no parts"));
    }
    for (field, map) in [("variance_ratio", &c.variance_ratio), ("nearest_distance", &c.nearest_distance)] {
        for p in &c.parts {
            let Some(series) = map.get(p) else {
                return Err(Error::file(path, format!("{field} has no entry for part '{p}'")));
            };
            if let Some(v) = series {
                if v.len() != c.frames {
                    return Err(Error::file(
                        path,
                        format!("{field} of '{p}' has {} values for {} frames", v.len(), c.frames),
                    ));
                }
                if let Some(f) = v.iter().position(|x| !x.is_finite()) {
                    return Err(Error::file(path, format!("{field} of '{p}' is not finite at frame {f}")));
                }
            }
        }
    }
    Ok(c)
}

/// Reads an `transfer-eval` record and checks that its per-frame pose errors
/// cover the `frames` frames of `confidence_path`. Errors name the file.
pub fn load_eval(path: &Path, frames: usize, confidence_path: &Path) -> Result<crate::evaluate::EvalRecord> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let r: crate::evaluate::EvalRecord = serde_json::from_str(&text)
        .map_err(|e| Error::file(path, format!("not an evaluate record: {e}")))?;
    if r.frame_pose_m.len() != frames {
        return Err(Error::file(
            path,
            format!(
                "frame_pose_m has {} frames but {} has {frames}: not the same motion",
                r.frame_pose_m.len(),
                confidence_path.display()
            ),
        ));
    }
    if let Some(f) = r.frame_pose_m.iter().position(|x| !x.is_finite()) {
        return Err(Error::file(path, format!("frame_pose_m is not finite at frame {f}")));
    }
    Ok(r)
}

/// Per frame, the largest normalised nearest distance over the body parts
/// (the displacement left out: the pose error of `transfer-eval` is measured after
/// a rigid alignment, which the displacement does not change). `None` when no
/// body part has distances (the affine baseline).
pub fn max_part_distance(c: &crate::confidence::Confidence) -> Option<Vec<f64>> {
    let series: Vec<&Vec<f64>> = c
        .parts
        .iter()
        .filter(|p| p.as_str() != DISPLACEMENT)
        .filter_map(|p| c.nearest_distance.get(p).and_then(|s| s.as_ref()))
        .collect();
    (!series.is_empty())
        .then(|| (0..c.frames).map(|f| series.iter().map(|s| s[f]).fold(f64::MIN, f64::max)).collect())
}

/// Pearson correlation of `a` and `b` (same length); `None` with fewer than 3
/// points or when either is constant.
pub fn pearson(a: &[f64], b: &[f64]) -> Option<f64> {
    let n = a.len().min(b.len());
    if n < 3 {
        return None;
    }
    let (ma, mb) = (a[..n].iter().sum::<f64>() / n as f64, b[..n].iter().sum::<f64>() / n as f64);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a[..n].iter().zip(&b[..n]) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    (saa > 0.0 && sbb > 0.0).then(|| sab / (saa * sbb).sqrt())
}

/// One entry of the confidence figure: a body part or the displacement.
#[derive(Clone, Debug)]
pub struct ConfidenceSeries {
    pub name: String,
    pub nearest: Option<Vec<f64>>,
    pub variance: Option<Vec<f64>>,
}

/// The per-frame confidence figure (`paper-figure confidence`): panel 1 the
/// normalised nearest distance of every part, panel 2 the variance ratio,
/// panel 3 (with an `transfer-eval` record) the pose error in cm; frames where
/// [`max_part_distance`] reaches `threshold` are shaded in every panel.
#[derive(Clone, Debug)]
pub struct ConfidenceFigure {
    pub title: String,
    /// Second title line (the correlation, the count of shaded frames).
    pub caption: String,
    pub frames: usize,
    pub series: Vec<ConfidenceSeries>,
    /// Per-frame max over the body parts of the nearest distance.
    pub max_distance: Option<Vec<f64>>,
    /// Per-frame pose RMS error (m).
    pub error_m: Option<Vec<f64>>,
    pub threshold: f64,
    /// Pearson correlation of `max_distance` and `error_m`.
    pub correlation: Option<f64>,
}

/// Width of the legend column right of each panel (pixels).
const LEGEND_W: u32 = 190;
/// Height of one panel and of the title block (pixels).
const PANEL_H: u32 = 240;
const TITLE_H: u32 = 58;

/// Size of the confidence figure for `frames` frames, with or without the
/// error panel: about 6 pixels per frame within 760..1800 wide, 240 pixels
/// per panel plus the title.
pub fn confidence_figure_size(frames: usize, with_error: bool) -> (u32, u32) {
    let w = ((frames * 6) as u32 + 120 + LEGEND_W).clamp(760, 1800);
    (w, TITLE_H + PANEL_H * if with_error { 3 } else { 2 })
}

/// Runs of consecutive frames where `v >= threshold`, as `[first, last]`.
pub fn runs_at_or_above(v: &[f64], threshold: f64) -> Vec<[usize; 2]> {
    let mut out: Vec<[usize; 2]> = Vec::new();
    for (f, x) in v.iter().enumerate() {
        if *x >= threshold {
            match out.last_mut() {
                Some(r) if r[1] + 1 == f => r[1] = f,
                _ => out.push([f, f]),
            }
        }
    }
    out
}

const PART_COLOURS: [[u8; 3]; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [188, 189, 34],
];

impl ConfidenceFigure {
    /// The figure of a checked confidence (see [`load_confidence`]) and
    /// optionally its checked evaluate record ([`load_eval`]).
    pub fn new(
        c: &crate::confidence::Confidence,
        eval: Option<&crate::evaluate::EvalRecord>,
        title: Option<String>,
        threshold: f64,
    ) -> Self {
        let series = c
            .parts
            .iter()
            .map(|p| ConfidenceSeries {
                name: p.clone(),
                nearest: c.nearest_distance.get(p).cloned().flatten(),
                variance: c.variance_ratio.get(p).cloned().flatten(),
            })
            .collect();
        let max_distance = max_part_distance(c);
        let error_m = eval.map(|r| r.frame_pose_m.clone());
        let correlation = match (&max_distance, &error_m) {
            (Some(d), Some(e)) => pearson(d, e),
            _ => None,
        };
        let shaded: usize = max_distance
            .as_ref()
            .map_or(0, |d| d.iter().filter(|x| **x >= threshold).count());
        let mut caption = format!(
            "shaded: {shaded} of {} frames where a body part's nearest distance is ≥ {threshold}",
            c.frames
        );
        if error_m.is_some() {
            caption.push_str(&match correlation {
                Some(r) => format!("; Pearson r(max part distance, pose error) = {r:.2}"),
                None => "; Pearson r undefined (a constant series)".into(),
            });
        }
        let title = title.unwrap_or_else(|| match eval {
            Some(r) => format!("{} {}, {}: per-frame confidence and pose error", r.direction, r.motion, r.method),
            None => "per-frame confidence".into(),
        });
        ConfidenceFigure {
            title,
            caption,
            frames: c.frames,
            series,
            max_distance,
            error_m,
            threshold,
            correlation,
        }
    }

    pub fn size(&self) -> (u32, u32) {
        confidence_figure_size(self.frames, self.error_m.is_some())
    }

    fn draw<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), String> {
        use plotters::prelude::*;
        let e = |x: &dyn std::fmt::Debug| format!("{x:?}");
        let rgb = |c: [u8; 3]| RGBColor(c[0], c[1], c[2]);
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let (w, _) = root.dim_in_pixel();
        let (head, body) = root.split_vertically(TITLE_H);
        head.draw(&Text::new(self.title.clone(), (14, 8), ("sans-serif", 19).into_font().color(&BLACK)))
            .map_err(|x| e(&x))?;
        head.draw(&Text::new(
            self.caption.clone(),
            (14, 34),
            ("sans-serif", 14).into_font().color(&RGBColor(60, 60, 60)),
        ))
        .map_err(|x| e(&x))?;
        let n_panels = if self.error_m.is_some() { 3 } else { 2 };
        let panels = body.split_evenly((n_panels, 1));
        let runs = self
            .max_distance
            .as_ref()
            .map(|d| runs_at_or_above(d, self.threshold))
            .unwrap_or_default();
        let colour_of = |k: usize, name: &str| {
            if name == DISPLACEMENT {
                RGBColor(110, 110, 110)
            } else {
                rgb(PART_COLOURS[k % PART_COLOURS.len()])
            }
        };
        let x_range = -0.5..(self.frames as f64 - 0.5).max(0.5);
        for (p, area) in panels.iter().enumerate() {
            let (plot, legend) = area.split_horizontally(w - LEGEND_W);
            // (panel title, y label, y max, per-series values)
            let (name, y_desc, values): (&str, &str, Vec<(usize, &str, &Vec<f64>)>) = match p {
                0 => (
                    "nearest distance to the training inputs (0 = a training pose, 1 = typical spread)",
                    "nearest distance",
                    self.series
                        .iter()
                        .enumerate()
                        .filter_map(|(k, s)| s.nearest.as_ref().map(|v| (k, s.name.as_str(), v)))
                        .collect(),
                ),
                1 => (
                    "GP predictive variance / prior variance",
                    "variance ratio",
                    self.series
                        .iter()
                        .enumerate()
                        .filter_map(|(k, s)| s.variance.as_ref().map(|v| (k, s.name.as_str(), v)))
                        .collect(),
                ),
                _ => (
                    "pose error (evaluate, after rigid alignment per frame)",
                    "RMS error (cm)",
                    vec![],
                ),
            };
            let err_cm: Vec<f64> = self.error_m.iter().flatten().map(|x| x * 100.0).collect();
            let top = match p {
                0 => values
                    .iter()
                    .flat_map(|v| v.2.iter())
                    .fold(self.threshold, |a, &b| a.max(b))
                    * 1.1,
                1 => 1.05,
                _ => err_cm.iter().fold(0.0f64, |a, &b| a.max(b)).max(1e-3) * 1.1,
            };
            let mut chart = ChartBuilder::on(&plot)
                .caption(name, ("sans-serif", 14))
                .margin_left(10)
                .margin_right(6)
                .margin_top(4)
                .margin_bottom(2)
                .x_label_area_size(34)
                .y_label_area_size(62)
                .build_cartesian_2d(x_range.clone(), 0.0..top)
                .map_err(|x| e(&x))?;
            chart
                .draw_series(runs.iter().map(|r| {
                    Rectangle::new(
                        [(r[0] as f64 - 0.5, 0.0), (r[1] as f64 + 0.5, top)],
                        rgb(EXTRAPOLATING_COLOUR).filled(),
                    )
                }))
                .map_err(|x| e(&x))?;
            chart
                .configure_mesh()
                .light_line_style(RGBColor(238, 238, 238))
                .x_label_formatter(&|x| format!("{x:.0}"))
                .x_desc(if p + 1 == n_panels { "frame" } else { "" })
                .y_desc(y_desc)
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(|x| e(&x))?;
            let mut entries: Vec<(String, RGBColor, bool)> = Vec::new();
            for (k, label, v) in &values {
                let c = colour_of(*k, label);
                let pts = v.iter().enumerate().map(|(f, y)| (f as f64, *y));
                if *label == DISPLACEMENT {
                    chart
                        .draw_series(DashedLineSeries::new(pts, 6, 4, c.stroke_width(2)))
                        .map_err(|x| e(&x))?;
                } else {
                    chart.draw_series(LineSeries::new(pts, c.stroke_width(2))).map_err(|x| e(&x))?;
                }
                entries.push((label.to_string(), c, *label == DISPLACEMENT));
            }
            if p == 0 {
                let t = self.threshold;
                chart
                    .draw_series(DashedLineSeries::new(
                        [(x_range.start, t), (x_range.end, t)],
                        8,
                        5,
                        BLACK.stroke_width(1),
                    ))
                    .map_err(|x| e(&x))?;
            }
            if p == 2 {
                let c = RGBColor(170, 20, 20);
                let pts: Vec<(f64, f64)> = err_cm.iter().enumerate().map(|(f, y)| (f as f64, *y)).collect();
                chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2))).map_err(|x| e(&x))?;
                if self.frames <= 200 {
                    chart
                        .draw_series(pts.iter().map(|q| Circle::new(*q, 2, c.filled())))
                        .map_err(|x| e(&x))?;
                }
                entries.push(("pose RMS error".into(), c, false));
            }
            if values.is_empty() && p < 2 {
                let (px, py) = chart.backend_coord(&(x_range.start, top * 0.5));
                plot.draw(&Text::new(
                    "none (no GP: the key-pose affine baseline)".to_string(),
                    (px + 20, py),
                    ("sans-serif", 14).into_font().color(&RGBColor(90, 90, 90)),
                ))
                .map_err(|x| e(&x))?;
            }
            // Legend column.
            let font = ("sans-serif", 13).into_font().color(&BLACK);
            let mut y = 28i32;
            for (label, c, dashed) in &entries {
                if *dashed {
                    legend
                        .draw(&PathElement::new(vec![(8, y + 7), (16, y + 7)], c.stroke_width(2)))
                        .map_err(|x| e(&x))?;
                    legend
                        .draw(&PathElement::new(vec![(21, y + 7), (30, y + 7)], c.stroke_width(2)))
                        .map_err(|x| e(&x))?;
                } else {
                    legend
                        .draw(&PathElement::new(vec![(8, y + 7), (30, y + 7)], c.stroke_width(3)))
                        .map_err(|x| e(&x))?;
                }
                legend.draw(&Text::new(label.clone(), (36, y), font.clone())).map_err(|x| e(&x))?;
                y += 19;
            }
            if p == 0 {
                legend
                    .draw(&PathElement::new(vec![(8, y + 7), (30, y + 7)], BLACK.stroke_width(1)))
                    .map_err(|x| e(&x))?;
                legend
                    .draw(&Text::new(format!("threshold {}", self.threshold), (36, y), font.clone()))
                    .map_err(|x| e(&x))?;
                y += 19;
            }
            if !runs.is_empty() {
                legend
                    .draw(&Rectangle::new([(8, y + 1), (30, y + 13)], rgb(EXTRAPOLATING_COLOUR).filled()))
                    .map_err(|x| e(&x))?;
                legend
                    .draw(&Text::new("extrapolating".to_string(), (36, y), font.clone()))
                    .map_err(|x| e(&x))?;
            }
        }
        root.present().map_err(|x| e(&x))?;
        Ok(())
    }

    /// Writes the PNG at `png` (and, with `svg`, the SVG), each atomically.
    pub fn write(&self, png: &Path, svg: Option<&Path>) -> Result<()> {
        use plotters::prelude::*;
        register_font();
        if self.frames == 0 {
            return Err(Error::file(png, "no frames to draw"));
        }
        let (w, h) = self.size();
        let mut pixels = vec![0u8; (w * h * 3) as usize];
        self.draw(BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area())
            .map_err(|m| Error::file(png, format!("cannot draw the figure: {m}")))?;
        let bytes = png_bytes(png, &pixels, w, h)?;
        let text = match svg {
            Some(svg) => {
                let mut text = String::new();
                self.draw(SVGBackend::with_string(&mut text, (w, h)).into_drawing_area())
                    .map_err(|m| Error::file(svg, format!("cannot draw the figure: {m}")))?;
                Some(text)
            }
            None => None,
        };
        mesh_core::atomic::write_bytes_atomic(png, &bytes)?;
        if let (Some(svg), Some(text)) = (svg, text) {
            mesh_core::atomic::write_bytes_atomic(svg, text.as_bytes())?;
        }
        Ok(())
    }
}
