//! Camera: a fixed view of a bounding box, orthographic or perspective.
//!
//! The box is computed over ALL frames of ALL sequences drawn, so one camera
//! serves a whole animation and nothing leaves the frame. Views are given in
//! the subject's own frame: `up` (default +y) and the facing direction
//! (default +z); azimuth turns the eye about `up` from the front towards the
//! subject's left side (+x for the default axes), elevation lifts it.

use nalgebra::Vector3;

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vector3<f64>,
    pub max: Vector3<f64>,
}

impl Aabb {
    /// The empty box (adding any point makes it that point).
    pub fn empty() -> Self {
        Aabb {
            min: Vector3::repeat(f64::INFINITY),
            max: Vector3::repeat(f64::NEG_INFINITY),
        }
    }
    pub fn is_empty(&self) -> bool {
        (0..3).any(|k| self.min[k] > self.max[k])
    }
    /// Grows the box to contain `p` (non-finite points are ignored).
    pub fn add(&mut self, p: &Vector3<f64>) {
        if p.iter().all(|v| v.is_finite()) {
            self.min = self.min.inf(p);
            self.max = self.max.sup(p);
        }
    }
    pub fn from_points<'a>(pts: impl IntoIterator<Item = &'a Vector3<f64>>) -> Self {
        let mut b = Aabb::empty();
        for p in pts {
            b.add(p);
        }
        b
    }
    pub fn center(&self) -> Vector3<f64> {
        (self.min + self.max) * 0.5
    }
    /// The 8 corners.
    pub fn corners(&self) -> [Vector3<f64>; 8] {
        let (a, b) = (self.min, self.max);
        std::array::from_fn(|i| {
            Vector3::new(
                if i & 1 == 0 { a.x } else { b.x },
                if i & 2 == 0 { a.y } else { b.y },
                if i & 4 == 0 { a.z } else { b.z },
            )
        })
    }
}

/// A signed coordinate axis, e.g. `+y` or `-z`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Axis {
    pub index: usize,
    pub positive: bool,
}

impl Axis {
    pub const PLUS_Y: Axis = Axis {
        index: 1,
        positive: true,
    };
    /// Parses `+x`, `-y`, `z`, ... (case-insensitive).
    pub fn parse(s: &str) -> Option<Axis> {
        let s = s.trim().to_ascii_lowercase();
        let (positive, rest) = match s.strip_prefix('-') {
            Some(r) => (false, r),
            None => (true, s.strip_prefix('+').unwrap_or(&s)),
        };
        let index = match rest {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return None,
        };
        Some(Axis { index, positive })
    }
    pub fn vector(&self) -> Vector3<f64> {
        let mut v = Vector3::zeros();
        v[self.index] = if self.positive { 1.0 } else { -1.0 };
        v
    }
    /// The default facing direction for this up axis: +z when up is along y
    /// or x; when up is +z (a y-up scan rotated +90 degrees about x), facing
    /// is -y; when up is -z it is +y.
    pub fn default_facing(&self) -> Vector3<f64> {
        match (self.index, self.positive) {
            (2, true) => -Vector3::y(),
            (2, false) => Vector3::y(),
            _ => Vector3::z(),
        }
    }
}

/// Where the eye is, relative to the subject.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct View {
    /// Degrees about the up axis, 0 = in front, 90 = the subject's left side.
    pub azimuth_deg: f64,
    /// Degrees above the horizontal plane.
    pub elevation_deg: f64,
}

impl View {
    pub const FRONT: View = View {
        azimuth_deg: 0.0,
        elevation_deg: 0.0,
    };
    pub const SIDE: View = View {
        azimuth_deg: 90.0,
        elevation_deg: 0.0,
    };
    pub const THREE_QUARTER: View = View {
        azimuth_deg: 40.0,
        elevation_deg: 15.0,
    };

    /// `front`, `side`, `three-quarter` (or `3q`), or `AZ,EL` in degrees.
    pub fn parse(s: &str) -> Option<View> {
        match s.trim().to_ascii_lowercase().as_str() {
            "front" => Some(View::FRONT),
            "side" => Some(View::SIDE),
            "three-quarter" | "threequarter" | "3q" => Some(View::THREE_QUARTER),
            other => {
                let (a, e) = other.split_once(',')?;
                let (a, e) = (a.trim().parse::<f64>().ok()?, e.trim().parse::<f64>().ok()?);
                (a.is_finite() && e.is_finite() && e.abs() <= 90.0).then_some(View {
                    azimuth_deg: a,
                    elevation_deg: e,
                })
            }
        }
    }

