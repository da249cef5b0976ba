//! The capture-set format (documented in docs/FORMATS.md):
//!
//! ```text
//! <set>/set.json                       SetSpec
//! <set>/<subject>/subject.json         SubjectSpec
//! <set>/<subject>/<motion>/000000.ply  one file per frame (PLY or OBJ)
//! <set>/truth/<subject>/<motion>/...   optional ground truth
//! ```
//!
//! These structs are the serde form of the JSON files. Next to them:
//! loading with one-line errors naming the file ([`SetSpec::load`],
//! [`SubjectSpec::load`]), the directory layout ([`CaptureSet`]), and the
//! validation of a subject's part tree and curves against its template mesh
//! ([`SubjectSpec::validate`], [`resolve_loop`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::sequence::frame_files;
use crate::topology::Topology;

/// `<set>/set.json`: which subject is the source, which the target, the
/// training motion pairs with their key-pose correspondences, and the test
/// motions (of the source subject).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SetSpec {
    pub source: String,
    pub target: String,
    pub train: Vec<TrainPair>,
    #[serde(default)]
    pub test: Vec<String>,
    /// Optional extra fields (e.g. the target subject's own test motions).
    #[serde(flatten)]
    pub extra: BTreeMap<String, serde_json::Value>,
}

/// One training motion pair: the source subject's motion, the target
/// subject's motion, and sparse key-pose correspondences `[src_frame, tgt_frame]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainPair {
    pub source: String,
    pub target: String,
    pub keyposes: Vec<[usize; 2]>,
    #[serde(flatten)]
    pub extra: BTreeMap<String, serde_json::Value>,
}

/// The part tree `propose-curves` writes into a `subject.json` that has none: part name and
/// parent (the body's own left and right).
pub const PROPOSED_PART_TREE: [(&str, Option<&str>); 5] = [
    ("torso", None),
    ("arm_l", Some("torso")),
    ("arm_r", Some("torso")),
    ("leg_l", Some("torso")),
    ("leg_r", Some("torso")),
];

/// `<set>/<subject>/subject.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SubjectSpec {
    pub fps: f64,
    #[serde(default = "default_units")]
    pub units: String,
    #[serde(default = "default_up")]
    pub up: String,
    /// Part tree: part name -> parent part name (`null` for the root). May be
    /// empty when the subject has no curves yet ([`SubjectSpec::needs_curves`]).
    #[serde(default)]
    pub parts: BTreeMap<String, Option<String>>,
    /// Per non-root part: its curves as vertex loops, first the loop near the
    /// parent, then the loop further down the limb. The band between them is
    /// the part's overlap with its parent.
    #[serde(default)]
    pub curves: BTreeMap<String, Vec<Vec<u32>>>,
    #[serde(flatten)]
    pub extra: BTreeMap<String, serde_json::Value>,
}

fn default_units() -> String {
    "m".to_string()
}
fn default_up() -> String {
    "+y".to_string()
}

/// Parses JSON; the error is one line.
fn parse_json<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> std::result::Result<T, String> {
    serde_json::from_slice(bytes).map_err(|e| format!("invalid JSON: {e}"))
}

/// A subject or motion name must be a plain directory name.
pub(crate) fn check_name(what: &str, name: &str) -> std::result::Result<(), String> {
    let bad = name.is_empty()
        || name == "."
        || name == ".."
        || name.contains(['/', '\\'])
        || name.chars().any(char::is_control);
    if bad {
        Err(format!(
            "{what} name '{name}' is not a plain directory name"
        ))
    } else {
        Ok(())
    }
}

impl SetSpec {
    /// Loads `set.json`, checking that subject and motion names are plain
    /// directory names and that there is at least one training pair.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = crate::input::read_regular_file(path)?;
        Self::parse(&bytes).map_err(|m| Error::file(path, m))
    }

    /// [`SetSpec::load`] of bytes held in memory (the error without the file name).
    pub fn parse(bytes: &[u8]) -> std::result::Result<Self, String> {
        let spec: SetSpec = parse_json(bytes)?;
        spec.check()?;
        Ok(spec)
    }

    fn check(&self) -> std::result::Result<(), String> {
        check_name("source subject", &self.source)?;
        check_name("target subject", &self.target)?;
        if self.train.is_empty() {
            return Err("no training motion pairs ('train' is empty)".into());
        }
        for (i, t) in self.train.iter().enumerate() {
            check_name("training source motion", &t.source)?;
            check_name("training target motion", &t.target)?;
            if t.keyposes.is_empty() {
                return Err(format!(
                    "training pair {i} ({} / {}) has no keyposes",
                    t.source, t.target
                ));
            }
        }
        for m in &self.test {
            check_name("test motion", m)?;
        }
        Ok(())
    }
}

