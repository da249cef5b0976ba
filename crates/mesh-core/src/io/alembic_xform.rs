//! The matrix of an Alembic Xform sample: its operations (`.ops`, one byte each: the type in
//! the high 4 bits, a hint in the low 4) applied to its channel values (`.vals`, f64).
//!
//! Types and their channels: 0 scale (x, y, z), 1 translate (x, y, z), 2 rotate (axis x, y, z,
//! angle in degrees), 3 matrix (16 values, row-major, for row vectors: the translation is in the
//! last row), 4/5/6 rotate about x/y/z (degrees). The operations listed first are outermost: the
//! sample's matrix (column vectors, `p' = M p`) is `O_1 O_2 ... O_n`, as Alembic's
//! `XformSample::getMatrix` composes them in its row-vector convention.

#![forbid(unsafe_code)]

use nalgebra::{Matrix4, Rotation3, Unit, Vector3};

/// Channel counts per operation type, or `None` for an unknown type.
fn channels(op: u8) -> Option<usize> {
    match op >> 4 {
        0 | 1 => Some(3),
        2 => Some(4),
        3 => Some(16),
        4..=6 => Some(1),
        _ => None,
    }
}

/// Number of channels the operations `ops` take; an error names an unknown operation.
pub fn channel_count(ops: &[u8]) -> Result<usize, String> {
    ops.iter().enumerate().try_fold(0, |n, (i, &op)| {
        channels(op)
            .map(|c| n + c)
            .ok_or_else(|| format!("Xform operation {i} has unknown type {}", op >> 4))
    })
}

/// The default channel values of `ops` (scale 1, matrix identity, the rest 0): what a file
/// without `.vals` holds.
pub fn default_values(ops: &[u8]) -> Vec<f64> {
    let mut v = Vec::new();
    for &op in ops {
        match op >> 4 {
            0 => v.extend([1.0; 3]),
            3 => v.extend(Matrix4::<f64>::identity().iter()),
            _ => v.extend(std::iter::repeat_n(0.0, channels(op).unwrap_or(0))),
        }
    }
    v
}

/// The matrix (column vectors) of operations `ops` with channel values `vals`;
/// `vals.len()` must be [`channel_count`]`(ops)`.
pub fn matrix(ops: &[u8], vals: &[f64]) -> Result<Matrix4<f64>, String> {
    let need = channel_count(ops)?;
    if vals.len() != need {
        return Err(format!("Xform has {} channel values, its operations take {need}", vals.len()));
    }
    let mut m = Matrix4::identity();
    let mut at = 0;
    for &op in ops {
        let n = channels(op).unwrap_or(0);
        let c = &vals[at..at + n];
        at += n;
        let v3 = || Vector3::new(c[0], c[1], c[2]);
        let rot = |axis: Vector3<f64>, deg: f64| -> Matrix4<f64> {
            match Unit::try_new(axis, 0.0) {
                Some(a) => Rotation3::from_axis_angle(&a, deg.to_radians()).to_homogeneous(),
                None => Matrix4::identity(),
            }
        };
        let o = match op >> 4 {
            0 => Matrix4::new_nonuniform_scaling(&v3()),
            1 => Matrix4::new_translation(&v3()),
            2 => rot(v3(), c[3]),
            // Row-major for row vectors: its transpose read row-major.
            3 => Matrix4::from_row_slice(c).transpose(),
            4 => rot(Vector3::x(), c[0]),
            5 => rot(Vector3::y(), c[0]),
            _ => rot(Vector3::z(), c[0]),
        };
        m *= o;
    }
    if m.iter().all(|x: &f64| x.is_finite()) {
        Ok(m)
    } else {
        Err("Xform matrix is not finite".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(m: &Matrix4<f64>, p: [f64; 3]) -> Vector3<f64> {
        (m * Vector3::from(p).push(1.0)).xyz()
    }

    #[test]
    fn operations_compose_outermost_first() {
        // translate (1, 2, 3), rotate 90 degrees about z, scale 2: scale, then turn, then move.
        let ops = [0x10, 0x60, 0x00];
        let m = matrix(&ops, &[1.0, 2.0, 3.0, 90.0, 2.0, 2.0, 2.0]).unwrap();
        assert!((apply(&m, [1.0, 0.0, 0.0]) - Vector3::new(1.0, 4.0, 3.0)).amax() < 1e-12);
        // The same as one matrix op, row-major for row vectors (translation in the last row).
        let row = [0.0, 2.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 1.0, 2.0, 3.0, 1.0];
        let m2 = matrix(&[0x30], &row).unwrap();
        assert!((m - m2).amax() < 1e-12, "{m} {m2}");
        // Rotate about an axis, right-handed.
        let r = matrix(&[0x20], &[0.0, 0.0, 2.0, 90.0]).unwrap();
        assert!((apply(&r, [1.0, 0.0, 0.0]) - Vector3::new(0.0, 1.0, 0.0)).amax() < 1e-12);
        let rx = matrix(&[0x40], &[90.0]).unwrap();
        assert!((apply(&rx, [0.0, 1.0, 0.0]) - Vector3::new(0.0, 0.0, 1.0)).amax() < 1e-12);
        let ry = matrix(&[0x50], &[90.0]).unwrap();
        assert!((apply(&ry, [0.0, 0.0, 1.0]) - Vector3::new(1.0, 0.0, 0.0)).amax() < 1e-12);
    }

    #[test]
    fn defaults_counts_and_errors() {
        let ops = [0x00, 0x10, 0x20, 0x30, 0x40];
        assert_eq!(channel_count(&ops), Ok(3 + 3 + 4 + 16 + 1));
        let d = default_values(&ops);
        assert_eq!(d.len(), 27);
        assert_eq!(matrix(&ops, &d).unwrap(), Matrix4::identity());
        assert!(channel_count(&[0x70]).unwrap_err().contains("unknown type 7"));
        assert!(matrix(&[0x10], &[1.0]).unwrap_err().contains("take 3"));
        assert!(matrix(&[0x00], &[f64::MAX, 1.0, 1.0]).is_ok());
        assert!(matrix(&[0x00, 0x00], &[f64::MAX, 1.0, 1.0, 10.0, 1.0, 1.0]).is_err());
        // A zero axis turns nothing.
        assert_eq!(matrix(&[0x20], &[0.0, 0.0, 0.0, 45.0]).unwrap(), Matrix4::identity());
    }
}
