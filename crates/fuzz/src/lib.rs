//! An in-process mutation fuzzer on stable Rust over every surfcap reader.
//!
//! Targets ([`Target`]): PLY and OBJ meshes, PC2 point caches, Alembic (Ogawa) mesh caches,
//! Quake 3 MD3
//! models (welded as the `characters` stage welds them) and their
//! `animation.cfg`, the capture
//! set's `set.json` and `subject.json` (with the subject's curves resolved on
//! a template, as `segment` does), and artifacts: every kind's decoder and
//! validator (segmentation, pca-model, aligned-motion, correspondences,
//! gpr-model, variation-group, variation-model, variation-variants, and the per-part pieces of
//! pca-model, gpr-model and variation-model with their join), followed by the
//! consumers that index with what validation let through.
//!
//! Each round takes a seed input ([`seed_corpus`], plus any files given with
//! `--corpus`) and applies 1-4 mutations ([`mutate`]): bit flips, interesting
//! bytes, truncation, insertion, splices from other inputs, token swaps and
//! replacements in text, and for artifacts rewrites of length fields and
//! varints with the checksum recomputed (so mutated payloads reach the
//! decoder instead of stopping at the checksum). A panic is caught
//! (`catch_unwind`), counted and its input kept; an input slower than
//! [`HANG_SECONDS`] counts as a hang if it is as slow again in thread CPU time (a worker
//! starved by a loaded machine is not a hang).

pub mod stage;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use mesh_core::artifact::{Artifact, Header, MAGIC};
use mesh_core::capture_set::{SetSpec, SubjectSpec};
use mesh_core::sequence::MeshSequence;
use mesh_core::shapes::capsule_body;
use mesh_core::topology::Topology;
use mesh_core::TriMesh;
use nalgebra::Vector3;
use rayon::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sha2::{Digest, Sha256};

/// An input slower than this counts as a hang.
pub const HANG_SECONDS: f64 = 2.0;

/// Which reader an input goes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Target {
    Ply,
    Obj,
    Pc2,
    Alembic,
    Md3,
    AnimationCfg,
    SetJson,
    SubjectJson,
    Artifact,
}

impl Target {
    pub fn name(self) -> &'static str {
        match self {
            Target::Ply => "ply",
            Target::Obj => "obj",
            Target::Pc2 => "pc2",
            Target::Alembic => "alembic",
            Target::Md3 => "md3",
            Target::AnimationCfg => "animation-cfg",
            Target::SetJson => "set-json",
            Target::SubjectJson => "subject-json",
            Target::Artifact => "artifact",
        }
    }

    /// The target of a corpus file, from its name.
    pub fn of_path(path: &Path) -> Option<Target> {
        let name = path.file_name()?.to_str()?.to_ascii_lowercase();
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        Some(match ext.as_str() {
            "ply" => Target::Ply,
            "obj" => Target::Obj,
            "pc2" => Target::Pc2,
            "abc" => Target::Alembic,
            "md3" => Target::Md3,
            "cfg" if name == "animation.cfg" => Target::AnimationCfg,
            "json" if name == "set.json" => Target::SetJson,
            "json" if name == "subject.json" => Target::SubjectJson,
            _ => {
                let mut magic = [0u8; 8];
                let mut f = std::fs::File::open(path).ok()?;
                std::io::Read::read_exact(&mut f, &mut magic).ok()?;
                if magic != MAGIC {
                    return None;
                }
                Target::Artifact
            }
        })
    }
}

/// The template subject.json curves are resolved on, and its segmentation.
struct Fixture {
    template: TriMesh,
    topology: Topology,
}

fn fixture() -> &'static Fixture {
    static F: std::sync::OnceLock<Fixture> = std::sync::OnceLock::new();
    F.get_or_init(|| {
        let (template, _) = capsule_body(20, 10, 0.15, 1.6);
        let topology = Topology::new(template.n_vertices(), &template.faces);
        Fixture { template, topology }
    })
}

