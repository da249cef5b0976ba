//! Small closed or open test meshes built in code: an icosphere, an open
//! cylinder and a closed capsule. All are manifold and consistently oriented
//! (counter-clockwise seen from outside); the axis of the cylinder and the
//! capsule is +y ("up" in the capture-set convention).

use std::collections::HashMap;

use nalgebra::Vector3;

use crate::mesh::TriMesh;

/// Unit-radius icosphere: the icosahedron with each face split into four
/// `level` times, new vertices projected to the sphere.
/// `10 * 4^level + 2` vertices, `20 * 4^level` faces.
pub fn icosphere(level: usize) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<Vector3<f64>> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vector3::from(*p).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<Vector3<f64>>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (vertices[a as usize] + vertices[b as usize]).normalize();
                vertices.push(p);
                (vertices.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(4 * faces.len());
        for &[a, b, c] in &faces {
            let ab = midpoint(a, b, &mut vertices);
            let bc = midpoint(b, c, &mut vertices);
            let ca = midpoint(c, a, &mut vertices);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    TriMesh::new(vertices, faces)
}

/// Index of the vertex at ring `r`, segment `s` in a ring-major layout.
fn ring_vertex(first: usize, segments: usize, r: usize, s: usize) -> u32 {
    (first + r * segments + s % segments) as u32
}

/// Pushes the outward-facing quads (two triangles each) between consecutive
/// rings `0..rings` that start at vertex `first`.
fn band_faces(faces: &mut Vec<[u32; 3]>, first: usize, rings: usize, segments: usize) {
    for r in 0..rings.saturating_sub(1) {
        for s in 0..segments {
            let a = ring_vertex(first, segments, r, s);
            let b = ring_vertex(first, segments, r + 1, s);
            let c = ring_vertex(first, segments, r, s + 1);
            let d = ring_vertex(first, segments, r + 1, s + 1);
            faces.push([a, b, c]);
            faces.push([c, b, d]);
        }
    }
}

fn ring_point(radius: f64, y: f64, s: usize, segments: usize) -> Vector3<f64> {
    let th = 2.0 * std::f64::consts::PI * s as f64 / segments as f64;
    Vector3::new(radius * th.cos(), y, radius * th.sin())
}

/// Open cylinder (a tube without caps) around the +y axis from `y = 0` to
/// `y = height`: `rings >= 2` rings of `segments >= 3` vertices each, ring `r`
/// at `y = height * r / (rings - 1)`. Vertex of ring `r`, segment `s` is
/// `r * segments + s`. Its two boundary loops are the first and last rings.
pub fn cylinder(rings: usize, segments: usize, radius: f64, height: f64) -> TriMesh {
    assert!(
        rings >= 2 && segments >= 3,
        "cylinder needs >= 2 rings and >= 3 segments"
    );
    let mut vertices = Vec::with_capacity(rings * segments);
    for r in 0..rings {
        let y = height * r as f64 / (rings - 1) as f64;
        vertices.extend((0..segments).map(|s| ring_point(radius, y, s, segments)));
    }
    let mut faces = Vec::with_capacity(2 * (rings - 1) * segments);
    band_faces(&mut faces, 0, rings, segments);
    TriMesh::new(vertices, faces)
}

/// Layout of a [`capsule_body`]: which vertices form each ring.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CapsuleLayout {
    pub segments: usize,
    /// Latitude rings in each hemispherical cap (excluding the pole).
    pub cap_rings: usize,
    /// Rings of the cylindrical middle section.
    pub rings: usize,
}

impl CapsuleLayout {
    /// Total number of rings, bottom to top (caps included, poles excluded).
    pub fn n_rings(&self) -> usize {
        self.rings + 2 * self.cap_rings
    }
    /// Vertex indices of ring `k` (0 = lowest ring, next to the bottom pole),
    /// in counter-clockwise order seen from +y.
    pub fn ring(&self, k: usize) -> Vec<u32> {
        (0..self.segments)
            .map(|s| ring_vertex(1, self.segments, k, s))
            .collect()
    }
    /// Ring index of the `r`-th ring of the cylindrical middle section.
    pub fn body_ring(&self, r: usize) -> usize {
        self.cap_rings + r
    }
    pub fn bottom_pole(&self) -> u32 {
        0
    }
    pub fn top_pole(&self) -> u32 {
        (1 + self.n_rings() * self.segments) as u32
    }
}

/// Closed capsule around the +y axis: a cylinder of `radius` from `y = 0` to
/// `y = height` with `rings >= 2` rings of `segments >= 3` vertices, closed by
/// two hemispheres of `max(2, segments / 4)` latitude rings and a pole each.
/// Vertex 0 is the bottom pole, then the rings bottom to top, then the top
/// pole (see [`CapsuleLayout`]); curves for tests are easily placed on the
/// middle rings. Genus 0, manifold, outward oriented.
pub fn capsule_body(
    rings: usize,
    segments: usize,
    radius: f64,
    height: f64,
) -> (TriMesh, CapsuleLayout) {
    assert!(
        rings >= 2 && segments >= 3,
        "capsule needs >= 2 rings and >= 3 segments"
    );
    let layout = CapsuleLayout {
        segments,
        cap_rings: (segments / 4).max(2),
        rings,
    };
    let c = layout.cap_rings;
    let half_pi = std::f64::consts::FRAC_PI_2;
    let mut vertices = vec![Vector3::new(0.0, -radius, 0.0)];
    // Bottom cap: latitude from -pi/2 (pole, excluded) up to the equator (excluded).
    for k in 1..=c {
        let phi = -half_pi + half_pi * k as f64 / (c + 1) as f64;
        let pts =
            (0..segments).map(|s| ring_point(radius * phi.cos(), radius * phi.sin(), s, segments));
        vertices.extend(pts);
    }
    for r in 0..rings {
        let y = height * r as f64 / (rings - 1) as f64;
        vertices.extend((0..segments).map(|s| ring_point(radius, y, s, segments)));
    }
    for k in 1..=c {
        let phi = half_pi * k as f64 / (c + 1) as f64;
        let pts = (0..segments)
            .map(|s| ring_point(radius * phi.cos(), height + radius * phi.sin(), s, segments));
        vertices.extend(pts);
    }
    vertices.push(Vector3::new(0.0, height + radius, 0.0));
    let mut faces = Vec::new();
    band_faces(&mut faces, 1, layout.n_rings(), segments);
    let (bottom, top) = (layout.bottom_pole(), layout.top_pole());
    let last = layout.n_rings() - 1;
    for s in 0..segments {
        faces.push([
            bottom,
            ring_vertex(1, segments, 0, s),
            ring_vertex(1, segments, 0, s + 1),
        ]);
        faces.push([
            top,
            ring_vertex(1, segments, last, s + 1),
            ring_vertex(1, segments, last, s),
        ]);
    }
    (TriMesh::new(vertices, faces), layout)
}