impl SubjectSpec {
    /// Loads `subject.json`, checking the frame rate and the part tree (see
    /// [`SubjectSpec::check_parts`]) unless it still needs its curves: such a
    /// subject loads, and the stages that need parts say so
    /// ([`SubjectSpec::needs_curves`]). Curves are checked against the template
    /// mesh by [`SubjectSpec::validate`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = crate::input::read_regular_file(path)?;
        Self::parse(&bytes).map_err(|m| Error::file(path, m))
    }

    /// [`SubjectSpec::load`] of bytes held in memory (the error without the file name).
    pub fn parse(bytes: &[u8]) -> std::result::Result<Self, String> {
        let spec: SubjectSpec = parse_json(bytes)?;
        crate::frame_rate::check_fps(spec.fps).map_err(|e| format!("'fps': {e}"))?;
        if spec.up_vector().is_none() {
            return Err(format!("up must be one of +x -x +y -y +z -z, got '{}'", spec.up));
        }
        if !spec.needs_curves() {
            spec.check_parts().map_err(|e| e.to_string())?;
        }
        Ok(spec)
    }

    /// Whether the description still lacks its part curves: no curves at all, and
    /// no part tree or one with limbs (a lab's own `subject.json` may have neither
    /// curves nor a part tree: `propose-curves` finds both). A tree of the root
    /// alone needs none.
    pub fn needs_curves(&self) -> bool {
        self.curves.is_empty() && (self.parts.is_empty() || self.parts.values().any(Option::is_some))
    }

    /// The unit "up" axis named by `up` (`"+y"`, `"-z"`, ...), if valid.
    pub fn up_vector(&self) -> Option<nalgebra::Vector3<f64>> {
        let (sign, axis) = match self.up.as_bytes() {
            [b'+', a] => (1.0, *a),
            [b'-', a] => (-1.0, *a),
            _ => return None,
        };
        let k = match axis {
            b'x' => 0,
            b'y' => 1,
            b'z' => 2,
            _ => return None,
        };
        let mut v = nalgebra::Vector3::zeros();
        v[k] = sign;
        Some(v)
    }

    /// The root part (the one whose parent is `null`).
    pub fn root(&self) -> Option<&str> {
        self.parts
            .iter()
            .find(|(_, p)| p.is_none())
            .map(|(n, _)| n.as_str())
    }

    /// Checks the part tree: exactly one root, every parent names a part,
    /// no cycles; every non-root part has exactly two curves, and curves are
    /// given only for parts that exist and are not the root.
    pub fn check_parts(&self) -> Result<()> {
        if self.needs_curves() {
            return Err(Error::invalid("no part curves ('curves'): `propose-curves` can find them"));
        }
        let roots: Vec<&String> = self
            .parts
            .iter()
            .filter(|(_, p)| p.is_none())
            .map(|(n, _)| n)
            .collect();
        if roots.len() != 1 {
            return Err(Error::invalid(format!(
                "the part tree must have exactly one root (a part with parent null), found {}",
                roots.len()
            )));
        }
        for (name, parent) in &self.parts {
            if let Some(p) = parent {
                if !self.parts.contains_key(p) {
                    return Err(Error::invalid(format!(
                        "part '{name}' has unknown parent '{p}'"
                    )));
                }
            }
            // Walk up: a tree reaches the root in fewer steps than there are parts.
            let mut cur = name;
            let mut steps = 0;
            while let Some(Some(p)) = self.parts.get(cur) {
                cur = p;
                steps += 1;
                if steps > self.parts.len() {
                    return Err(Error::invalid(format!(
                        "part '{name}' is in a parent cycle"
                    )));
                }
            }
        }
        for name in self.curves.keys() {
            match self.parts.get(name) {
                None => {
                    return Err(Error::invalid(format!(
                        "curves given for unknown part '{name}'"
                    )))
                }
                Some(None) => {
                    return Err(Error::invalid(format!(
                        "curves given for the root part '{name}'"
                    )))
                }
                Some(Some(_)) => {}
            }
        }
        for (name, parent) in &self.parts {
            if parent.is_some() {
                let n = self.curves.get(name).map_or(0, Vec::len);
                if n != 2 {
                    return Err(Error::invalid(format!(
                        "part '{name}' needs exactly 2 curves (near the parent, then down the limb), found {n}"
                    )));
                }
            }
        }
        Ok(())
    }

    /// Validates the parts and curves against the subject's template mesh and
    /// resolves every curve with [`resolve_loop`]. Returns, per non-root part,
    /// its two closed vertex loops `[near the parent, down the limb]`. Errors
    /// name the part and the loop (callers add the file).
    pub fn validate(
        &self,
        mesh: &TriMesh,
        topology: &Topology,
    ) -> Result<BTreeMap<String, [Vec<u32>; 2]>> {
        self.check_parts()?;
        let mut out = BTreeMap::new();
        for (name, loops) in &self.curves {
            let mut resolved = [Vec::new(), Vec::new()];
            for (k, lp) in loops.iter().enumerate() {
                resolved[k] = resolve_loop(mesh, topology, lp)
                    .map_err(|e| Error::invalid(format!("part '{name}', curve {}: {e}", k + 1)))?;
            }
            out.insert(name.clone(), resolved);
        }
        Ok(out)
    }
}

