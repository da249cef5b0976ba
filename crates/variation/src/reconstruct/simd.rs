//! Placement of the vertices of a block that are in one part only, with AVX2 when the CPU has it.

use mesh_core::rigid::RigidMotion;
use nalgebra::Vector3;

/// `o[v_i] = F(x_i, y_i, z_i)` for the vertices of a block that are in one part only; with
/// AVX2 when the CPU has it (the same arithmetic, no FMA contraction: identical results).
pub(super) fn place_singles(o: &mut [Vector3<f64>], vs: &[u32], p: [&[f64]; 3], f: &RigidMotion) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        unsafe { place_singles_avx2(o, vs, p, f) };
        return;
    }
    place_singles_soa(o, vs, p, f)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn place_singles_avx2(o: &mut [Vector3<f64>], vs: &[u32], p: [&[f64]; 3], f: &RigidMotion) {
    place_singles_soa(o, vs, p, f)
}

#[inline(always)]
fn place_singles_soa(o: &mut [Vector3<f64>], vs: &[u32], p: [&[f64]; 3], f: &RigidMotion) {
    let r = f.rotation.matrix();
    let t = f.translation;
    let [xs, ys, zs] = p;
    let n = vs.len().min(xs.len()).min(ys.len()).min(zs.len());
    for i in 0..n {
        let (x, y, z) = (xs[i], ys[i], zs[i]);
        o[vs[i] as usize] = Vector3::new(
            r[(0, 0)] * x + r[(0, 1)] * y + r[(0, 2)] * z + t[0],
            r[(1, 0)] * x + r[(1, 1)] * y + r[(1, 2)] * z + t[1],
            r[(2, 0)] * x + r[(2, 1)] * y + r[(2, 2)] * z + t[2],
        );
    }
}