    /// Unit vector from the subject towards the eye.
    pub fn eye_direction(&self, up: &Vector3<f64>, facing: &Vector3<f64>) -> Vector3<f64> {
        let u = up.normalize();
        let f = (facing - u * u.dot(facing)).normalize();
        let l = u.cross(&f);
        let (az, el) = (
            self.azimuth_deg.to_radians(),
            self.elevation_deg.to_radians(),
        );
        (f * az.cos() + l * az.sin()) * el.cos() + u * el.sin()
    }
}

/// Projection model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Parallel projection: `scale` pixels per world unit.
    Orthographic { scale: f64 },
    /// Pinhole: eye at `distance` from the target, vertical field of view `fov_y_deg`.
    Perspective { fov_y_deg: f64, distance: f64 },
}

/// Which projection to frame with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProjectionKind {
    Orthographic,
    Perspective { fov_y_deg: f64 },
}

/// A camera producing pixel coordinates (x right, y down, pixel centres at
/// `i + 0.5`) and a depth key that is affine in screen space and larger for
/// nearer points (camera-space z for orthographic, 1/distance for perspective).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub width: u32,
    pub height: u32,
    pub target: Vector3<f64>,
    /// Orthonormal camera basis in world coordinates; `back` points at the eye.
    pub right: Vector3<f64>,
    pub up: Vector3<f64>,
    pub back: Vector3<f64>,
    /// Image-plane offset of the framed centre from `target` (world units, camera axes).
    pub offset: [f64; 2],
    pub projection: Projection,
}

/// Fraction of the image left free on each side when framing.
pub const MARGIN: f64 = 0.05;

/// Smallest eye distance, as a fraction of the framing radius, kept between
/// the eye and any framed point (guards the perspective division).
const NEAR: f64 = 1e-6;

