//! A picture for checking proposed curves by eye: the template drawn from the front, the left
//! side and the back, every vertex coloured by the part `segment` gives it (the overlap bands as
//! a 50/50 mix of the two parts, as `render --parts` draws them; pieces of the mesh that no loop
//! crosses in the colour of the part they join), the loops drawn over it in black where they
//! are not hidden, the chosen extremities marked and named, and the part names and colours as a
//! legend. When the curves do not cut the template into parts (or there are none yet) the
//! template is drawn in the root's colour with whatever loops there are.

use std::path::Path;

use anyhow::{Context, Result};
use mesh_core::capture_set::SubjectSpec;
use mesh_core::TriMesh;
use nalgebra::Vector3;
use render::camera::{Aabb, Axis, ProjectionKind, View};
use render::colour::Rgb;
use render::image::RgbImage;
use render::scene::{Layer, Renderer, Style};

use crate::extremities::{Extremities, NAMES};

/// Colour of the loops.
pub const LOOP_COLOUR: Rgb = [20, 20, 20];
/// Colour of the extremities' marks and names.
pub const EXTREMITY_COLOUR: Rgb = [200, 0, 160];
/// Size of one view, in pixels.
const VIEW_W: u32 = 360;
const VIEW_H: u32 = 540;
/// Height of the legend strip under the views.
const LEGEND_H: u32 = 28;

/// The loops as world segments: consecutive vertices of each loop, last to first included.
pub fn loop_segments(mesh: &TriMesh, spec: &SubjectSpec) -> Vec<(Vector3<f64>, Vector3<f64>, Rgb)> {
    let mut lines = Vec::new();
    for lp in spec.curves.values().flatten() {
        let at = |v: u32| mesh.vertices.get(v as usize).copied();
        for (k, &v) in lp.iter().enumerate() {
            let w = lp[(k + 1) % lp.len()];
            if let (Some(a), Some(b)) = (at(v), at(w)) {
                lines.push((a, b, LOOP_COLOUR));
            }
        }
    }
    lines
}

/// Per-vertex colours of the parts `spec` cuts `mesh` into (`render::parts::part_colours`); all
/// the root's colour when `spec` does not segment the mesh.
pub fn part_colours(mesh: &TriMesh, spec: &SubjectSpec) -> Vec<Rgb> {
    render::parts::part_colours(spec, Path::new("subject.json"), &mesh.vertices, &mesh.faces)
        .unwrap_or_else(|_| vec![render::parts::ROOT_COLOUR; mesh.vertices.len()])
}

/// The three views side by side with a legend, as an image; with `extremities`, each marked
/// and named in every view.
pub fn check_image(mesh: &TriMesh, spec: &SubjectSpec, extremities: Option<&Extremities>, spec_path: &Path) -> Result<RgbImage> {
    let colours = part_colours(mesh, spec);
    let lines = loop_segments(mesh, spec);
    let up = Axis::parse(&spec.up).with_context(|| format!("{}: 'up' must be one of +x -x +y -y +z -z", spec_path.display()))?;
    let bbox = Aabb::from_points(&mesh.vertices);
    let bbox_diagonal = (bbox.max - bbox.min).norm();
    let views = [("front", View::FRONT), ("left side", View::SIDE), ("back", View { azimuth_deg: 180.0, elevation_deg: 0.0 })];
    let style = Style { floor: false, ..Style::default() };
    let mut image = RgbImage::new(VIEW_W * views.len() as u32, VIEW_H + LEGEND_H, style.background);
    let layer = Layer { vertices: &mesh.vertices, faces: &mesh.faces, colour: render::parts::ROOT_COLOUR, vertex_colours: Some(&colours) };
    for (i, (name, view)) in views.iter().enumerate() {
        let renderer = Renderer::new(&bbox, view, &up, ProjectionKind::Orthographic, VIEW_W, VIEW_H, style);
        let mut panel = renderer.render_with_lines(&[layer], &lines, 0.004 * bbox_diagonal);
        for (name, v) in extremities.iter().flat_map(|e| NAMES.iter().zip(e.vertices)) {
            if let Some([px, py, _]) = renderer.camera.project(&mesh.vertices[v as usize]) {
                let (px, py) = (px.round() as i64, py.round() as i64);
                panel.fill_rect(px - 3, py - 3, 7, 7, EXTREMITY_COLOUR);
                render::font::draw_text(&mut panel, px + 6, py - 3, name, 1, EXTREMITY_COLOUR);
            }
        }
        let x = (i as u32 * VIEW_W) as i64;
        image.blit(&panel, x, 0);
        render::font::draw_text(&mut image, x + 8, 8, name, 2, [60, 60, 60]);
    }
    // Legend: a swatch and the name of each part, then the loops.
    let mut entries: Vec<(String, Rgb)> = render::parts::part_palette(spec).into_iter().collect();
    entries.push(("loops".into(), LOOP_COLOUR));
    if extremities.is_some() {
        entries.push(("extremities".into(), EXTREMITY_COLOUR));
    }
    let mut x = 8i64;
    let y = (VIEW_H + 6) as i64;
    for (name, c) in &entries {
        image.fill_rect(x, y, 14, 14, *c);
        render::font::draw_text(&mut image, x + 20, y + 1, name, 2, [40, 40, 40]);
        x += 20 + render::font::text_width(name, 2) as i64 + 18;
    }
    Ok(image)
}

/// Writes [`check_image`] as a PNG at `out` (atomically).
pub fn write_check_image(mesh: &TriMesh, spec: &SubjectSpec, extremities: Option<&Extremities>, spec_path: &Path, out: &Path) -> Result<()> {
    let image = check_image(mesh, spec, extremities, spec_path)?;
    mesh_core::atomic::write_bytes_atomic(out, &image.encode_png())?;
    Ok(())
}