/// Runs every reader of `target` on `bytes`, and the consumers of what it accepts.
pub fn exercise(target: Target, bytes: &[u8]) {
    match target {
        Target::Ply => {
            let _ = mesh_core::io::ply::parse_ply(bytes);
            let _ = mesh_core::io::ply::parse_ply_generic(bytes);
        }
        Target::Obj => {
            let _ = mesh_core::io::obj::parse_obj(bytes);
        }
        Target::Pc2 => {
            let _ = mesh_core::io::pc2::parse_pc2(bytes);
        }
        Target::Alembic => {
            if let Ok(m) = mesh_core::io::alembic::parse_alembic(bytes, None) {
                let _ = m.sequence.topology();
            }
        }
        Target::Md3 => {
            if let Ok(model) = export::md3::parse_md3(bytes) {
                let _ = characters::character::weld(&model);
            }
        }
        Target::AnimationCfg => {
            if let Ok(cfg) = characters::animation_cfg::parse_animation_cfg(bytes) {
                for anim in cfg.animations.values() {
                    let _ = anim.frame_at(3 * anim.count + 1);
                }
            }
        }
        Target::SetJson => {
            let _ = SetSpec::parse(bytes);
        }
        Target::SubjectJson => {
            if let Ok(s) = SubjectSpec::parse(bytes) {
                let f = fixture();
                if s.validate(&f.template, &f.topology).is_ok() {
                    let _ = mesh_core::segmentation::segment(&f.template, &s);
                }
            }
        }
        Target::Artifact => exercise_artifact(bytes),
    }
}

fn exercise_artifact(bytes: &[u8]) {
    use capture::part_pca::PcaModel;
    use mesh_core::part_merge::Partitioned;
    use mesh_core::segmentation::Segmentation;
    use transfer::gpr_model::GprModel;
    use variation::train::VariationModel;
    // Every decoder verifies the checksum over the whole file before it compares the kind, so a
    // decoder of another kind only repeats that hash: the generic decode covers the container
    // (lengths, checksum, header) of every input, and only the decoders of the kind the file
    // names run after it.
    let _ = mesh_core::artifact::decode_artifact::<serde_json::Value>(bytes, "any", 1);
    let Some(kind) = stored_kind(bytes) else { return };
    match kind {
        k if k == Segmentation::KIND => {
            if let Ok((_, s)) = Segmentation::decode(bytes) {
                let _ = s.tree_order();
                let _ = s.vertex_labels();
            }
        }
        k if k == PcaModel::KIND => {
            if let Ok((_, m)) = <PcaModel as Artifact>::decode(bytes) {
                let _ = m.template_vertices();
                let _ = capture::assemble::plan(&m);
            }
        }
        k if k == capture::align::AlignedMotion::KIND => {
            if let Ok((_, m)) = capture::align::AlignedMotion::decode(bytes) {
                let _ = m.frames.len();
            }
        }
        k if k == transfer::densify::Correspondences::KIND => {
            let _ = transfer::densify::Correspondences::decode(bytes);
        }
        k if k == GprModel::KIND => {
            let _ = GprModel::decode(bytes);
        }
        k if k == variation::group::Group::KIND => {
            let _ = variation::group::Group::decode(bytes);
        }
        k if k == VariationModel::KIND => {
            let _ = VariationModel::decode(bytes);
        }
        k if k == variation::variant_cache::CachedVariants::KIND => {
            let _ = variation::variant_cache::CachedVariants::decode(bytes);
        }
        k if k == PcaModel::PIECE_KIND => exercise_piece::<PcaModel>(bytes),
        k if k == GprModel::PIECE_KIND => exercise_piece::<GprModel>(bytes),
        k if k == VariationModel::PIECE_KIND => exercise_piece::<VariationModel>(bytes),
        // Another kind: one decoder still runs, for its kind-mismatch path.
        _ => {
            let _ = Segmentation::decode(bytes);
        }
    }
}

/// The kind an artifact's bytes name, read without any check (the decoders do those).
fn stored_kind(b: &[u8]) -> Option<&str> {
    if b.len() < 16 || b[..8] != MAGIC {
        return None;
    }
    let k = u32::from_le_bytes(b[12..16].try_into().ok()?) as usize;
    std::str::from_utf8(b.get(16..16usize.checked_add(k)?)?).ok()
}

