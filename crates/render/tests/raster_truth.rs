//! Rendering against independent truth: pixel areas of known shapes,
//! occlusion, framing, determinism.

use mesh_core::shapes;
use nalgebra::Vector3;
use render::colour::{self, WHITE};
use render::scene::Shading;
use render::{Aabb, Axis, Layer, ProjectionKind, Renderer, RgbImage, Style, View};

fn plain_style(supersample: u32) -> Style {
    Style {
        supersample,
        floor: false,
        shading: Shading::Flat,
        ..Style::default()
    }
}

/// Renderer looking at the square [-1,1]^2 (z in [-1,1]) from the front:
/// orthographic scale = 0.9 * size / 2 pixels per unit (5% margins).
fn front_renderer(size: u32, supersample: u32) -> Renderer {
    let b = Aabb {
        min: Vector3::new(-1.0, -1.0, -1.0),
        max: Vector3::new(1.0, 1.0, 1.0),
    };
    Renderer::new(
        &b,
        &View::FRONT,
        &Axis::PLUS_Y,
        ProjectionKind::Orthographic,
        size,
        size,
        plain_style(supersample),
    )
}

fn quad(z: f64, half: f64) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    let v = vec![
        Vector3::new(-half, -half, z),
        Vector3::new(half, -half, z),
        Vector3::new(half, half, z),
        Vector3::new(-half, half, z),
    ];
    (v, vec![[0, 1, 2], [0, 2, 3]])
}

/// Coverage in pixels: each pixel counts by how far it moved from the
/// background towards the (uniform) shape colour, so anti-aliased edges count
/// fractionally.
fn coverage(img: &RgbImage, shape: [u8; 3]) -> f64 {
    img.data
        .chunks_exact(3)
        .map(|p| {
            let (num, den): (f64, f64) = (0..3).fold((0.0, 0.0), |(n, d), k| {
                let dk = WHITE[k] as f64 - shape[k] as f64;
                (n + (WHITE[k] as f64 - p[k] as f64) * dk, d + dk * dk)
            });
            (num / den).clamp(0.0, 1.0)
        })
        .sum()
}

fn centre_colour(img: &RgbImage) -> [u8; 3] {
    img.get(img.width / 2, img.height / 2)
}

#[test]
fn unit_quad_and_triangle_cover_their_area() {
    for ss in [1, 2] {
        let r = front_renderer(200, ss);
        let scale = 0.9 * 200.0 / 2.0; // pixels per unit
        let (v, f) = quad(0.0, 0.5);
        let layer = Layer {
            vertices: &v,
            faces: &f,
            colour: colour::palette(0),
            vertex_colours: None,
        };
        let img = r.render(&[layer]);
        let shade = centre_colour(&img);
        let area = coverage(&img, shade);
        let expect = scale * scale;
        assert!(
            (area - expect).abs() / expect < 0.02,
            "quad ss={ss}: {area} px vs {expect}"
        );
        let tri = Layer {
            faces: &f[..1],
            ..layer
        };
        let img = r.render(&[tri]);
        let area = coverage(&img, shade);
        assert!(
            (area - expect / 2.0).abs() / (expect / 2.0) < 0.02,
            "triangle ss={ss}: {area} px vs {}",
            expect / 2.0
        );
    }
}

#[test]
fn nearer_mesh_occludes_farther_in_either_draw_order() {
    let r = front_renderer(64, 2);
    let (near, f) = quad(0.3, 0.5);
    let (far, _) = quad(-0.3, 0.8);
    let (cn, cf) = (colour::palette(1), colour::palette(0));
    let ln = Layer {
        vertices: &near,
        faces: &f,
        colour: cn,
        vertex_colours: None,
    };
    let lf = Layer {
        vertices: &far,
        faces: &f,
        colour: cf,
        vertex_colours: None,
    };
    for layers in [[ln, lf], [lf, ln]] {
        let img = r.render(&layers);
        let c = centre_colour(&img);
        // Orange (near) has red > blue; blue (far) has blue > red.
        assert!(c[0] > c[2], "centre {c:?} is not the near (orange) quad");
        // Where only the far quad is, it shows.
        let e = img.get(
            img.width / 2,
            (img.height as f64 * 0.5 - 0.65 * 0.9 * 32.0) as u32,
        );
        assert!(e[2] > e[0], "far quad missing at its rim: {e:?}");
    }
}

