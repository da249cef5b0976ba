//! The capture-set format (documented in docs/FORMATS.md):
//!
//! ```text
//! <set>/set.json                       SetSpec
//! <set>/<subject>/subject.json         SubjectSpec
//! <set>/<subject>/<motion>/000000.ply  one file per frame (PLY or OBJ)
//! <set>/truth/<subject>/<motion>/...   optional ground truth
//! ```
//!
//! These structs are the serde form of the JSON files; validation against a
//! template mesh (curve indices in range, loops closed) lives next to them.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

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

/// `<set>/<subject>/subject.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SubjectSpec {
    pub fps: f64,
    #[serde(default = "default_units")]
    pub units: String,
    #[serde(default = "default_up")]
    pub up: String,
    /// Part tree: part name -> parent part name (`null` for the root).
    pub parts: BTreeMap<String, Option<String>>,
    /// Per non-root part: its curves as vertex loops, first the loop near the
    /// parent, then the loop further down the limb. The band between them is
    /// the part's overlap with its parent.
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
