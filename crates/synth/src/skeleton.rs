//! The body's skeleton: bones with rest heads and tails (which follow the body shape, being
//! means of vertex groups), and forward kinematics.

use std::collections::BTreeMap;

use nalgebra::{Rotation3, Vector3};

use crate::makehuman::{JointSpec, RigBone};
use mesh_core::{Error, Result};

/// One bone: rest head and tail (metres), parent index (parents come first).
#[derive(Clone, Debug)]
pub struct Bone {
    pub name: String,
    pub parent: Option<usize>,
    pub head: Vector3<f64>,
    pub tail: Vector3<f64>,
}

impl Bone {
    /// Unit rest direction head -> tail.
    pub fn direction(&self) -> Vector3<f64> {
        (self.tail - self.head).normalize()
    }
}

/// Bones in topological order (every parent before its children).
#[derive(Clone, Debug)]
pub struct Skeleton {
    pub bones: Vec<Bone>,
}

/// A posed skeleton: per bone its world rotation (relative to rest) and posed head.
#[derive(Clone, Debug)]
pub struct Pose {
    pub rotations: Vec<Rotation3<f64>>,
    pub heads: Vec<Vector3<f64>>,
}

fn joint_position(
    spec: &JointSpec,
    vertices: &[Vector3<f64>],
    groups: &BTreeMap<String, Vec<usize>>,
) -> Result<Vector3<f64>> {
    let idx: &[usize] = match spec {
        JointSpec::Cube(name) => groups.get(name).ok_or_else(|| {
            Error::invalid(format!(
                "rig: joint cube {name} not among the vertex groups"
            ))
        })?,
        JointSpec::Mean(v) => v,
    };
    let mut sum = Vector3::zeros();
    for &i in idx {
        sum += vertices
            .get(i)
            .ok_or_else(|| Error::invalid(format!("rig: vertex {i} out of range")))?;
    }
    if idx.is_empty() {
        return Err(Error::invalid("rig: empty joint vertex group"));
    }
    Ok(sum / idx.len() as f64)
}

impl Skeleton {
    /// Builds the skeleton from the rig, placing each joint at the mean of its vertex group
    /// in `vertices` (the shaped base mesh including joint cubes).
    pub fn from_rig(
        rig: &[RigBone],
        vertices: &[Vector3<f64>],
        groups: &BTreeMap<String, Vec<usize>>,
    ) -> Result<Self> {
        let mut bones: Vec<Bone> = Vec::new();
        let mut index: BTreeMap<String, usize> = BTreeMap::new();
        let mut pending: Vec<&RigBone> = rig.iter().collect();
        while !pending.is_empty() {
            let before = pending.len();
            let mut rest = Vec::new();
            for b in pending {
                let parent = match &b.parent {
                    None => None,
                    Some(p) => match index.get(p) {
                        Some(&i) => Some(i),
                        None => {
                            rest.push(b);
                            continue;
                        }
                    },
                };
                index.insert(b.name.clone(), bones.len());
                bones.push(Bone {
                    name: b.name.clone(),
                    parent,
                    head: joint_position(&b.head, vertices, groups)?,
                    tail: joint_position(&b.tail, vertices, groups)?,
                });
            }
            if rest.len() == before {
                return Err(Error::invalid(
                    "rig: unknown parent or cycle in the bone hierarchy",
                ));
            }
            pending = rest;
        }
        Ok(Skeleton { bones })
    }

    pub fn index(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }

    /// Index of the root bone (the one without parent).
    pub fn root(&self) -> usize {
        self.bones
            .iter()
            .position(|b| b.parent.is_none())
            .unwrap_or(0)
    }

    /// Translates every joint by `d`.
    pub fn translate(&mut self, d: &Vector3<f64>) {
        for b in &mut self.bones {
            b.head += d;
            b.tail += d;
        }
    }

    /// Forward kinematics from world rotations `R_b` and the posed root head:
    /// `h'_root = root`, `h'_b = h'_p + R_p (h_b - h_p)` for a bone `b` with parent `p`.
    pub fn forward_kinematics(&self, rotations: Vec<Rotation3<f64>>, root: Vector3<f64>) -> Pose {
        let mut heads = vec![Vector3::zeros(); self.bones.len()];
        for (i, b) in self.bones.iter().enumerate() {
            heads[i] = match b.parent {
                None => root + (b.head - self.bones[self.root()].head),
                Some(p) => heads[p] + rotations[p] * (b.head - self.bones[p].head),
            };
        }
        Pose { rotations, heads }
    }

    /// The rest pose (identity rotations, root at its rest head).
    pub fn rest_pose(&self) -> Pose {
        let r = self.bones[self.root()].head;
        self.forward_kinematics(vec![Rotation3::identity(); self.bones.len()], r)
    }

    /// Posed tail of bone `b`.
    pub fn posed_tail(&self, pose: &Pose, b: usize) -> Vector3<f64> {
        pose.heads[b] + pose.rotations[b] * (self.bones[b].tail - self.bones[b].head)
    }
}