/// A piece of a per-part model, and the join `merge-parts` makes of its body as a one-part model.
fn exercise_piece<M: mesh_core::part_merge::Partitioned>(bytes: &[u8]) {
    use mesh_core::part_merge::Piece;
    if let Ok((_, piece)) = Piece::<M>::decode(bytes) {
        let _ = M::join(std::slice::from_ref(&piece.part), vec![piece.body]);
    }
}

/// The built-in seed corpus: one or more valid inputs per target, made the way
/// the stages make them (a small capsule body, its aligned motion, part
/// PCA and segmentation).
pub fn seed_corpus() -> Vec<(Target, Vec<u8>)> {
    use gp::pca::Components;
    use mesh_core::io::ply::{encode_ply, PlyEncoding, PlyOptions, PlyPrecision};
    let (mesh, l) = capsule_body(20, 10, 0.15, 1.6);
    let mut out = Vec::new();
    for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian] {
        for precision in [PlyPrecision::Float, PlyPrecision::Double] {
            let mut b = Vec::new();
            encode_ply(&mut b, &mesh, PlyOptions { encoding, precision }).unwrap();
            out.push((Target::Ply, b));
        }
    }
    let mut b = Vec::new();
    mesh_core::io::obj::encode_obj(&mut b, &mesh).unwrap();
    out.push((Target::Obj, b));
    out.push((Target::Obj, b"# caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1/1/1 2//2 3\nf -1 -2 -3 -4\nf\n".to_vec()));
    let frames: Vec<Vec<Vector3<f64>>> = (0..6)
        .map(|k| {
            mesh.vertices
                .iter()
                .map(|v| Vector3::new(v.x + 0.02 * k as f64 * v.y, v.y, v.z))
                .collect()
        })
        .collect();
    let mut b = Vec::new();
    mesh_core::io::pc2::encode_pc2(&mut b, &frames[..3]).unwrap();
    out.push((Target::Pc2, b));
    // Blender 5.0.1's Alembic exports: a 3-frame cube, a rigid motion (fixtures/alembic/*.py).
    out.push((Target::Alembic, include_bytes!("../../../fixtures/alembic/cube.abc").to_vec()));
    out.push((Target::Alembic, include_bytes!("../../../fixtures/alembic/rigid.abc").to_vec()));
    out.push((Target::Md3, md3_seed(&mesh, &frames[..2])));
    out.push((Target::AnimationCfg, ANIMATION_CFG_SEED.to_vec()));
    out.push((Target::SetJson, br#"{"source": "A", "target": "B", "train": [{"source": "walk", "target": "walk", "keyposes": [[0, 0], [12, 25]]}], "test": ["punch"]}"#.to_vec()));
    let near = l.ring(l.body_ring(8));
    let far = l.ring(l.body_ring(12));
    let subject = serde_json::json!({"fps": 25, "units": "m", "up": "+y",
        "parts": {"torso": null, "limb": "torso"}, "curves": {"limb": [near, far]}});
    out.push((Target::SubjectJson, subject.to_string().into_bytes()));
    let spec = SubjectSpec::parse(subject.to_string().as_bytes()).unwrap();
    let seg = mesh_core::segmentation::segment(&mesh, &spec).unwrap();
    let aligned = capture::align::align_motion(&mesh, &MeshSequence::new(mesh.faces.clone(), frames)).unwrap();
    let (pca, _) = capture::part_pca::fit(
        &mesh.vertices,
        &seg,
        &[&aligned],
        Components::Count(3),
        capture::part_pca::PartAlignment::Body,
    )
    .unwrap();
    let header = Header::new("fuzz", "0").with_seed(0);
    out.push((Target::Artifact, artifact_bytes(&seg, &header)));
    out.push((Target::Artifact, artifact_bytes(&aligned, &header)));
    out.push((Target::Artifact, artifact_bytes(&pca, &header)));
    let names: Vec<String> = pca.parts.iter().map(|p| p.name.clone()).collect();
    let piece = mesh_core::part_merge::Piece::<capture::part_pca::PcaModel> {
        parts: names.clone(),
        part: names[0].clone(),
        body: capture::part_pca::PcaModel { parts: pca.parts[..1].to_vec(), ..pca.clone() },
    };
    out.push((Target::Artifact, artifact_bytes(&piece, &header)));
    let corr = transfer::densify::Correspondences {
        source_motion: "walk".into(),
        target_motion: "walk".into(),
        keyposes: vec![[0, 0], [5, 5]],
        pairs: (0..6).map(|i| [i, i]).collect(),
    };
    out.push((Target::Artifact, artifact_bytes(&corr, &header)));
    out.push((Target::Artifact, artifact_bytes(&variants_seed(), &header)));
    out
}

/// A blend query's cached variants (`variation::variant_cache`): two variations of two parts.
fn variants_seed() -> variation::variant_cache::CachedVariants {
    use variation::sample::{HmcStart, Sampler};
    use variation::variant_cache::{CachedVariants, VariantKey};
    let key = VariantKey {
        model_sha256: "0".repeat(64),
        build: "1 bytes, modified 0.000000000".into(),
        sequence: 0,
        name: "walk".into(),
        frames: 3,
        sampler: Sampler::Hmc,
        variance_scale: 0.3,
        n: 2,
        seed: 0,
        hmc_start: HmcStart::Mean,
        burn_in: 200,
        thin: 10,
        target_accept: 0.7,
        leapfrog_steps: 20,
        initial_step: 0.01,
    };
    let x = nalgebra::DMatrix::from_fn(3, 2, |t, c| t as f64 - 0.5 * c as f64);
    CachedVariants { key, chains: Vec::new(), variations: vec![vec![x.clone(), x]; 2] }
}

/// A two-frame MD3 of `mesh` in two surfaces, with a tag (positions in
/// decimetres, so the body fits MD3's 16-bit coordinates with room to spare).
fn md3_seed(mesh: &TriMesh, frames: &[Vec<Vector3<f64>>]) -> Vec<u8> {
    use export::md3::{Md3, Md3Frame, Surface, Tag};
    let half = mesh.faces.len() / 2;
    let surface = |name: &str, faces: &[[u32; 3]]| Surface {
        name: name.into(),
        triangles: faces.to_vec(),
        frames: frames.iter().map(|f| f.iter().map(|p| p * 10.0).collect()).collect(),
    };
    let frame = Md3Frame { name: "f".into(), min: Vector3::zeros(), max: Vector3::zeros(), origin: Vector3::zeros(), radius: 1.0 };
    let tag = Tag { name: "tag_torso".into(), origin: Vector3::new(0.0, 0.0, 8.0), axis: nalgebra::Matrix3::identity() };
    let model = Md3 {
        name: "seed".into(),
        frames: vec![frame; frames.len()],
        tags: vec![vec![tag]; frames.len()],
        surfaces: vec![surface("a", &mesh.faces[..half]), surface("b", &mesh.faces[half..])],
    };
    export::md3::encode_md3(&model).expect("the seed fits MD3")
}

/// A player's `animation.cfg` (the 25 animations, keywords and comments).
const ANIMATION_CFG_SEED: &[u8] = b"// animation config file\nsex m\nheadoffset 0 0 0\nfootsteps boot\n\n\
0 30 0 25 // BOTH_DEATH1\n29 1 0 25\n30 30 0 25\n59 1 0 25\n60 30 0 25\n89 1 0 25\n\
90 40 0 13 // TORSO_GESTURE\n130 6 0 15\n136 6 0 15\n142 5 0 20\n147 4 0 20\n151 1 0 15\n152 1 0 15\n\
153 8 8 20 // LEGS_WALKCR\n161 12 12 20\n173 9 9 15\n182 10 10 18\n185 10 10 15\n202 8 0 15\n\
211 8 0 20\n219 9 0 15\n228 -6 0 20\n234 10 4 10\n244 10 10 0\n254 7 7 18 // LEGS_TURN\n";

fn artifact_bytes<T: Artifact>(value: &T, header: &Header) -> Vec<u8> {
    mesh_core::artifact::encode_artifact(T::KIND, T::VERSION, header, value).unwrap()
}

/// A numbered frame file other than `000000.*`.
fn is_later_frame(p: &Path) -> bool {
    p.file_stem()
        .and_then(|s| s.to_str())
        .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()) && s.bytes().any(|b| b != b'0'))
}