/// Resolves a curve given as a list of vertex indices into a closed vertex
/// loop along mesh edges.
///
/// The list is read cyclically: each entry is joined to the next, and the
/// last back to the first. Consecutive entries that share an edge are kept
/// as they are; the others are joined by the shortest edge path on `mesh`
/// (Dijkstra, Euclidean edge lengths). Repeated consecutive entries (and a
/// last entry equal to the first) are dropped first.
///
/// The precise rule for a valid ("closed") loop: every index is a vertex of
/// the mesh; the list has at least 3 distinct vertices; every join, including
/// last -> first, exists (the vertices are connected); and the resolved loop
/// is a simple cycle, i.e. visits no vertex twice (a loop that retraces its
/// own path encloses nothing). The result lists each loop vertex once, in
/// order, without repeating the first vertex at the end.
pub fn resolve_loop(mesh: &TriMesh, topology: &Topology, indices: &[u32]) -> Result<Vec<u32>> {
    let n = mesh.vertices.len();
    if let Some(&i) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(Error::invalid(format!(
            "vertex index {i} is out of range (the mesh has {n} vertices)"
        )));
    }
    let mut pts: Vec<u32> = Vec::with_capacity(indices.len());
    for &i in indices {
        if pts.last() != Some(&i) {
            pts.push(i);
        }
    }
    while pts.len() > 1 && pts.first() == pts.last() {
        pts.pop();
    }
    let mut distinct = pts.clone();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() < 3 {
        return Err(Error::invalid(format!(
            "loop has {} distinct vertices; a closed loop needs at least 3",
            distinct.len()
        )));
    }
    let mut out = Vec::new();
    for k in 0..pts.len() {
        let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
        if topology.are_adjacent(a, b) {
            out.push(a);
            continue;
        }
        let (path, _) = topology
            .shortest_path(&mesh.vertices, a, b)
            .ok_or_else(|| {
                Error::invalid(format!(
                    "loop is not closed: vertex {a} cannot be joined to vertex {b} (not connected)"
                ))
            })?;
        out.extend_from_slice(&path[..path.len() - 1]);
    }
    let mut seen = vec![false; n];
    for &v in &out {
        if std::mem::replace(&mut seen[v as usize], true) {
            return Err(Error::invalid(format!(
                "loop is not a simple closed curve: the joined loop passes vertex {v} twice"
            )));
        }
    }
    Ok(out)
}

/// A capture set on disk (layout in the module doc): the parsed `set.json`
/// and the paths of its subjects, motions and ground truth.
#[derive(Clone, Debug)]
pub struct CaptureSet {
    pub root: PathBuf,
    pub spec: SetSpec,
}

/// A subject with its template mesh and resolved curves.
#[derive(Clone, Debug)]
pub struct Subject {
    pub name: String,
    pub spec: SubjectSpec,
    /// The mesh the curves index into (see [`CaptureSet::template_path`]).
    pub template: TriMesh,
    pub topology: Topology,
    /// Per non-root part: `[loop near the parent, loop down the limb]`.
    pub curves: BTreeMap<String, [Vec<u32>; 2]>,
}

