//! Lambert shading with a head light, a fill light and ambient light.
//!
//! `I = albedo * min(1, ambient + head * max(0, n.e) + fill * max(0, n.f))`
//! where `e` points from the surface to the eye (the head light sits on the
//! camera) and `f` is the fill light's direction, fixed in camera space
//! (from the upper left, slightly in front). Lighting is two-sided: a normal
//! facing away from the eye is flipped, so open meshes and inconsistently
//! oriented faces are lit like their front side.

use nalgebra::Vector3;

use crate::camera::Camera;
use crate::colour::Rgb;

/// Light intensities (fractions of the albedo).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lights {
    pub ambient: f32,
    pub head: f32,
    pub fill: f32,
}

impl Default for Lights {
    fn default() -> Self {
        Lights {
            ambient: 0.28,
            head: 0.62,
            fill: 0.25,
        }
    }
}

/// Lights placed for one camera.
#[derive(Clone, Copy, Debug)]
pub struct LightRig {
    pub lights: Lights,
    /// Unit direction towards the fill light (world coordinates).
    pub fill_dir: Vector3<f64>,
}

impl LightRig {
    pub fn new(lights: Lights, camera: &Camera) -> Self {
        let d = camera.right * -0.55 + camera.up * 0.7 + camera.back * 0.45;
        LightRig {
            lights,
            fill_dir: d.normalize(),
        }
    }

    /// Light intensity for unit normal `n` seen along `to_eye` (unit, surface to eye).
    #[inline]
    pub fn intensity(&self, n: &Vector3<f64>, to_eye: &Vector3<f64>) -> f32 {
        let mut ne = n.dot(to_eye);
        let mut nf = n.dot(&self.fill_dir);
        if ne < 0.0 {
            ne = -ne;
            nf = -nf;
        }
        let l = &self.lights;
        l.ambient + l.head * ne as f32 + l.fill * nf.max(0.0) as f32
    }

    /// Shaded colour (0..255 per channel, as f32 for interpolation).
    #[inline]
    pub fn shade(&self, albedo: Rgb, n: &Vector3<f64>, to_eye: &Vector3<f64>) -> [f32; 3] {
        let i = self.intensity(n, to_eye);
        albedo.map(|c| (c as f32 * i).min(255.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lambert_falls_off_with_the_cosine_and_is_two_sided() {
        let rig = LightRig {
            lights: Lights {
                ambient: 0.1,
                head: 0.9,
                fill: 0.0,
            },
            fill_dir: Vector3::y(),
        };
        let e = Vector3::z();
        assert!((rig.intensity(&Vector3::z(), &e) - 1.0).abs() < 1e-6);
        let n60 = Vector3::new(60f64.to_radians().sin(), 0.0, 60f64.to_radians().cos());
        assert!((rig.intensity(&n60, &e) - (0.1 + 0.9 * 0.5)).abs() < 1e-6);
        assert_eq!(rig.intensity(&-n60, &e), rig.intensity(&n60, &e));
        assert!((rig.intensity(&Vector3::x(), &e) - 0.1).abs() < 1e-6);
    }
}