/// Reads every file under `dir` (recursively) that has a target, but only the
/// first frame of each motion folder.
pub fn load_corpus(dir: &Path) -> Vec<(Target, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        let mut paths: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
        paths.sort();
        for p in paths {
            if p.is_dir() {
                stack.push(p);
            } else if is_later_frame(&p) {
                // One frame per motion folder is enough: the others share its layout.
                continue;
            } else if let Some(t) = Target::of_path(&p) {
                if let Ok(b) = std::fs::read(&p) {
                    if b.len() <= 4 << 20 {
                        out.push((t, b));
                    }
                }
            }
        }
    }
    out
}

const INTERESTING_BYTES: [u8; 10] = [0, 1, 0x7f, 0x80, 0xff, 251, 252, 253, b'\n', b' '];
const TOKENS: [&str; 16] = [
    "0", "-1", "1", "3", "255", "4294967295", "-2147483648", "18446744073709551615", "nan", "inf",
    "1e999", "3.1+e2", "null", "[]", "{}", "\u{1b}[2J",
];

/// The offsets of the artifact sections' length fields: kind, header, payload.
fn artifact_length_fields(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    if b.len() < 16 || b[..8] != MAGIC {
        return out;
    }
    out.push((12, 4));
    let k = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    let h_at = 16 + k + 4;
    if b.len() < h_at + 8 {
        return out;
    }
    out.push((h_at, 8));
    let h = u64::from_le_bytes(b[h_at..h_at + 8].try_into().unwrap()) as usize;
    let p_at = h_at + 8 + h;
    if b.len() >= p_at + 8 {
        out.push((p_at, 8));
    }
    out
}

