//! The GIF's single global palette reproduces shaded renders closely.

use mesh_core::shapes;
use nalgebra::Vector3;
use render::anim::{GifBuilder, GifPalette};
use render::{colour, Aabb, Axis, Layer, ProjectionKind, Renderer, Style, View};

#[test]
fn gif_frames_stay_close_to_the_rendered_frames() {
    // Two overlaid shaded spheres moving apart: many shades of two hues,
    // anti-aliased edges, the floor grid.
    let s = shapes::icosphere(3);
    let frames: Vec<[Vec<Vector3<f64>>; 2]> = (0..6)
        .map(|i| {
            let d = 0.2 * i as f64;
            [
                s.vertices
                    .iter()
                    .map(|p| p + Vector3::new(-d, 1.0, 0.0))
                    .collect(),
                s.vertices
                    .iter()
                    .map(|p| p + Vector3::new(d, 1.0, 0.3))
                    .collect(),
            ]
        })
        .collect();
    let bbox = Aabb::from_points(frames.iter().flatten().flatten());
    let r = Renderer::new(
        &bbox,
        &View::THREE_QUARTER,
        &Axis::PLUS_Y,
        ProjectionKind::Orthographic,
        128,
        96,
        Style::default(),
    );
    let imgs: Vec<_> = frames
        .iter()
        .map(|f| {
            r.render(&[
                Layer {
                    vertices: &f[0],
                    faces: &s.faces,
                    colour: colour::palette(0),
                    vertex_colours: None,
                },
                Layer {
                    vertices: &f[1],
                    faces: &s.faces,
                    colour: colour::palette(1),
                    vertex_colours: None,
                },
            ])
        })
        .collect();
    let refs: Vec<_> = imgs.iter().collect();
    let mut g = GifBuilder::new(128, 96, 25.0, GifPalette::learn(&refs[..3])).unwrap();
    for img in &imgs {
        g.push(img).unwrap();
    }
    let bytes = g.finish().unwrap();
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut d = opts.read_info(std::io::Cursor::new(bytes)).unwrap();
    let mut k = 0;
    while let Some(f) = d.read_next_frame().unwrap() {
        assert_eq!(f.delay, 4);
        let errs: Vec<i32> = f
            .buffer
            .chunks_exact(4)
            .zip(imgs[k].data.chunks_exact(3))
            .map(|(q, p)| {
                (0..3)
                    .map(|c| (q[c] as i32 - p[c] as i32).abs())
                    .max()
                    .unwrap()
            })
            .collect();
        let mean = errs.iter().sum::<i32>() as f64 / errs.len() as f64;
        let bad = errs.iter().filter(|&&e| e > 24).count();
        assert!(
            mean < 3.0 && bad * 200 < errs.len(),
            "frame {k}: mean error {mean}, {bad} pixels off by > 24"
        );
        k += 1;
    }
    assert_eq!(k, 6);
}