#[test]
fn framing_keeps_a_moving_mesh_inside_every_image() {
    // A capsule walking 3 units along +x and 1 along -z over 10 frames.
    let (m, _) = shapes::capsule_body(6, 16, 0.2, 1.4);
    let frames: Vec<Vec<Vector3<f64>>> = (0..10)
        .map(|i| {
            m.vertices
                .iter()
                .map(|p| p + Vector3::new(0.3 * i as f64, 0.0, -0.1 * i as f64))
                .collect()
        })
        .collect();
    let bbox = Aabb::from_points(frames.iter().flatten());
    for view in [View::FRONT, View::SIDE, View::THREE_QUARTER] {
        for proj in [
            ProjectionKind::Orthographic,
            ProjectionKind::Perspective { fov_y_deg: 40.0 },
        ] {
            let r = Renderer::new(&bbox, &view, &Axis::PLUS_Y, proj, 160, 120, plain_style(1));
            for fr in &frames {
                for p in fr {
                    let q = r.camera.project(p).unwrap();
                    assert!(
                        q[0] > 0.0 && q[0] < 160.0 && q[1] > 0.0 && q[1] < 120.0,
                        "{view:?} {proj:?}: vertex at {q:?}"
                    );
                }
                let img = r.render(&[Layer {
                    vertices: fr,
                    faces: &m.faces,
                    colour: colour::palette(0),
                    vertex_colours: None,
                }]);
                let border_clear = (0..160)
                    .all(|x| img.get(x, 0) == WHITE && img.get(x, 119) == WHITE)
                    && (0..120).all(|y| img.get(0, y) == WHITE && img.get(159, y) == WHITE);
                assert!(
                    border_clear,
                    "{view:?} {proj:?}: mesh touches the image border"
                );
            }
        }
    }
}

#[test]
fn same_input_gives_identical_png_bytes() {
    let s = shapes::icosphere(3);
    let b = Aabb::from_points(&s.vertices);
    let r = Renderer::new(
        &b,
        &View::THREE_QUARTER,
        &Axis::PLUS_Y,
        ProjectionKind::Perspective { fov_y_deg: 30.0 },
        96,
        80,
        Style::default(),
    );
    let l = Layer {
        vertices: &s.vertices,
        faces: &s.faces,
        colour: colour::palette(2),
        vertex_colours: None,
    };
    let a = r.render(&[l]).encode_png();
    let b = r.render(&[l]).encode_png();
    assert_eq!(a, b);
    let dec = png::Decoder::new(std::io::Cursor::new(a));
    let info = dec.read_info().unwrap();
    assert_eq!((info.info().width, info.info().height), (96, 80));
}

#[test]
fn sphere_is_shaded_brightest_facing_the_head_light() {
    // Head light on the camera: the sphere's centre (normal towards the eye) is
    // brighter than a point near its rim, for both shading modes.
    let s = shapes::icosphere(3);
    let b = Aabb {
        min: Vector3::repeat(-1.0),
        max: Vector3::repeat(1.0),
    };
    for shading in [Shading::Flat, Shading::Gouraud] {
        let st = Style {
            shading,
            floor: false,
            ..Style::default()
        };
        let r = Renderer::new(
            &b,
            &View::FRONT,
            &Axis::PLUS_Y,
            ProjectionKind::Orthographic,
            100,
            100,
            st,
        );
        let img = r.render(&[Layer {
            vertices: &s.vertices,
            faces: &s.faces,
            colour: [200, 200, 200],
            vertex_colours: None,
        }]);
        let lum = |p: [u8; 3]| p.iter().map(|&c| c as u32).sum::<u32>();
        let centre = lum(img.get(50, 50));
        let rim = lum(img.get(50 + 40, 50)); // 0.89 of the radius, right side
        assert!(centre > rim + 60, "{shading:?}: centre {centre} rim {rim}");
    }
}

#[test]
fn z_up_data_with_up_z_looks_like_y_up_data() {
    // Rotating the scene +90 degrees about x (y -> z, z -> -y) and telling the
    // camera that up is +z must give the same picture (facing +z becomes -y).
    let (m, _) = shapes::capsule_body(6, 16, 0.2, 1.4);
    let bent: Vec<Vector3<f64>> = m
        .vertices
        .iter()
        .map(|p| Vector3::new(p.x + 0.3 * p.y * p.y, p.y, p.z + 0.1 * p.y))
        .collect();
    let rot: Vec<Vector3<f64>> = bent.iter().map(|p| Vector3::new(p.x, -p.z, p.y)).collect();
    for view in [View::FRONT, View::SIDE, View::THREE_QUARTER] {
        let draw = |v: &[Vector3<f64>], up: Axis| {
            let r = Renderer::new(
                &Aabb::from_points(v),
                &view,
                &up,
                ProjectionKind::Orthographic,
                120,
                120,
                Style::default(),
            );
            r.render(&[Layer {
                vertices: v,
                faces: &m.faces,
                colour: colour::palette(3),
                vertex_colours: None,
            }])
        };
        let a = draw(&bent, Axis::PLUS_Y);
        let b = draw(&rot, Axis::parse("+z").unwrap());
        let close = a
            .data
            .chunks_exact(3)
            .zip(b.data.chunks_exact(3))
            .filter(|(p, q)| (0..3).all(|k| (p[k] as i32 - q[k] as i32).abs() <= 8))
            .count();
        assert!(
            close as f64 >= 0.99 * (120.0 * 120.0),
            "{view:?}: only {close} of 14400 pixels agree"
        );
        // And the picture is not trivially empty.
        assert!(a.data.chunks_exact(3).filter(|p| *p != WHITE).count() > 1000);
    }
}
