//! A trained model holds everything a query of a training sequence needs: `hmc-sample` without
//! the group writes the same bytes as with it; the group stays needed for the exact blend guide
//! and for the statistics against the captures. Damaged and older model files are refused in one line.

mod common;

use std::path::{Path, PathBuf};

use mesh_core::artifact::{encoded_len, encoded_seq_len, Artifact, Header};
use sha2::{Digest, Sha256};
use variation::group::Group;
use variation::reference::{Landmarks, Reference};
use variation::train::VariationModel;

/// Every file under `dir`, relative path and bytes, sorted.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

fn s(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

const SAMPLE: &str = env!("CARGO_BIN_EXE_hmc-sample");

/// `hmc-sample` on `model` with `args` (and `--group group` when given): its output.
fn sample(model: &Path, group: Option<&Path>, args: &[&str]) -> std::process::Output {
    let mut all = vec!["-q".to_string(), "--model".into(), s(model)];
    if let Some(g) = group {
        all.extend(["--group".into(), s(g)]);
    }
    all.extend(args.iter().map(|a| a.to_string()));
    let refs: Vec<&str> = all.iter().map(String::as_str).collect();
    common::stage(SAMPLE, &refs)
}

/// Stderr of a failed run: one line.
fn one_line_error(out: &std::process::Output) -> String {
    assert!(!out.status.success(), "the stage succeeded");
    assert!(out.status.code().is_some(), "killed by a signal: {out:?}");
    let err = String::from_utf8_lossy(&out.stderr).trim_end().to_string();
    assert_eq!(err.lines().count(), 1, "{err}");
    err
}

/// The artifact container around `header_json` and `payload` (kind `variation-model`, version
/// `version`): magic, versions, lengths, SHA-256 (mesh_core::artifact's layout).
fn container(header_json: &[u8], version: u32, payload: &[u8]) -> Vec<u8> {
    let kind = VariationModel::KIND.as_bytes();
    let mut b = b"SURFCAP\0".to_vec();
    b.extend(1u32.to_le_bytes());
    b.extend((kind.len() as u32).to_le_bytes());
    b.extend(kind);
    b.extend(version.to_le_bytes());
    b.extend((header_json.len() as u64).to_le_bytes());
    b.extend(header_json);
    b.extend((payload.len() as u64).to_le_bytes());
    b.extend(payload);
    let sum = Sha256::digest(&b);
    b.extend(sum);
    b
}

/// The header JSON and payload of a variation-model file's bytes.
fn sections(bytes: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let mut pos = 8 + 4;
    let kind_len = u32::from_le_bytes(bytes[pos..pos + 4].try_into().unwrap()) as usize;
    pos += 4 + kind_len + 4;
    let header_len = u64::from_le_bytes(bytes[pos..pos + 8].try_into().unwrap()) as usize;
    pos += 8;
    let header = bytes[pos..pos + header_len].to_vec();
    pos += header_len;
    let payload_len = u64::from_le_bytes(bytes[pos..pos + 8].try_into().unwrap()) as usize;
    pos += 8;
    (header, bytes[pos..pos + payload_len].to_vec())
}

#[test]
fn a_model_alone_answers_a_query_with_the_bytes_of_the_group_query() {
    let dir = tempfile::tempdir().unwrap();
    let (group, model) = common::tiny_model(dir.path());
    for (name, extra) in [
        ("walk", vec!["--motion", "walk"]),
        ("pre-blend", vec!["--motion", "blend-0.5", "--frame-format", "pc2"]),
        ("matching", vec!["--motion", "run", "--sampler", "motion-matching", "--frame-count", "50"]),
    ] {
        let (alone, with) = (dir.path().join(format!("{name}-alone")), dir.path().join(format!("{name}-group")));
        let (alone_s, with_s) = (s(&alone), s(&with));
        let mut args = vec!["-n", "3", "--seed", "4"];
        args.extend(&extra);
        let a: Vec<&str> = args.iter().copied().chain(["--out", alone_s.as_str()]).collect();
        let out = sample(&model, None, &a);
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let g: Vec<&str> = args.iter().copied().chain(["--out", with_s.as_str()]).collect();
        let out = sample(&model, Some(&group), &g);
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let (fa, fg) = (files(&alone), files(&with));
        assert!(fa.len() >= 3, "{name}: {} files", fa.len());
        assert_eq!(fa.len(), fg.len(), "{name}");
        for ((pa, ba), (pg, bg)) in fa.iter().zip(&fg) {
            assert_eq!(pa, pg, "{name}");
            assert!(ba == bg, "{name}: {} differs", pa.display());
        }
    }
}

#[test]
fn without_the_group_the_report_says_the_statistics_were_skipped_and_exact_blends_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (_, model) = common::tiny_model(dir.path());
    let (out, report) = (s(&dir.path().join("walk")), dir.path().join("walk.json"));
    let report_s = s(&report);
    let run = sample(&model, None, &["--motion", "walk", "-n", "2", "--out", &out, "--report", &report_s]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(json["sequences"].as_array().map(Vec::len), Some(0));
    assert!(json["capture_limits"].is_null());
    let notes = json["notes"].to_string();
    assert!(notes.contains("statistics against the sources skipped"), "{notes}");

    // The exact blend guide is made from the captured meshes: one line, nothing written.
    for args in [
        vec!["--blend", "walk:run", "--weight", "0.3", "--blend-guide", "exact"],
        vec!["--blends", "0.25", "--blend-guide", "exact"],
    ] {
        let o = dir.path().join("blend");
        let o_s = s(&o);
        let mut a = args.clone();
        a.extend(["-n", "2", "--out", o_s.as_str()]);
        let err = one_line_error(&sample(&model, None, &a));
        assert!(err.contains("--group"), "{err}");
        assert!(!o.exists(), "a refused query wrote {}", o.display());
    }
}

#[test]
fn the_model_round_trips_and_holds_the_references_of_its_group() {
    let dir = tempfile::tempdir().unwrap();
    let (group_path, model_path) = common::tiny_model(dir.path());
    let (header, model) = VariationModel::load_with_header(&model_path).unwrap();
    let again = dir.path().join("again.model");
    model.save(&again, &header).unwrap();
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&model_path).unwrap(), "saved bytes differ");
    assert_eq!(VariationModel::load(&again).unwrap(), model);

    let group = Group::load(&group_path).unwrap();
    let landmarks = Landmarks::of(&group.template, &group.faces, &group.parts, &group.up);
    assert!(landmarks.leg_weights.is_some(), "the tiny body has two legs");
    for (info, seq) in model.sequences.iter().zip(&group.sequences) {
        let want = Reference::of(&seq.motion.world_frames(), &group.template, &landmarks, &group.up);
        assert_eq!(info.reference, want, "{}", info.name);
        assert_eq!(info.reference.len(), model.frames);
        assert_eq!(info.contacts, seq.contacts, "{}", info.name);
    }
}