impl Camera {
    /// A camera looking at `bbox` from `view`, sized `width x height`, with
    /// every point of the box inside the image (5% margin).
    ///
    /// Orthographic: the 8 box corners are projected and the scale fits their
    /// extent (the projection of the box lies in the hull of its projected
    /// corners). Perspective: the eye is placed at the nearest distance where
    /// all 8 corners project inside the image (bisection from the bounding
    /// sphere's distance, which always fits); every point of the box is then
    /// in view, since its image is the hull of the corners' images.
    pub fn frame(
        bbox: &Aabb,
        view: &View,
        up_axis: &Axis,
        kind: ProjectionKind,
        width: u32,
        height: u32,
    ) -> Camera {
        let bbox = if bbox.is_empty() {
            Aabb {
                min: Vector3::repeat(-1.0),
                max: Vector3::repeat(1.0),
            }
        } else {
            *bbox
        };
        let upw = up_axis.vector();
        let back = view.eye_direction(&upw, &up_axis.default_facing());
        let mut right = upw.cross(&back);
        if right.norm() < 1e-9 {
            // Looking straight down or up: keep the facing direction pointing down the image.
            right = up_axis.default_facing().cross(&back) * -1.0;
        }
        let right = right.normalize();
        let up = back.cross(&right);
        let target = bbox.center();
        let (w, h) = (width.max(1) as f64, height.max(1) as f64);
        let mut cam = Camera {
            width: width.max(1),
            height: height.max(1),
            target,
            right,
            up,
            back,
            offset: [0.0, 0.0],
            projection: Projection::Orthographic { scale: 1.0 },
        };
        match kind {
            ProjectionKind::Orthographic => {
                let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
                for c in bbox.corners() {
                    let d = c - target;
                    let (x, y) = (d.dot(&right), d.dot(&up));
                    x0 = x0.min(x);
                    x1 = x1.max(x);
                    y0 = y0.min(y);
                    y1 = y1.max(y);
                }
                let span_x = (x1 - x0).max(1e-9);
                let span_y = (y1 - y0).max(1e-9);
                let free = 1.0 - 2.0 * MARGIN;
                let scale = (w * free / span_x).min(h * free / span_y);
                cam.offset = [(x0 + x1) * 0.5, (y0 + y1) * 0.5];
                cam.projection = Projection::Orthographic { scale };
            }
            ProjectionKind::Perspective { fov_y_deg } => {
                let fov_y = fov_y_deg.clamp(1.0, 170.0).to_radians();
                // Usable tangents of the half angles, shrunk by the margin.
                let ty = (fov_y * 0.5).tan() * (1.0 - 2.0 * MARGIN);
                let tx = ty * w / h;
                // Corners in camera axes (z towards the eye), relative to the centre.
                let corners: Vec<[f64; 3]> = bbox
                    .corners()
                    .iter()
                    .map(|c| {
                        let d = c - target;
                        [d.dot(&right), d.dot(&up), d.dot(&back)]
                    })
                    .collect();
                let fits = |dist: f64| {
                    corners.iter().all(|c| {
                        let depth = dist - c[2];
                        depth > 0.0 && c[0].abs() <= tx * depth && c[1].abs() <= ty * depth
                    })
                };
                // The bounding sphere always fits; bisect down to the nearest eye
                // distance at which all 8 corners (hence the whole box, whose
                // image is the hull of theirs) are in the image.
                let r = ((bbox.max - bbox.min).norm() * 0.5).max(1e-9);
                let mut hi = r / tx.min(ty).atan().sin() * (1.0 + 1e-9);
                let mut lo = 0.0;
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if fits(mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                let distance = hi;
                cam.projection = Projection::Perspective {
                    fov_y_deg: fov_y.to_degrees(),
                    distance,
                };
            }
        }
        cam
    }

    /// The same view rendered `s` times larger (for supersampling).
    pub fn scaled(&self, s: u32) -> Camera {
        let mut c = *self;
        c.width *= s;
        c.height *= s;
        if let Projection::Orthographic { scale } = c.projection {
            c.projection = Projection::Orthographic {
                scale: scale * s as f64,
            };
        }
        c
    }

    /// Eye position (perspective) or `None` (orthographic).
    pub fn eye(&self) -> Option<Vector3<f64>> {
        match self.projection {
            Projection::Perspective { distance, .. } => Some(self.target + self.back * distance),
            Projection::Orthographic { .. } => None,
        }
    }

    /// Camera-space coordinates of `p` relative to the framed centre
    /// (x right, y up, z towards the eye; for perspective, relative to the eye).
    #[inline]
    pub fn to_camera(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let d = p - self.target;
        let (x, y, z) = (d.dot(&self.right), d.dot(&self.up), d.dot(&self.back));
        match self.projection {
            Projection::Orthographic { .. } => {
                Vector3::new(x - self.offset[0], y - self.offset[1], z)
            }
            Projection::Perspective { distance, .. } => Vector3::new(x, y, z - distance),
        }
    }

    /// Pixel position and depth key of a camera-space point, or `None` when
    /// it is behind (or at) the eye of a perspective camera.
    #[inline]
    pub fn project_camera(&self, c: &Vector3<f64>) -> Option<[f64; 3]> {
        let (w2, h2) = (self.width as f64 * 0.5, self.height as f64 * 0.5);
        match self.projection {
            Projection::Orthographic { scale } => Some([w2 + c.x * scale, h2 - c.y * scale, c.z]),
            Projection::Perspective {
                fov_y_deg,
                distance,
            } => {
                let depth = -c.z;
                if depth <= NEAR * distance {
                    return None;
                }
                let f = h2 / (fov_y_deg.to_radians() * 0.5).tan();
                Some([w2 + f * c.x / depth, h2 - f * c.y / depth, 1.0 / depth])
            }
        }
    }

    /// Pixel position (x, y) and depth key of a world point.
    #[inline]
    pub fn project(&self, p: &Vector3<f64>) -> Option<[f64; 3]> {
        self.project_camera(&self.to_camera(p))
    }

    /// Unit vector from world point `p` towards the eye.
    #[inline]
    pub fn towards_eye(&self, p: &Vector3<f64>) -> Vector3<f64> {
        match self.eye() {
            Some(e) => (e - p).try_normalize(1e-300).unwrap_or(self.back),
            None => self.back,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inside(cam: &Camera, p: &Vector3<f64>) -> bool {
        let q = cam.project(p).unwrap();
        q[0] >= 0.0 && q[1] >= 0.0 && q[0] <= cam.width as f64 && q[1] <= cam.height as f64
    }

    #[test]
    fn front_view_looks_down_minus_z_with_y_up() {
        let b = Aabb {
            min: Vector3::new(-1.0, -1.0, -1.0),
            max: Vector3::new(1.0, 1.0, 1.0),
        };
        let cam = Camera::frame(
            &b,
            &View::FRONT,
            &Axis::PLUS_Y,
            ProjectionKind::Orthographic,
            100,
            100,
        );
        assert!((cam.back - Vector3::z()).norm() < 1e-12);
        assert!((cam.right - Vector3::x()).norm() < 1e-12);
        // +x lands right of centre, +y above centre, +z is nearer.
        let px = cam.project(&Vector3::new(0.5, 0.0, 0.0)).unwrap();
        let py = cam.project(&Vector3::new(0.0, 0.5, 0.0)).unwrap();
        let pn = cam.project(&Vector3::new(0.0, 0.0, 0.5)).unwrap();
        let pf = cam.project(&Vector3::new(0.0, 0.0, -0.5)).unwrap();
        assert!(px[0] > 50.0 && (px[1] - 50.0).abs() < 1e-9);
        assert!(py[1] < 50.0);
        assert!(pn[2] > pf[2]);
    }

    #[test]
    fn side_view_sees_subject_left_side() {
        let v = View::SIDE.eye_direction(&Vector3::y(), &Vector3::z());
        assert!((v - Vector3::x()).norm() < 1e-12);
        let up_z = Axis::parse("+z").unwrap();
        let v = View::FRONT.eye_direction(&up_z.vector(), &up_z.default_facing());
        assert!((v + Vector3::y()).norm() < 1e-12);
    }

    #[test]
    fn ortho_framing_is_tight_on_the_longer_side() {
        let b = Aabb {
            min: Vector3::new(-0.5, 0.0, -0.1),
            max: Vector3::new(0.5, 2.0, 0.1),
        };
        let cam = Camera::frame(
            &b,
            &View::FRONT,
            &Axis::PLUS_Y,
            ProjectionKind::Orthographic,
            200,
            200,
        );
        let top = cam.project(&Vector3::new(0.0, 2.0, 0.0)).unwrap();
        let bottom = cam.project(&Vector3::new(0.0, 0.0, 0.0)).unwrap();
        assert!((top[1] - 10.0).abs() < 1e-9, "{top:?}");
        assert!((bottom[1] - 190.0).abs() < 1e-9, "{bottom:?}");
    }

    #[test]
    fn every_corner_in_frame_for_all_presets_and_projections() {
        let b = Aabb {
            min: Vector3::new(-0.3, 0.0, -2.0),
            max: Vector3::new(0.4, 1.8, 3.0),
        };
        for view in [
            View::FRONT,
            View::SIDE,
            View::THREE_QUARTER,
            View {
                azimuth_deg: 200.0,
                elevation_deg: 89.0,
            },
        ] {
            for kind in [
                ProjectionKind::Orthographic,
                ProjectionKind::Perspective { fov_y_deg: 35.0 },
            ] {
                for (w, h) in [(320, 200), (200, 320)] {
                    let cam = Camera::frame(&b, &view, &Axis::PLUS_Y, kind, w, h);
                    for c in b.corners() {
                        assert!(inside(&cam, &c), "{view:?} {kind:?} {w}x{h} corner {c:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn perspective_framing_is_tight() {
        // Some corner lies on the 5% margin (within a pixel): the eye is no
        // further away than it must be.
        let b = Aabb {
            min: Vector3::new(-0.3, 0.0, -0.2),
            max: Vector3::new(0.4, 1.8, 0.3),
        };
        for view in [View::FRONT, View::THREE_QUARTER] {
            let kind = ProjectionKind::Perspective { fov_y_deg: 40.0 };
            let cam = Camera::frame(&b, &view, &Axis::PLUS_Y, kind, 300, 200);
            let gap = b
                .corners()
                .iter()
                .map(|c| {
                    let q = cam.project(c).unwrap();
                    (q[0] - 15.0)
                        .min(285.0 - q[0])
                        .min(q[1] - 10.0)
                        .min(190.0 - q[1])
                })
                .fold(f64::INFINITY, f64::min);
            assert!(
                (-1e-6..1.0).contains(&gap),
                "{view:?}: closest corner {gap} px inside the margin"
            );
        }
    }

    #[test]
    fn parses_views_and_axes() {
        assert_eq!(View::parse("side"), Some(View::SIDE));
        assert_eq!(
            View::parse("30, -10"),
            Some(View {
                azimuth_deg: 30.0,
                elevation_deg: -10.0
            })
        );
        assert_eq!(View::parse("30,100"), None);
        assert_eq!(View::parse("top"), None);
        assert_eq!(
            Axis::parse("-X"),
            Some(Axis {
                index: 0,
                positive: false
            })
        );
        assert_eq!(Axis::parse("w"), None);
    }
}
