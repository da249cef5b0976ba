//! A Quake 3 player assembled as one mesh per frame: the legs (`lower.md3`),
//! the torso (`upper.md3`) attached at the legs' `tag_torso`, and the head
//! (`head.md3`) at the torso's `tag_head`, as the game's
//! `CG_PositionRotatedEntityOnTag` places them (with the torso and head
//! turned straight ahead).
//!
//! Placing a model on a tag: a point `p` of the child maps to
//! `o + A p` in the parent, `o` the tag's origin and `A` its axes (columns);
//! between two animation frames the tag is interpolated linearly and its
//! axes renormalised (the game's `R_LerpTag`), the vertices linearly.
//!
//! The models store each vertex once per texture-seam side, so a surface is
//! cut into pieces along its seams. Vertices of one model that coincide in
//! every frame of that model are one point of the surface and are welded
//! ([`weld`]), so a character's mesh is a few connected pieces (the legs,
//! the torso, the head, and whatever the artist modelled apart), not
//! hundreds. Triangles made degenerate by the welding are dropped.
//!
//! Output axes and units ([`to_set_axes`]): y up, the character facing +z,
//! metres at 1/32 m per Quake unit (a player's 56-unit bounding box becomes
//! 1.75 m), feet near y = 0 (the game's bounding box starts 24 units below
//! the legs model's origin).

use std::collections::HashMap;
use std::path::Path;

use export::md3::{read_md3, Md3, Tag};
use mesh_core::{Error, Result, TriMesh};
use nalgebra::{Matrix3, Vector3};

use crate::animation_cfg::{read_animation_cfg, Animation, AnimationConfig, Model};

/// Metres per Quake unit.
pub const METRES_PER_UNIT: f64 = 1.0 / 32.0;
/// How far the game's player bounding box reaches below the legs' origin, in units.
pub const FEET_BELOW_ORIGIN: f64 = 24.0;

/// A point of a Quake model (x forward, y left, z up, units) in the capture
/// set's axes (x left of the character, y up, z forward; metres, feet at 0).
pub fn to_set_axes(p: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(p.y, p.z + FEET_BELOW_ORIGIN, p.x) * METRES_PER_UNIT
}

/// Where an animation is at one instant: `(1 - t) * frame a + t * frame b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FramePosition {
    pub a: usize,
    pub b: usize,
    pub t: f64,
}

/// One model of a character, welded: its triangles and its positions per frame.
#[derive(Clone, Debug)]
pub struct WeldedModel {
    pub faces: Vec<[u32; 3]>,
    pub frames: Vec<Vec<Vector3<f64>>>,
    /// The tags per frame, as stored.
    pub tags: Vec<Vec<Tag>>,
}

impl WeldedModel {
    fn n_frames(&self) -> usize {
        self.frames.len()
    }
    fn positions(&self, at: FramePosition) -> Vec<Vector3<f64>> {
        let (a, b) = (&self.frames[at.a], &self.frames[at.b]);
        a.iter().zip(b).map(|(p, q)| p * (1.0 - at.t) + q * at.t).collect()
    }
    /// The tag `k` interpolated at `at`, as a placement (axes, origin).
    fn tag(&self, k: usize, at: FramePosition) -> (Matrix3<f64>, Vector3<f64>) {
        let (a, b) = (&self.tags[at.a][k], &self.tags[at.b][k]);
        let origin = a.origin * (1.0 - at.t) + b.origin * at.t;
        let mut axis = a.axis * (1.0 - at.t) + b.axis * at.t;
        for mut c in axis.column_iter_mut() {
            let n = c.norm();
            if n > 0.0 {
                c /= n;
            }
        }
        (axis, origin)
    }
}

/// Welds the vertices of all `model`'s surfaces that coincide in every frame.
pub fn weld(model: &Md3) -> WeldedModel {
    let n_frames = model.frames.len();
    let mut index: HashMap<Vec<i64>, u32> = HashMap::new();
    let mut frames: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); n_frames];
    let mut faces = Vec::new();
    for s in &model.surfaces {
        let n = s.frames.first().map_or(0, Vec::len);
        let mut map = Vec::with_capacity(n);
        for v in 0..n {
            // Positions are whole 1/64 steps: exact keys.
            let key: Vec<i64> = s
                .frames
                .iter()
                .flat_map(|f| f[v].iter().map(|c| (c * 64.0).round() as i64).collect::<Vec<_>>())
                .collect();
            let next = frames[0].len() as u32;
            let id = *index.entry(key).or_insert_with(|| {
                for (f, out) in frames.iter_mut().enumerate() {
                    out.push(s.frames[f][v]);
                }
                next
            });
            map.push(id);
        }
        for t in &s.triangles {
            let w = [map[t[0] as usize], map[t[1] as usize], map[t[2] as usize]];
            if w[0] != w[1] && w[1] != w[2] && w[0] != w[2] {
                faces.push(w);
            }
        }
    }
    WeldedModel { faces, frames, tags: model.tags.clone() }
}