/// Recomputes an artifact's trailing SHA-256 over everything before it.
pub fn fix_checksum(b: &mut [u8]) {
    if b.len() >= 8 + 32 && b[..8] == MAGIC {
        let n = b.len() - 32;
        let d = Sha256::digest(&b[..n]);
        b[n..].copy_from_slice(&d);
    }
}

/// One mutation of `input` (see the module documentation).
pub fn mutate(rng: &mut ChaCha8Rng, input: &[u8], target: Target, corpus: &[(Target, Vec<u8>)]) -> Vec<u8> {
    let mut b = input.to_vec();
    let rounds = rng.random_range(1..=4);
    for _ in 0..rounds {
        let len = b.len();
        match rng.random_range(0..10) {
            0 if len > 0 => {
                let i = rng.random_range(0..len);
                b[i] ^= 1 << rng.random_range(0..8);
            }
            1 if len > 0 => {
                let i = rng.random_range(0..len);
                b[i] = INTERESTING_BYTES[rng.random_range(0..INTERESTING_BYTES.len())];
            }
            2 if len > 0 => {
                b.truncate(rng.random_range(0..len));
            }
            3 => {
                let i = rng.random_range(0..=len);
                let n = rng.random_range(1..16);
                let ins: Vec<u8> = (0..n).map(|_| rng.random()).collect();
                b.splice(i..i, ins);
            }
            4 if !corpus.is_empty() => {
                // Splice a chunk of another input (of any target) in.
                let other = &corpus[rng.random_range(0..corpus.len())].1;
                if !other.is_empty() {
                    let s = rng.random_range(0..other.len());
                    let e = (s + rng.random_range(1..256)).min(other.len());
                    let i = rng.random_range(0..=len);
                    let j = (i + rng.random_range(0..64)).min(len);
                    b.splice(i..j, other[s..e].iter().copied());
                }
            }
            5 if len > 8 => {
                // Rewrite an integer somewhere: a length field or a varint.
                let fields = artifact_length_fields(&b);
                let (at, width) = if !fields.is_empty() && rng.random_bool(0.5) {
                    fields[rng.random_range(0..fields.len())]
                } else {
                    (rng.random_range(0..len - 8), [1, 2, 4, 8][rng.random_range(0..4)])
                };
                let v: u64 = match rng.random_range(0..4) {
                    0 => rng.random_range(0..16),
                    1 => 1 << rng.random_range(0..64),
                    2 => u64::MAX >> rng.random_range(0..64),
                    _ => rng.random(),
                };
                if at + width <= b.len() {
                    b[at..at + width].copy_from_slice(&v.to_le_bytes()[..width]);
                }
            }
            6 if len > 9 => {
                // A bincode varint length marker followed by a large value.
                let at = rng.random_range(0..len - 9);
                b[at] = [251u8, 252, 253][rng.random_range(0..3)];
                let v: u64 = 1 << rng.random_range(8..63);
                b[at + 1..at + 9].copy_from_slice(&v.to_le_bytes());
            }
            7 | 8 if !matches!(target, Target::Artifact | Target::Pc2 | Target::Alembic | Target::Md3) => {
                // Token swap or replacement in text.
                // The tokens at two random positions (a scan of the whole text per mutation
                // cost more than the parse on large files).
                let spans: Vec<(usize, usize)> =
                    (0..2).filter_map(|_| token_at(&b, rng.random_range(0..len.max(1)))).collect();
                if spans.len() == 2 {
                    let (s1, e1) = spans[0];
                    if rng.random_bool(0.5) {
                        let (s2, e2) = spans[1];
                        let (a, c) = if s1 <= s2 { ((s1, e1), (s2, e2)) } else { ((s2, e2), (s1, e1)) };
                        if a.1 <= c.0 {
                            let (ta, tc) = (b[a.0..a.1].to_vec(), b[c.0..c.1].to_vec());
                            b.splice(c.0..c.1, ta);
                            b.splice(a.0..a.1, tc);
                        }
                    } else {
                        let t = TOKENS[rng.random_range(0..TOKENS.len())];
                        b.splice(s1..e1, t.bytes());
                    }
                }
            }
            _ if len > 1 => {
                // Duplicate or delete a range.
                let s = rng.random_range(0..len);
                let e = (s + rng.random_range(1..64)).min(len);
                if rng.random_bool(0.5) {
                    let chunk = b[s..e].to_vec();
                    b.splice(e..e, chunk);
                } else {
                    b.drain(s..e);
                }
            }
            _ => {}
        }
        if b.len() > 8 << 20 {
            b.truncate(8 << 20);
        }
    }
    if target == Target::Artifact && rng.random_bool(0.85) {
        fix_checksum(&mut b);
    }
    b
}