impl CaptureSet {
    /// Opens `dir/set.json` and checks that both subjects have a
    /// `subject.json`, every training and test motion a directory of frames,
    /// and every keypose `[src_frame, tgt_frame]` lies within its motions.
    pub fn open(dir: impl AsRef<Path>) -> Result<Self> {
        let root = dir.as_ref().to_path_buf();
        let spec = SetSpec::load(root.join("set.json"))?;
        let set = CaptureSet { root, spec };
        for s in [&set.spec.source, &set.spec.target] {
            let p = set.subject_json(s);
            if !p.is_file() {
                return Err(Error::file(
                    &p,
                    "missing subject description (subject.json)",
                ));
            }
        }
        for (i, t) in set.spec.train.iter().enumerate() {
            let mut n_frames = [0; 2];
            for (k, d) in [
                set.motion_dir(&set.spec.source, &t.source),
                set.motion_dir(&set.spec.target, &t.target),
            ]
            .iter()
            .enumerate()
            {
                if !d.is_dir() {
                    return Err(Error::file(d, "training motion directory is missing"));
                }
                n_frames[k] = frame_files(d)?.len();
            }
            if let Some(kp) = t
                .keyposes
                .iter()
                .find(|kp| kp[0] >= n_frames[0] || kp[1] >= n_frames[1])
            {
                return Err(Error::file(
                    set.set_json(),
                    format!(
                        "training pair {i} ({} / {}): keypose {kp:?} is outside the motions' {} / {} frames",
                        t.source, t.target, n_frames[0], n_frames[1]
                    ),
                ));
            }
        }
        for m in &set.spec.test {
            let d = set.motion_dir(&set.spec.source, m);
            if !d.is_dir() {
                return Err(Error::file(&d, "test motion directory is missing"));
            }
        }
        Ok(set)
    }

    pub fn set_json(&self) -> PathBuf {
        self.root.join("set.json")
    }
    pub fn subject_dir(&self, subject: &str) -> PathBuf {
        self.root.join(subject)
    }
    pub fn subject_json(&self, subject: &str) -> PathBuf {
        self.subject_dir(subject).join("subject.json")
    }
    /// `<set>/<subject>/<motion>`.
    pub fn motion_dir(&self, subject: &str, motion: &str) -> PathBuf {
        self.subject_dir(subject).join(motion)
    }
    /// `<set>/truth/<subject>/<motion>` (may not exist: truth is optional).
    pub fn truth_dir(&self, subject: &str, motion: &str) -> PathBuf {
        self.root.join("truth").join(subject).join(motion)
    }
    pub fn has_truth(&self, subject: &str, motion: &str) -> bool {
        self.truth_dir(subject, motion).is_dir()
    }
    /// Frame files of a motion, in frame order (see [`frame_files`]).
    pub fn frames(&self, subject: &str, motion: &str) -> Result<Vec<PathBuf>> {
        frame_files(self.motion_dir(subject, motion))
    }
    /// Motion directories of a subject (sorted names of its subdirectories).
    pub fn motions(&self, subject: &str) -> Result<Vec<String>> {
        let dir = self.subject_dir(subject);
        let mut out = Vec::new();
        for e in std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))? {
            let e = e.map_err(|e| Error::io(&dir, e))?;
            if e.path().is_dir() {
                out.push(e.file_name().to_string_lossy().into_owned());
            }
        }
        out.sort();
        Ok(out)
    }

    /// The mesh a subject's curve indices refer to: the optional
    /// `"template"` field of `subject.json` (a path relative to the subject
    /// directory), else the first frame of the subject's first training
    /// motion (all frames of a subject share one topology).
    pub fn template_path(&self, subject: &str, spec: &SubjectSpec) -> Result<PathBuf> {
        if let Some(t) = spec.extra.get("template") {
            let t = t.as_str().ok_or_else(|| {
                Error::file(
                    self.subject_json(subject),
                    "'template' must be a path string",
                )
            })?;
            return Ok(self.subject_dir(subject).join(t));
        }
        let motion = self
            .spec
            .train
            .iter()
            .find_map(|t| {
                if subject == self.spec.source {
                    Some(&t.source)
                } else if subject == self.spec.target {
                    Some(&t.target)
                } else {
                    None
                }
            })
            .ok_or_else(|| {
                Error::file(
                    self.set_json(),
                    format!("subject '{subject}' is neither source nor target"),
                )
            })?;
        Ok(self.frames(subject, motion)?.swap_remove(0))
    }

    /// Loads a subject: its `subject.json`, its template mesh, and its curves
    /// validated and resolved against the template. Errors name
    /// `subject.json` (or the mesh file).
    pub fn subject(&self, name: &str) -> Result<Subject> {
        let json = self.subject_json(name);
        let spec = SubjectSpec::load(&json)?;
        let template = crate::io::read_mesh(self.template_path(name, &spec)?)?;
        let topology = Topology::new(template.vertices.len(), &template.faces);
        let curves = spec
            .validate(&template, &topology)
            .map_err(|e| Error::file(&json, e.to_string()))?;
        Ok(Subject {
            name: name.to_string(),
            spec,
            template,
            topology,
            curves,
        })
    }
}
