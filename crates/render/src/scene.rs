//! One image of several overlaid meshes: the camera, the lights, the floor
//! grid and the rasterizer put together.

use nalgebra::Vector3;

use crate::camera::{Aabb, Axis, Camera, ProjectionKind, View};
use crate::colour::{self, Rgb};
use crate::image::RgbImage;
use crate::lighting::{LightRig, Lights};
use crate::raster::{ScreenVertex, Target};

/// One mesh to draw: positions, triangles and a colour (or per-vertex colours).
#[derive(Clone, Copy, Debug)]
pub struct Layer<'a> {
    pub vertices: &'a [Vector3<f64>],
    pub faces: &'a [[u32; 3]],
    pub colour: Rgb,
    /// Per-vertex albedo (e.g. body parts); used instead of `colour` when its
    /// length matches `vertices`.
    pub vertex_colours: Option<&'a [Rgb]>,
}

/// Flat (one normal per face) or Gouraud (lit at vertices, interpolated) shading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    Flat,
    Gouraud,
}

/// How images look.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    pub shading: Shading,
    /// Supersampling factor per axis (1 = none, 2 = 2x2 anti-aliasing).
    pub supersample: u32,
    pub background: Rgb,
    pub lights: Lights,
    /// Draw a ground grid on the plane under the scene.
    pub floor: bool,
    pub floor_colour: Rgb,
}

impl Default for Style {
    fn default() -> Self {
        Style {
            shading: Shading::Gouraud,
            supersample: 2,
            background: colour::WHITE,
            lights: Lights::default(),
            floor: true,
            floor_colour: [170, 170, 170],
        }
    }
}

/// A ground grid: line segments on the plane through the scene's lowest
/// point along the up axis, a little wider than the scene's footprint.
#[derive(Clone, Debug, PartialEq)]
pub struct FloorGrid {
    pub lines: Vec<(Vector3<f64>, Vector3<f64>)>,
}

impl FloorGrid {
    /// Grid spacing is 1, 2 or 5 times a power of ten, about a tenth of the
    /// footprint; the grid extends 25% beyond the footprint on every side.
    pub fn under(bbox: &Aabb, up: &Axis) -> FloorGrid {
        if bbox.is_empty() {
            return FloorGrid { lines: Vec::new() };
        }
        let u = up.index;
        let (a, b) = ((u + 1) % 3, (u + 2) % 3);
        let level = if up.positive {
            bbox.min[u]
        } else {
            bbox.max[u]
        };
        let ext = (bbox.max[a] - bbox.min[a])
            .max(bbox.max[b] - bbox.min[b])
            .max(1e-6);
        let step = nice_step(ext / 10.0);
        let lo = |k: usize| ((bbox.min[k] - 0.25 * ext) / step).floor() * step;
        let hi = |k: usize| ((bbox.max[k] + 0.25 * ext) / step).ceil() * step;
        let (a0, a1, b0, b1) = (lo(a), hi(a), lo(b), hi(b));
        let point = |va: f64, vb: f64| {
            let mut p = Vector3::zeros();
            p[u] = level;
            p[a] = va;
            p[b] = vb;
            p
        };
        let mut lines = Vec::new();
        let na = ((a1 - a0) / step).round() as i64;
        let nb = ((b1 - b0) / step).round() as i64;
        for i in 0..=na.min(1000) {
            let va = a0 + i as f64 * step;
            lines.push((point(va, b0), point(va, b1)));
        }
        for j in 0..=nb.min(1000) {
            let vb = b0 + j as f64 * step;
            lines.push((point(a0, vb), point(a1, vb)));
        }
        FloorGrid { lines }
    }
}

/// The 1-2-5 series value nearest to `x` (x > 0).
fn nice_step(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    let m = x / p;
    let k = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    k * p
}

/// Everything fixed for a whole animation: camera, style, floor, lights.
#[derive(Clone, Debug)]
pub struct Renderer {
    pub camera: Camera,
    pub style: Style,
    pub floor: Option<FloorGrid>,
}

impl Renderer {
    /// Frames `bbox` (which should cover every frame of every sequence).
    pub fn new(
        bbox: &Aabb,
        view: &View,
        up: &Axis,
        projection: ProjectionKind,
        width: u32,
        height: u32,
        style: Style,
    ) -> Self {
        let camera = Camera::frame(bbox, view, up, projection, width, height);
        let floor = style.floor.then(|| FloorGrid::under(bbox, up));
        Renderer {
            camera,
            style,
            floor,
        }
    }

    /// Draws the layers (and the floor) into a `width x height` image.
    pub fn render(&self, layers: &[Layer]) -> RgbImage {
        self.render_with_lines(layers, &[], 0.0)
    }

    /// [`Renderer::render`], then world segments `(a, b, colour)` drawn over the surfaces
    /// where they are not hidden (depth-tested, each end moved `bias` world units towards the
    /// eye so that lines lying on a surface are not hidden by it), one output pixel wide.
    pub fn render_with_lines(&self, layers: &[Layer], lines: &[(Vector3<f64>, Vector3<f64>, Rgb)], bias: f64) -> RgbImage {
        let s = self.style.supersample.clamp(1, 4);
        let cam = self.camera.scaled(s);
        let rig = LightRig::new(self.style.lights, &cam);
        let mut target = Target::new(cam.width, cam.height, self.style.background);
        if let Some(floor) = &self.floor {
            let far = cam.eye().map(|e| (e - cam.target).norm());
            for (p, q) in &floor.lines {
                if let Some((a, b)) = project_segment(&cam, p, q, far) {
                    target.draw_line(a, b, self.style.floor_colour);
                }
            }
        }
        for layer in layers {
            draw_layer(&mut target, &cam, &rig, layer, self.style.shading);
        }
        for (p, q, colour) in lines {
            let (p, q) = (p + cam.towards_eye(p) * bias, q + cam.towards_eye(q) * bias);
            if let Some((a, b)) = project_segment(&cam, &p, &q, None) {
                // One output pixel wide: every supersample offset of the block.
                for dx in 0..s {
                    for dy in 0..s {
                        let o = |v: ScreenVertex| [v[0] + dx as f32, v[1] + dy as f32, v[2]];
                        target.draw_line(o(a), o(b), *colour);
                    }
                }
            }
        }
        target.resolve(s)
    }
}