fn is_token_separator(c: u8) -> bool {
    c.is_ascii_whitespace() || b",:[]{}\"/".contains(&c)
}

/// The whitespace- or punctuation-separated token at or after byte `at` (within 64 bytes), as
/// a byte range.
fn token_at(b: &[u8], at: usize) -> Option<(usize, usize)> {
    let start = (at..b.len().min(at + 64)).find(|&i| !is_token_separator(b[i]))?;
    let start = (0..start).rev().take_while(|&i| !is_token_separator(b[i])).last().unwrap_or(start);
    let end = (start..b.len()).find(|&i| is_token_separator(b[i])).unwrap_or(b.len());
    Some((start, end))
}

/// What a run found.
#[derive(Clone, Debug, Default)]
pub struct Report {
    pub inputs: u64,
    pub per_target: std::collections::BTreeMap<&'static str, u64>,
    pub panics: u64,
    pub hangs: u64,
    pub slowest_seconds: f64,
    /// Peak resident memory of the process (VmHWM), kB; 0 where unknown.
    pub peak_rss_kb: u64,
    /// Where the inputs that panicked or hung were written.
    pub kept: Vec<PathBuf>,
    pub seconds: f64,
}

/// Peak resident set size of this process, kB (Linux; 0 elsewhere).
pub fn peak_rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