/// A player: its three models and its animations.
#[derive(Clone, Debug)]
pub struct Character {
    pub name: String,
    pub legs: WeldedModel,
    pub torso: WeldedModel,
    pub head: WeldedModel,
    pub animations: AnimationConfig,
    tag_torso: usize,
    tag_head: usize,
}

impl Character {
    /// Loads `dir/{lower,upper,head}.md3` and `dir/animation.cfg`; the
    /// character is named after the folder.
    pub fn load(dir: &Path) -> Result<Character> {
        let name = dir
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| Error::file(dir, "a character folder needs a plain name"))?
            .to_string();
        let lower_path = dir.join("lower.md3");
        let upper_path = dir.join("upper.md3");
        let lower = read_md3(&lower_path)?;
        let upper = read_md3(&upper_path)?;
        let head = read_md3(dir.join("head.md3"))?;
        let animations = read_animation_cfg(dir.join("animation.cfg"))?;
        let tag_torso = lower
            .tag_index("tag_torso")
            .ok_or_else(|| Error::file(&lower_path, "no tag_torso (where the torso attaches)"))?;
        let tag_head = upper
            .tag_index("tag_head")
            .ok_or_else(|| Error::file(&upper_path, "no tag_head (where the head attaches)"))?;
        Ok(Character {
            name,
            legs: weld(&lower),
            torso: weld(&upper),
            head: weld(&head),
            animations,
            tag_torso,
            tag_head,
        })
    }

    /// The animation `name`, checked against the frames of the model(s) it plays.
    pub fn animation(&self, name: &str) -> std::result::Result<Animation, String> {
        let anim = *self
            .animations
            .get(name)
            .ok_or_else(|| format!("{}: animation.cfg has no {name}", self.name))?;
        let legs = ("lower.md3", self.legs.n_frames());
        let torso = ("upper.md3", self.torso.n_frames());
        let models = match anim.model {
            Model::Legs => vec![legs],
            Model::Torso => vec![torso],
            Model::Both => vec![legs, torso],
        };
        for (file, n) in models {
            if anim.last_frame() >= n {
                return Err(format!(
                    "{}: animation.cfg's {name} shows frames {}..{} but {file} has {n}",
                    self.name,
                    anim.first,
                    anim.last_frame()
                ));
            }
        }
        Ok(anim)
    }

    /// Vertex count of the assembled mesh.
    pub fn n_vertices(&self) -> usize {
        self.legs.frames[0].len() + self.torso.frames[0].len() + self.head.frames[0].len()
    }

    /// The faces of the assembled mesh (legs, then torso, then head vertices).
    pub fn faces(&self) -> Vec<[u32; 3]> {
        let mut faces = self.legs.faces.clone();
        let mut offset = self.legs.frames[0].len() as u32;
        for model in [&self.torso, &self.head] {
            faces.extend(model.faces.iter().map(|f| [f[0] + offset, f[1] + offset, f[2] + offset]));
            offset += model.frames[0].len() as u32;
        }
        faces
    }

    /// The assembled vertex positions (in the capture set's axes) with the
    /// legs at `legs` and the torso at `torso`; the head shows its frame 0.
    /// Frame numbers must be below the models' frame counts.
    pub fn pose(&self, legs: FramePosition, torso: FramePosition) -> Vec<Vector3<f64>> {
        let (torso_axis, torso_origin) = self.legs.tag(self.tag_torso, legs);
        let (head_axis, head_origin) = self.torso.tag(self.tag_head, torso);
        let head_at = FramePosition { a: 0, b: 0, t: 0.0 };
        let mut out: Vec<Vector3<f64>> = self.legs.positions(legs);
        out.extend(self.torso.positions(torso).iter().map(|p| torso_origin + torso_axis * p));
        let (axis, origin) = (torso_axis * head_axis, torso_origin + torso_axis * head_origin);
        out.extend(self.head.positions(head_at).iter().map(|p| origin + axis * p));
        out.iter().map(to_set_axes).collect()
    }

    /// [`Character::pose`] as a mesh.
    pub fn pose_mesh(&self, legs: FramePosition, torso: FramePosition) -> TriMesh {
        TriMesh::new(self.pose(legs, torso), self.faces())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use export::md3::{Md3Frame, Surface};

    fn frame() -> Md3Frame {
        Md3Frame { name: String::new(), min: Vector3::zeros(), max: Vector3::zeros(), origin: Vector3::zeros(), radius: 0.0 }
    }

    #[test]
    fn the_set_axes_are_a_rotation_scaled_to_metres_with_the_feet_at_zero() {
        // Forward (+x) becomes +z, left (+y) becomes +x, up (+z) becomes +y.
        assert_eq!(to_set_axes(&Vector3::new(32.0, 0.0, -24.0)), Vector3::new(0.0, 0.0, 1.0));
        assert_eq!(to_set_axes(&Vector3::new(0.0, 32.0, -24.0)), Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(to_set_axes(&Vector3::new(0.0, 0.0, 32.0)), Vector3::new(0.0, 1.75, 0.0));
        // A right-handed triple stays right-handed: a rotation, not a mirror.
        let (x, y, z) = (
            to_set_axes(&Vector3::new(32.0, 0.0, -24.0)),
            to_set_axes(&Vector3::new(0.0, 32.0, -24.0)),
            to_set_axes(&Vector3::new(0.0, 0.0, 8.0)),
        );
        assert!((x.cross(&y).dot(&z) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn welding_joins_vertices_that_coincide_in_every_frame_only() {
        let p = |x: f64, y: f64| Vector3::new(x, y, 0.0);
        // Two triangles sharing an edge, stored apart (a seam); in frame 1 the
        // second triangle's copy of (1, 0) moves away, so only (0, 1) welds.
        let a = Surface {
            name: "a".into(),
            triangles: vec![[0, 1, 2]],
            frames: vec![vec![p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0)], vec![p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0)]],
        };
        let b = Surface {
            name: "b".into(),
            triangles: vec![[0, 1, 2], [0, 0, 1]],
            frames: vec![vec![p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)], vec![p(2.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]],
        };
        let model = Md3 { name: String::new(), frames: vec![frame(), frame()], tags: vec![vec![], vec![]], surfaces: vec![a, b] };
        let w = weld(&model);
        assert_eq!(w.frames[0].len(), 5);
        assert_eq!(w.faces, vec![[0, 1, 2], [3, 4, 2]], "the degenerate triangle is dropped");
        assert_eq!(w.frames[1][3], p(2.0, 0.0));
    }

    fn tag(name: &str, origin: Vector3<f64>, axis: Matrix3<f64>) -> Tag {
        Tag { name: name.into(), origin, axis }
    }

    #[test]
    fn the_torso_and_head_follow_their_tags() {
        let one = |v: Vector3<f64>| Surface { name: "s".into(), triangles: vec![], frames: vec![vec![v]] };
        let quarter_z = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let model = |tags: Vec<Tag>, v: Vector3<f64>| Md3 {
            name: String::new(),
            frames: vec![frame()],
            tags: vec![tags],
            surfaces: vec![one(v)],
        };
        let lower = model(vec![tag("tag_torso", Vector3::new(0.0, 0.0, 10.0), quarter_z)], Vector3::new(1.0, 0.0, 0.0));
        let upper = model(vec![tag("tag_head", Vector3::new(2.0, 0.0, 5.0), Matrix3::identity())], Vector3::new(1.0, 0.0, 0.0));
        let head = model(vec![], Vector3::new(0.0, 0.0, 1.0));
        let cfg = crate::animation_cfg::AnimationConfig { sex: String::new(), animations: Default::default() };
        let c = Character {
            name: "t".into(),
            legs: weld(&lower),
            torso: weld(&upper),
            head: weld(&head),
            animations: cfg,
            tag_torso: 0,
            tag_head: 0,
        };
        let at = FramePosition { a: 0, b: 0, t: 0.0 };
        let got = c.pose(at, at);
        // Torso point (1, 0, 0) turned a quarter about z is (0, 1, 0), lifted to z = 10.
        // Head: the tag at (2, 0, 5) turned is (0, 2, 5), plus 10 up, plus (0, 0, 1).
        let expected = [Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 1.0, 10.0), Vector3::new(0.0, 2.0, 16.0)];
        for (g, e) in got.iter().zip(expected) {
            assert!((g - to_set_axes(&e)).norm() < 1e-12, "{g} vs {e}");
        }
    }

    #[test]
    fn interpolated_tags_keep_unit_axes() {
        let turn = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let m = WeldedModel {
            faces: vec![],
            frames: vec![vec![], vec![]],
            tags: vec![vec![tag("t", Vector3::zeros(), Matrix3::identity())], vec![tag("t", Vector3::new(0.0, 0.0, 4.0), turn)]],
        };
        let (axis, origin) = m.tag(0, FramePosition { a: 0, b: 1, t: 0.5 });
        assert_eq!(origin, Vector3::new(0.0, 0.0, 2.0));
        for c in axis.column_iter() {
            assert!((c.norm() - 1.0).abs() < 1e-12);
        }
        let s = std::f64::consts::FRAC_1_SQRT_2;
        assert!((axis.column(0) - Vector3::new(s, s, 0.0)).norm() < 1e-12, "halfway between x and y");
    }
}