/// Projects a world segment, clipping it against the perspective near plane.
fn project_segment(
    cam: &Camera,
    p: &Vector3<f64>,
    q: &Vector3<f64>,
    distance: Option<f64>,
) -> Option<(ScreenVertex, ScreenVertex)> {
    let (mut a, mut b) = (cam.to_camera(p), cam.to_camera(q));
    if let Some(d) = distance {
        let near = -0.01 * d; // camera-space z must be below this
        if a.z > near && b.z > near {
            return None;
        }
        if a.z > near || b.z > near {
            let t = (near - a.z) / (b.z - a.z);
            let m = a + (b - a) * t;
            if a.z > near {
                a = m;
            } else {
                b = m;
            }
        }
    }
    let f = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
    Some((f(cam.project_camera(&a)?), f(cam.project_camera(&b)?)))
}

/// Area-weighted vertex normals (sum of unnormalised face normals).
pub fn vertex_normals(vertices: &[Vector3<f64>], faces: &[[u32; 3]]) -> Vec<Vector3<f64>> {
    let mut n = vec![Vector3::zeros(); vertices.len()];
    for f in faces {
        let [i, j, k] = f.map(|v| v as usize);
        if i >= n.len() || j >= n.len() || k >= n.len() {
            continue;
        }
        let fn_ = (vertices[j] - vertices[i]).cross(&(vertices[k] - vertices[i]));
        if fn_.iter().all(|v| v.is_finite()) {
            n[i] += fn_;
            n[j] += fn_;
            n[k] += fn_;
        }
    }
    for v in &mut n {
        *v = v.try_normalize(0.0).unwrap_or_else(Vector3::zeros);
    }
    n
}

fn draw_layer(target: &mut Target, cam: &Camera, rig: &LightRig, layer: &Layer, shading: Shading) {
    let verts = layer.vertices;
    let albedo = |i: usize| match layer.vertex_colours {
        Some(c) if c.len() == verts.len() => c[i],
        _ => layer.colour,
    };
    let screen: Vec<Option<ScreenVertex>> = verts
        .iter()
        .map(|p| {
            let q = cam.project(p)?;
            q.iter()
                .all(|v| v.is_finite())
                .then(|| [q[0] as f32, q[1] as f32, q[2] as f32])
        })
        .collect();
    let lit: Vec<[f32; 3]> = match shading {
        Shading::Gouraud => {
            let normals = vertex_normals(verts, layer.faces);
            (0..verts.len())
                .map(|i| rig.shade(albedo(i), &normals[i], &cam.towards_eye(&verts[i])))
                .collect()
        }
        Shading::Flat => Vec::new(),
    };
    let n = verts.len();
    for f in layer.faces {
        let [i, j, k] = f.map(|v| v as usize);
        if i >= n || j >= n || k >= n {
            continue;
        }
        let (Some(a), Some(b), Some(c)) = (screen[i], screen[j], screen[k]) else {
            continue;
        };
        let colours = match shading {
            Shading::Gouraud => [lit[i], lit[j], lit[k]],
            Shading::Flat => {
                let (p, q, r) = (&verts[i], &verts[j], &verts[k]);
                let normal = (q - p)
                    .cross(&(r - p))
                    .try_normalize(0.0)
                    .unwrap_or_else(Vector3::zeros);
                let e = cam.towards_eye(&((p + q + r) / 3.0));
                [
                    rig.shade(albedo(i), &normal, &e),
                    rig.shade(albedo(j), &normal, &e),
                    rig.shade(albedo(k), &normal, &e),
                ]
            }
        };
        target.fill_triangle([a, b, c], colours);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps() {
        assert_eq!(nice_step(0.17), 0.2);
        assert_eq!(nice_step(0.09), 0.1);
        assert_eq!(nice_step(4.0), 5.0);
        assert_eq!(nice_step(1.2), 1.0);
    }

    #[test]
    fn floor_grid_lies_on_the_lowest_plane_and_covers_the_footprint() {
        let b = Aabb {
            min: Vector3::new(-0.3, 0.1, -0.2),
            max: Vector3::new(0.3, 1.8, 0.2),
        };
        let g = FloorGrid::under(&b, &Axis::PLUS_Y);
        assert!(!g.lines.is_empty());
        let fb = Aabb::from_points(g.lines.iter().flat_map(|(p, q)| [p, q]));
        assert_eq!((fb.min.y, fb.max.y), (0.1, 0.1));
        assert!(fb.min.x <= -0.3 && fb.max.x >= 0.3 && fb.min.z <= -0.2 && fb.max.z >= 0.2);
    }

    #[test]
    fn vertex_normals_of_a_flat_quad_point_along_z() {
        let v = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let n = vertex_normals(&v, &[[0, 1, 2], [0, 2, 3]]);
        for x in n {
            assert!((x - Vector3::z()).norm() < 1e-12);
        }
    }
}
