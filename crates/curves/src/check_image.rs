//! A picture for checking proposed curves by eye: the template drawn from the front, the left
//! side and the back, every vertex coloured by the part it falls in (the overlap bands as a
//! 50/50 mix of the two parts, as `render --parts` draws them) and the loops drawn over it in
//! black where they are not hidden, with the part names and colours as a legend.

use std::path::Path;

use anyhow::{Context, Result};
use mesh_core::capture_set::SubjectSpec;
use mesh_core::TriMesh;
use nalgebra::Vector3;
use render::camera::{Aabb, Axis, ProjectionKind, View};
use render::colour::Rgb;
use render::image::RgbImage;
use render::scene::{Layer, Renderer, Style};

/// Colour of the loops.
pub const LOOP_COLOUR: Rgb = [20, 20, 20];
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

/// The three views side by side with a legend, as an image.
pub fn check_image(mesh: &TriMesh, spec: &SubjectSpec, spec_path: &Path) -> Result<RgbImage> {
    let colours = render::parts::part_colours(spec, spec_path, &mesh.vertices, &mesh.faces)?;
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
        let panel = renderer.render_with_lines(&[layer], &lines, 0.004 * bbox_diagonal);
        let x = (i as u32 * VIEW_W) as i64;
        image.blit(&panel, x, 0);
        render::font::draw_text(&mut image, x + 8, 8, name, 2, [60, 60, 60]);
    }
    // Legend: a swatch and the name of each part, then the loops.
    let mut entries: Vec<(String, Rgb)> = render::parts::part_palette(spec).into_iter().collect();
    entries.push(("loops".into(), LOOP_COLOUR));
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
pub fn write_check_image(mesh: &TriMesh, spec: &SubjectSpec, spec_path: &Path, out: &Path) -> Result<()> {
    let image = check_image(mesh, spec, spec_path)?;
    mesh_core::atomic::write_bytes_atomic(out, &image.encode_png())?;
    Ok(())
}
