//! Makes a capture set of a tracked capture's size from a benchmark set, for running `make
//! transfer` at that size (`scripts/bench-lab-size`, docs/studies/44-lab-size-run.md).
//!
//! - Meshes: each subject named by `--vertices SUBJECT=N` is midpoint-subdivided (every triangle
//!   into four, as `synth` subdivides its bodies) while the next level stays within N vertices,
//!   then its first faces are split at their centroid (one new vertex, three triangles) until it
//!   has exactly N. Both steps are linear in the vertex positions, so every frame of a subject
//!   keeps one topology; the original vertices keep their indices, so the part curves stay valid
//!   (a loop's joins are shortest edge paths).
//! - Length: every training pair is repeated in turn, source and target motion alike, until the
//!   source's training motions hold `--training-frames` frames together; its key-poses repeat
//!   with each cycle. A repeated frame is a symbolic link to the one stored copy of that frame.
//! - What a lab has: `set.json` keeps source, target, training pairs with key-poses, test
//!   motions; `subject.json` keeps fps, units, up, part tree and curves. The synthetic extras
//!   (true correspondences, contacts, clip times) are left out; `truth/` of the test motions is
//!   subdivided alongside.
//!
//! e.g.: lab_size_set --set out/holdout/set --vertices C=100000 --vertices D=40000 \
//!           --training-frames 5000 --out ~/.cache/surfcap/lab-size/set

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::io::{read_mesh, write_ply};
use mesh_core::mesh::TriMesh;
use nalgebra::Vector3;
use rayon::prelude::*;
use serde_json::{json, Value};

#[derive(Parser)]
struct Args {
    /// The benchmark capture set to enlarge
    #[arg(long)]
    set: PathBuf,
    /// Output capture set (a new folder)
    #[arg(short, long)]
    out: PathBuf,
    /// A subject's vertex count, as SUBJECT=N (repeat; a subject not named keeps its meshes)
    #[arg(long, value_parser = parse_vertices)]
    vertices: Vec<(String, usize)>,
    /// Frames of the source subject's training motions together, reached by repeating them
    #[arg(long)]
    training_frames: usize,
}

fn parse_vertices(s: &str) -> Result<(String, usize), String> {
    let (name, n) = s.split_once('=').ok_or("expected SUBJECT=N")?;
    Ok((name.to_string(), n.parse().map_err(|e| format!("{n}: {e}"))?))
}

/// How a subject's meshes are refined: midpoint levels, each with the faces it subdivides, then
/// centroid splits of the first faces of the last level.
struct Refinement {
    level_faces: Vec<Vec<[u32; 3]>>,
    /// The faces split at their centroid (indices into the last level's vertices).
    centroid_faces: Vec<[u32; 3]>,
    /// The refined mesh's faces.
    faces: Vec<[u32; 3]>,
}

impl Refinement {
    fn plan(template: &TriMesh, vertices: Option<usize>) -> anyhow::Result<Self> {
        let mut level_faces = Vec::new();
        let mut faces = template.faces.clone();
        let mut v = template.vertices.clone();
        let Some(n) = vertices else {
            return Ok(Refinement { level_faces, centroid_faces: Vec::new(), faces });
        };
        if n < v.len() {
            bail!("{n} vertices is fewer than the template's {}", v.len());
        }
        loop {
            let (nv, nf) = synth::subject::subdivide(&v, &faces);
            if nv.len() > n {
                break;
            }
            level_faces.push(std::mem::replace(&mut faces, nf));
            v = nv;
        }
        let splits = n - v.len();
        if splits > faces.len() {
            bail!("{n} vertices needs {splits} centroid splits, more than the {} faces", faces.len());
        }
        let centroid_faces = faces[..splits].to_vec();
        let mut refined = Vec::with_capacity(faces.len() + 2 * splits);
        for (k, &[a, b, c]) in centroid_faces.iter().enumerate() {
            let m = (v.len() + k) as u32;
            refined.extend([[a, b, m], [b, c, m], [c, a, m]]);
        }
        refined.extend_from_slice(&faces[splits..]);
        Ok(Refinement { level_faces, centroid_faces, faces: refined })
    }

    fn apply(&self, vertices: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut v = vertices.to_vec();
        for f in &self.level_faces {
            v = synth::subject::subdivide(&v, f).0;
        }
        let centroids: Vec<Vector3<f64>> =
            self.centroid_faces.iter().map(|&[a, b, c]| (v[a as usize] + v[b as usize] + v[c as usize]) / 3.0).collect();
        v.extend(centroids);
        v
    }
}

/// Writes the refined frames of `dir` into `out` (a new folder); returns the frame count.
fn refine_motion(dir: &Path, out: &Path, r: &Refinement) -> anyhow::Result<usize> {
    let files = mesh_core::sequence::frame_files(dir)?;
    std::fs::create_dir_all(out)?;
    files.par_iter().enumerate().try_for_each(|(i, f)| -> anyhow::Result<()> {
        let mesh = read_mesh(f)?;
        write_ply(out.join(format!("{i:06}.ply")), &TriMesh::new(r.apply(&mesh.vertices), r.faces.clone()))?;
        Ok(())
    })?;
    Ok(files.len())
}