/// CPU time of the calling thread in seconds, from `/proc/thread-self/schedstat` (Linux; NaN
/// elsewhere).
fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse::<f64>().ok()))
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

/// Whether an input whose wall time passed [`HANG_SECONDS`] really takes that long: it runs
/// again and its thread CPU time is what counts (its wall time where that is unknown), so an
/// input that only waited for a core on a loaded machine is not a hang.
fn still_slow(target: Target, bytes: &[u8]) -> bool {
    let (cpu0, t0) = (thread_cpu_seconds(), Instant::now());
    let _ = catch_unwind(AssertUnwindSafe(|| exercise(target, bytes)));
    let cpu = thread_cpu_seconds() - cpu0;
    let spent = if cpu.is_finite() { cpu } else { t0.elapsed().as_secs_f64() };
    spent > HANG_SECONDS
}

/// Fuzzes until `inputs` inputs or `duration` have been spent, whichever comes first, on the
/// rayon pool's threads, each worker with its own random stream (worker 0: `seed`) and share of
/// `inputs`; keeps panicking / hanging inputs in `keep` (if given). The reports are summed.
pub fn fuzz(
    seed: u64,
    corpus: &[(Target, Vec<u8>)],
    inputs: u64,
    duration: Duration,
    keep: Option<&Path>,
) -> Report {
    let workers = rayon::current_num_threads().max(1) as u64;
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let reports: Vec<Report> = (0..workers)
        .into_par_iter()
        .map(|w| {
            let share = inputs / workers + u64::from(w < inputs % workers);
            let stream = seed.wrapping_add(w.wrapping_mul(0x9E37_79B9_7F4A_7C15));
            fuzz_worker(if w == 0 { seed } else { stream }, corpus, share, duration, keep)
        })
        .collect();
    std::panic::set_hook(previous);
    let mut total = Report::default();
    for r in reports {
        total.inputs += r.inputs;
        for (t, n) in r.per_target {
            *total.per_target.entry(t).or_default() += n;
        }
        total.panics += r.panics;
        total.hangs += r.hangs;
        total.slowest_seconds = total.slowest_seconds.max(r.slowest_seconds);
        total.kept.extend(r.kept);
        total.seconds = total.seconds.max(r.seconds);
    }
    total.peak_rss_kb = peak_rss_kb();
    total
}

/// One fuzzing loop; the caller silences the panic hook.
fn fuzz_worker(
    seed: u64,
    corpus: &[(Target, Vec<u8>)],
    inputs: u64,
    duration: Duration,
    keep: Option<&Path>,
) -> Report {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut report = Report::default();
    let start = Instant::now();
    // The first inputs are the seeds themselves, unmutated.
    let mut pool: Vec<(Target, Vec<u8>)> = corpus.to_vec();
    while report.inputs < inputs && start.elapsed() < duration {
        let k = rng.random_range(0..pool.len());
        let (target, input) = (pool[k].0, &pool[k].1);
        let bytes = if report.inputs < pool.len() as u64 {
            pool[report.inputs as usize].1.clone()
        } else {
            mutate(&mut rng, input, target, &pool)
        };
        let target = if report.inputs < pool.len() as u64 { pool[report.inputs as usize].0 } else { target };
        let t0 = Instant::now();
        let ok = catch_unwind(AssertUnwindSafe(|| exercise(target, &bytes))).is_ok();
        let dt = t0.elapsed().as_secs_f64();
        report.inputs += 1;
        *report.per_target.entry(target.name()).or_default() += 1;
        report.slowest_seconds = report.slowest_seconds.max(dt);
        let hang = dt > HANG_SECONDS && ok && still_slow(target, &bytes);
        report.panics += (!ok) as u64;
        report.hangs += hang as u64;
        if !ok || hang {
            if let Some(dir) = keep {
                let _ = std::fs::create_dir_all(dir);
                let digest = Sha256::digest(&bytes);
                let name = format!(
                    "{}-{}-{:02x}{:02x}{:02x}{:02x}",
                    if ok { "hang" } else { "panic" },
                    target.name(),
                    digest[0], digest[1], digest[2], digest[3]
                );
                let p = dir.join(name);
                let _ = std::fs::write(&p, &bytes);
                report.kept.push(p);
            }
        }
        // Occasionally keep a mutated input that still parses as a new seed
        // (bounded pool), so mutations compound.
        if ok && pool.len() < 4 * corpus.len() + 64 && rng.random_ratio(1, 64) {
            pool.push((target, bytes));
        }
    }
    report.seconds = start.elapsed().as_secs_f64();
    report.peak_rss_kb = peak_rss_kb();
    report
}

