//! Small test meshes (private to the tests and benches).
// NOTE(next): use mesh_core::shapes::{cylinder, icosphere} once they exist.
#![allow(dead_code)]

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

/// Deterministic pseudo-random number in [0, 1) from an integer.
pub fn hash01(i: u64) -> f64 {
    let mut x = i
        .wrapping_mul(0x9E3779B97F4A7C15)
        .wrapping_add(0x632BE59BD9B4E019);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58476D1CE4E5B9);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

pub fn rot(axis: [f64; 3], angle: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::from(axis)), angle).into_inner()
}

/// Flat (nx+1) x (ny+1) grid on [0,1]², interior vertices jittered by up to `jitter` cells.
pub fn grid(nx: usize, ny: usize, jitter: f64) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>, Vec<bool>) {
    let mut v = Vec::new();
    let mut interior = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let inside = i > 0 && i < nx && j > 0 && j < ny;
            let k = (j * (nx + 1) + i) as u64;
            let (dx, dy) = if inside {
                (
                    jitter * (hash01(2 * k) - 0.5),
                    jitter * (hash01(2 * k + 1) - 0.5),
                )
            } else {
                (0.0, 0.0)
            };
            v.push(Vector3::new(
                (i as f64 + dx) / nx as f64,
                (j as f64 + dy) / ny as f64,
                0.0,
            ));
            interior.push(inside);
        }
    }
    let mut f = Vec::new();
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..ny {
        for i in 0..nx {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (v, f, interior)
}

/// Tube along +z: `rings` rings of `around` vertices (index ring*around + j), radius r, ring
/// spacing h, outward-facing triangles; with `capped`, two centre vertices close the ends
/// (bottom = rings*around, top = rings*around + 1).
pub fn tube(
    around: usize,
    rings: usize,
    r: f64,
    h: f64,
    capped: bool,
) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for k in 0..rings {
        for j in 0..around {
            let t = 2.0 * std::f64::consts::PI * j as f64 / around as f64;
            v.push(Vector3::new(r * t.cos(), r * t.sin(), k as f64 * h));
        }
    }
    let id = |k: usize, j: usize| (k * around + j % around) as u32;
    let mut f = Vec::new();
    for k in 0..rings - 1 {
        for j in 0..around {
            let (a, b, c, d) = (id(k, j), id(k, j + 1), id(k + 1, j), id(k + 1, j + 1));
            f.push([a, b, d]);
            f.push([a, d, c]);
        }
    }
    if capped {
        let (bot, top) = ((rings * around) as u32, (rings * around + 1) as u32);
        v.push(Vector3::new(0.0, 0.0, 0.0));
        v.push(Vector3::new(0.0, 0.0, (rings - 1) as f64 * h));
        for j in 0..around {
            f.push([bot, id(0, j + 1), id(0, j)]);
            f.push([top, id(rings - 1, j), id(rings - 1, j + 1)]);
        }
    }
    (v, f)
}

/// Bends points of a z-axis tube: below z0 unchanged, then the axis follows a circular arc of
/// radius `rho` turning by `angle` (about the y axis) over arc length `rho*angle`, then
/// continues straight. Cross-sections stay perpendicular to the axis.
pub fn bend(v: &[Vector3<f64>], z0: f64, rho: f64, angle: f64) -> Vec<Vector3<f64>> {
    let len = rho * angle;
    v.iter()
        .map(|p| {
            let s = p.z - z0;
            if s <= 0.0 {
                return *p;
            }
            let th = (s.min(len)) / rho;
            // axis point and frame at arc parameter th; turning towards +x
            let c = Vector3::new(rho * (1.0 - th.cos()), 0.0, z0 + rho * th.sin());
            let t = Vector3::new(th.sin(), 0.0, th.cos());
            let nx = Vector3::new(th.cos(), 0.0, -th.sin());
            let extra = (s - len).max(0.0);
            c + t * extra + nx * p.x + Vector3::y() * p.y
        })
        .collect()
}

/// Signed volume of a closed, outward-oriented mesh.
pub fn volume(v: &[Vector3<f64>], f: &[[u32; 3]]) -> f64 {
    f.iter()
        .map(|t| v[t[0] as usize].dot(&v[t[1] as usize].cross(&v[t[2] as usize])) / 6.0)
        .sum()
}

/// Lengths of all face edges (each interior edge twice).
pub fn edge_lengths(v: &[Vector3<f64>], f: &[[u32; 3]]) -> Vec<f64> {
    f.iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .map(|(a, b)| (v[a as usize] - v[b as usize]).norm())
        .collect()
}

pub fn max_dist(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max)
}
