//! CVPR figure 5: one predicted part mesh before and after the §6.1 correction, beside the
//! training meshes it was corrected with.

use mesh_core::{Error, Result};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

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

/// Builds figure 5: `model` maps the source motion (`source_coeffs`, its frames encoded with
/// the model's source PCA, and `source_disp`, its displacements) onto the target; the part
/// meshes decoded with `target_pca` are corrected against the target's `training` part meshes
/// (`[part][mesh]`, as `transfer::reconstruct::training_part_meshes` reads them) with the `m`
/// nearest meshes (§6.1). `part` and `frame` choose the example; by default the (part, frame)
/// whose prediction is farthest from every training mesh (where the correction has most to
/// do). `truth`: the target's true frames of the same motion (whole meshes, any placement).
#[allow(clippy::too_many_arguments)]
pub fn correction_example(
    model: &transfer::gpr_model::GprModel,
    source_coeffs: &[nalgebra::DMatrix<f64>],
    source_disp: &[[f64; 6]],
    target_pca: &capture::part_pca::PcaModel,
    seg: &mesh_core::segmentation::Segmentation,
    training: Vec<Vec<Vec<Vector3<f64>>>>,
    part: Option<&str>,
    frame: Option<usize>,
    m: usize,
    truth: Option<&[Vec<Vector3<f64>>]>,
) -> Result<(CorrectionFigure, CorrectionReport)> {
    use surface::correct::Corrector;
    if training.iter().all(Vec::is_empty) {
        return Err(Error::invalid("no target training motions for the correction"));
    }
    if seg.parts.len() != target_pca.parts.len()
        || training.len() != seg.parts.len()
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
    let disp = transfer::predict::displacement_matrix(source_disp);
    let pred = transfer::predict::predict(model, source_coeffs, &disp, false)?;
    let decoded = target_pca.decode(&pred.coeffs)?;
    let n_frames = source_disp.len();
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
    let correctors: Vec<(usize, Corrector)> = training
        .into_iter()
        .enumerate()
        .filter(|(k, _)| parts.contains(k))
        .map(|(k, meshes)| Ok((k, Corrector::new(seg.parts[k].faces.clone(), meshes)?)))
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
    let nearest: Vec<(Vec<Vector3<f64>>, f64)> = near
        .iter()
        .map(|&(i, d)| (corrector.training_mesh(i).to_vec(), d))
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