/// A motion folder of `cycles` repeats of `store`'s `n` frames, as symbolic links.
fn link_cycles(store: &Path, n: usize, cycles: usize, out: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(out)?;
    let store = std::fs::canonicalize(store)?;
    for i in 0..n * cycles {
        std::os::unix::fs::symlink(store.join(format!("{:06}.ply", i % n)), out.join(format!("{i:06}.ply")))?;
    }
    Ok(())
}

fn read_json(path: &Path) -> anyhow::Result<Value> {
    serde_json::from_slice(&std::fs::read(path).with_context(|| path.display().to_string())?)
        .with_context(|| path.display().to_string())
}

fn main() -> anyhow::Result<()> {
    let a = Args::parse();
    if a.out.exists() {
        bail!("{}: already exists", a.out.display());
    }
    let set = read_json(&a.set.join("set.json"))?;
    let name = |k: &str| set[k].as_str().map(str::to_string).with_context(|| format!("set.json: no {k}"));
    let (source, target) = (name("source")?, name("target")?);
    let sizes: BTreeMap<String, usize> = a.vertices.iter().cloned().collect();
    let train = set["train"].as_array().context("set.json: no train")?;
    let first_motion = |side: &str| train[0][side].as_str().map(str::to_string).context("set.json: train[0]");

    let mut refinements = BTreeMap::new();
    for (subject, side) in [(&source, "source"), (&target, "target")] {
        let template = read_mesh(mesh_core::sequence::frame_files(a.set.join(subject).join(first_motion(side)?))?[0].clone())?;
        let r = Refinement::plan(&template, sizes.get(subject).copied()).with_context(|| subject.clone())?;
        eprintln!(
            "lab_size_set: {subject}: {} -> {} vertices ({} midpoint levels, {} centroid splits)",
            template.vertices.len(),
            r.apply(&template.vertices).len(),
            r.level_faces.len(),
            r.centroid_faces.len()
        );
        let info = read_json(&a.set.join(subject).join("subject.json"))?;
        let mut kept = serde_json::Map::new();
        for k in ["fps", "units", "up", "parts", "curves"] {
            if let Some(v) = info.get(k) {
                kept.insert(k.into(), v.clone());
            }
        }
        std::fs::create_dir_all(a.out.join(subject))?;
        std::fs::write(a.out.join(subject).join("subject.json"), serde_json::to_vec_pretty(&Value::Object(kept))?)?;
        refinements.insert(subject.clone(), r);
    }

    let store = a.out.join(".frames");
    let mut lengths = Vec::new();
    for pair in train {
        let mut n = [0; 2];
        for (k, (subject, side)) in [(&source, "source"), (&target, "target")].into_iter().enumerate() {
            let m = pair[side].as_str().context("set.json: a training pair without motion names")?;
            n[k] = refine_motion(&a.set.join(subject).join(m), &store.join(subject).join(m), &refinements[subject])?;
        }
        lengths.push(n);
    }
    let source_frames: usize = lengths.iter().map(|n| n[0]).sum();
    let cycles = a.training_frames.div_ceil(source_frames).max(1);
    let mut new_train = Vec::new();
    for (pair, n) in train.iter().zip(&lengths) {
        for (k, (subject, side)) in [(&source, "source"), (&target, "target")].into_iter().enumerate() {
            let m = pair[side].as_str().unwrap_or_default();
            link_cycles(&store.join(subject).join(m), n[k], cycles, &a.out.join(subject).join(m))?;
        }
        let mut keyposes = Vec::new();
        for c in 0..cycles {
            for kp in pair["keyposes"].as_array().context("set.json: a training pair without keyposes")? {
                let (s, t) = (kp[0].as_u64().unwrap_or(0) as usize, kp[1].as_u64().unwrap_or(0) as usize);
                keyposes.push(json!([s + c * n[0], t + c * n[1]]));
            }
        }
        new_train.push(json!({"source": pair["source"], "target": pair["target"], "keyposes": keyposes}));
    }

    let mut tests = Vec::new();
    for (key, subject, other) in [("test", &source, &target), ("target_test", &target, &source)] {
        for m in set[key].as_array().into_iter().flatten().filter_map(Value::as_str) {
            refine_motion(&a.set.join(subject).join(m), &a.out.join(subject).join(m), &refinements[subject])?;
            let truth = a.set.join("truth").join(other).join(m);
            if truth.is_dir() {
                refine_motion(&truth, &a.out.join("truth").join(other).join(m), &refinements[other])?;
            }
            tests.push((key, m.to_string()));
        }
    }
    let mut out_set = json!({"source": source, "target": target, "train": new_train});
    for key in ["test", "target_test"] {
        let ms: Vec<&String> = tests.iter().filter(|(k, _)| *k == key).map(|(_, m)| m).collect();
        if !ms.is_empty() {
            out_set[key] = json!(ms);
        }
    }
    std::fs::write(a.out.join("set.json"), serde_json::to_vec_pretty(&out_set)?)?;
    eprintln!(
        "lab_size_set: {} training pairs x {cycles} cycles: source {} frames, target {} frames",
        train.len(),
        source_frames * cycles,
        lengths.iter().map(|n| n[1]).sum::<usize>() * cycles
    );
    Ok(())
}