#[test]
fn truncated_crafted_and_older_models_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let (_, model_path) = common::tiny_model(dir.path());
    let bytes = std::fs::read(&model_path).unwrap();
    let bad = dir.path().join("bad.model");
    let out = dir.path().join("out");
    let out_s = s(&out);
    let query = |path: &Path| sample(path, None, &["--motion", "walk", "-n", "1", "--out", &out_s]);
    let name = s(&bad);

    // Truncated anywhere: the lengths are checked against the bytes that remain.
    for cut in [0, 7, 20, 60, bytes.len() / 3, bytes.len() / 2, bytes.len() - 33, bytes.len() - 1] {
        std::fs::write(&bad, &bytes[..cut]).unwrap();
        let err = one_line_error(&query(&bad));
        assert!(err.contains(&name), "cut at {cut}: {err}");
    }

    // A crafted length inside the payload (checksum recomputed): the first sequence's headings
    // claim 2^40 values. The decoder's byte limit refuses it before allocating.
    let (header, payload) = sections(&bytes);
    let model = VariationModel::load(&model_path).unwrap();
    let first = &model.sequences[0];
    let at = [
        encoded_len(&model.group).unwrap(),
        encoded_len(&model.subject).unwrap(),
        encoded_len(&model.fps).unwrap(),
        encoded_len(&model.up).unwrap(),
        encoded_len(&model.template).unwrap(),
        encoded_len(&model.faces).unwrap(),
        encoded_len(&model.parts).unwrap(),
        encoded_len(&model.scale).unwrap(),
        encoded_seq_len(model.sequences.len()),
        encoded_len(&first.name).unwrap(),
        encoded_len(&first.blend).unwrap(),
        encoded_len(&first.blend_of).unwrap(),
        encoded_len(&first.start_pose).unwrap(),
        encoded_len(&first.contacts).unwrap(),
    ]
    .iter()
    .sum::<u64>() as usize;
    let len_bytes = encoded_seq_len(first.reference.heading.len()) as usize;
    assert_eq!(payload[at..at + len_bytes], encoded_seq_len_bytes(first.reference.heading.len()));
    let mut crafted = payload[..at].to_vec();
    crafted.push(253);
    crafted.extend((1u64 << 40).to_le_bytes());
    crafted.extend(&payload[at + len_bytes..]);
    std::fs::write(&bad, container(&header, VariationModel::VERSION, &crafted)).unwrap();
    let err = one_line_error(&query(&bad));
    assert!(err.contains(&name) && err.contains("does not decode"), "{err}");

    // Reference trajectories of the wrong length (a valid encoding): refused by validation.
    let mut short = model.clone();
    short.sequences[1].reference.lowest.pop();
    short.save(&bad, &Header::new("gpdm-train", "0")).unwrap();
    let err = one_line_error(&query(&bad));
    assert!(err.contains(&name) && err.contains("reference trajectories"), "{err}");

    // A model of the previous version: refused, naming the stage that re-creates it.
    std::fs::write(&bad, container(&header, VariationModel::VERSION - 1, &payload)).unwrap();
    let err = one_line_error(&query(&bad));
    assert!(err.contains(&name) && err.contains(&format!("version {} is not supported", VariationModel::VERSION - 1)) && err.contains("gpdm-train"), "{err}");
    assert!(!out.exists(), "a refused model wrote output");
}

/// bincode 2's `standard()` encoding of a sequence length `n` (a varint).
fn encoded_seq_len_bytes(n: usize) -> Vec<u8> {
    match n {
        0..=250 => vec![n as u8],
        251..=0xffff => [vec![251], (n as u16).to_le_bytes().to_vec()].concat(),
        _ => [vec![252], (n as u32).to_le_bytes().to_vec()].concat(),
    }
}