/// Re-runs a kept input (`<kind>-<target>-<hash>`, as [`fuzz`] names them):
/// `true` if it no longer panics.
pub fn replay(path: &Path) -> Option<bool> {
    let name = path.file_name()?.to_str()?;
    let target = [
        Target::Ply,
        Target::Obj,
        Target::Pc2,
        Target::Alembic,
        Target::Md3,
        Target::AnimationCfg,
        Target::SetJson,
        Target::SubjectJson,
        Target::Artifact,
    ]
        .into_iter()
        .find(|t| name.contains(&format!("-{}-", t.name())))?;
    let bytes = std::fs::read(path).ok()?;
    Some(catch_unwind(AssertUnwindSafe(|| exercise(target, &bytes))).is_ok())
}

/// [`fuzz`] over the built-in seeds plus the `corpus` folders, as the JSON
/// the `fuzz` binary writes.
pub fn run_to_json(
    seed: u64,
    corpus: &[PathBuf],
    inputs: u64,
    duration: Duration,
    keep: Option<&Path>,
) -> serde_json::Value {
    let mut seeds = seed_corpus();
    for dir in corpus {
        seeds.extend(load_corpus(dir));
    }
    let r = fuzz(seed, &seeds, inputs, duration, keep);
    serde_json::json!({
        "seed": seed,
        "threads": rayon::current_num_threads(),
        "seed_inputs": seeds.len(),
        "inputs": r.inputs,
        "per_target": r.per_target,
        "panics": r.panics,
        "hangs": r.hangs,
        "hang_seconds": HANG_SECONDS,
        "slowest_input_s": r.slowest_seconds,
        "peak_rss_kb": r.peak_rss_kb,
        "seconds": r.seconds,
        "inputs_per_second": r.inputs as f64 / r.seconds.max(1e-9),
        "kept": r.kept.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_cpu_time_counts_work_not_sleep() {
        let t0 = thread_cpu_seconds();
        std::thread::sleep(Duration::from_millis(200));
        let slept = thread_cpu_seconds() - t0;
        let t1 = thread_cpu_seconds();
        let mut x = 0u64;
        while thread_cpu_seconds() - t1 < 0.05 {
            x = x.wrapping_add(std::hint::black_box(1));
        }
        assert!(x > 0);
        assert!(slept < 0.05, "sleeping 0.2 s counted {slept} s of CPU");
    }

    #[test]
    fn token_at_finds_the_token_at_or_after_a_position() {
        let b = b"ply\nelement vertex 12\n";
        let text = |r: Option<(usize, usize)>| r.map(|(s, e)| &b[s..e]);
        assert_eq!(text(token_at(b, 0)), Some(&b"ply"[..]));
        assert_eq!(text(token_at(b, 2)), Some(&b"ply"[..]));
        assert_eq!(text(token_at(b, 3)), Some(&b"element"[..]));
        assert_eq!(text(token_at(b, 20)), Some(&b"12"[..]));
        assert_eq!(token_at(b, 22), None);
    }

    #[test]
    fn stored_kind_reads_each_seed_artifacts_kind() {
        let seeds = seed_corpus();
        let kinds: Vec<&str> =
            seeds.iter().filter(|(t, _)| *t == Target::Artifact).filter_map(|(_, b)| stored_kind(b)).collect();
        assert_eq!(kinds, ["segmentation", "aligned-motion", "pca-model", "pca-model-part", "correspondences", "variation-variants"]);
        assert_eq!(stored_kind(b"SURFCAP"), None);
    }
}
