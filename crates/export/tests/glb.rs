//! glTF export: the Khronos validator accepts every variant with no errors,
//! and decoding the file independently gives back the frames.
mod common;

use std::path::Path;

use export::glb::{encode_glb, write_glb, GlbOptions, Interpolation};
use mesh_core::sequence::MeshSequence;
use serde_json::Value;

/// Splits a .glb into its JSON document and BIN chunk (checking the container).
fn split_glb(bytes: &[u8]) -> (Value, &[u8]) {
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(4), 2);
    assert_eq!(u32_at(8), bytes.len());
    let json_len = u32_at(12);
    assert_eq!(&bytes[16..20], b"JSON");
    let doc = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let at = 20 + json_len;
    assert_eq!(&bytes[at + 4..at + 8], b"BIN\0");
    (doc, &bytes[at + 8..at + 8 + u32_at(at)])
}

/// Reads accessor `i` as f64 values (float, or normalized int16 with
/// byteStride), per the glTF 2.0 rules.
fn read_accessor(doc: &Value, bin: &[u8], i: usize) -> Vec<f64> {
    let a = &doc["accessors"][i];
    let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let off =
        v["byteOffset"].as_u64().unwrap() as usize + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    let width = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        t => panic!("{t}"),
    };
    let count = a["count"].as_u64().unwrap() as usize;
    let ct = a["componentType"].as_u64().unwrap();
    let size = if ct == 5126 { 4 } else { 2 };
    let stride = v["byteStride"]
        .as_u64()
        .map_or(width * size, |s| s as usize);
    let mut out = Vec::with_capacity(count * width);
    for e in 0..count {
        for c in 0..width {
            let p = off + e * stride + c * size;
            out.push(match ct {
                5126 => f32::from_le_bytes(bin[p..p + 4].try_into().unwrap()) as f64,
                5122 => {
                    assert_eq!(a["normalized"], true);
                    (i16::from_le_bytes(bin[p..p + 2].try_into().unwrap()) as f64 / 32767.0)
                        .max(-1.0)
                }
                _ => panic!("component type {ct}"),
            });
        }
    }
    out
}

/// Frame positions as a glTF viewer computes them: node TRS applied to base + target.
fn decoded_frames(bytes: &[u8]) -> (Vec<Vec<[f64; 3]>>, Vec<f64>, Vec<f64>) {
    let (doc, bin) = split_glb(bytes);
    let prim = &doc["meshes"][0]["primitives"][0];
    let base = read_accessor(
        &doc,
        bin,
        prim["attributes"]["POSITION"].as_u64().unwrap() as usize,
    );
    let node = &doc["nodes"][0];
    let tr: Vec<f64> = node.get("translation").map_or(vec![0.0; 3], |t| {
        t.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    });
    let sc: Vec<f64> = node.get("scale").map_or(vec![1.0; 3], |t| {
        t.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    });
    let world = |local: &[f64]| -> Vec<[f64; 3]> {
        local
            .chunks(3)
            .map(|p| {
                [
                    tr[0] + sc[0] * p[0],
                    tr[1] + sc[1] * p[1],
                    tr[2] + sc[2] * p[2],
                ]
            })
            .collect()
    };
    let mut frames = vec![world(&base)];
    let targets = prim["targets"].as_array().cloned().unwrap_or_default();
    for t in &targets {
        let d = read_accessor(&doc, bin, t["POSITION"].as_u64().unwrap() as usize);
        let p: Vec<f64> = base.iter().zip(&d).map(|(b, d)| b + d).collect();
        frames.push(world(&p));
    }
    let (mut times, mut weights) = (vec![], vec![]);
    if let Some(anim) = doc.get("animations") {
        let s = &anim[0]["samplers"][0];
        times = read_accessor(&doc, bin, s["input"].as_u64().unwrap() as usize);
        weights = read_accessor(&doc, bin, s["output"].as_u64().unwrap() as usize);
    }
    (frames, times, weights)
}

fn max_error(decoded: &[Vec<[f64; 3]>], seq: &MeshSequence, kept: &[usize]) -> f64 {
    assert_eq!(decoded.len(), kept.len());
    let mut worst = 0.0f64;
    for (f, &k) in decoded.iter().zip(kept) {
        for (p, q) in f.iter().zip(&seq.frames[k]) {
            worst = worst
                .max((p[0] - q.x).abs())
                .max((p[1] - q.y).abs())
                .max((p[2] - q.z).abs());
        }
    }
    worst
}

#[test]
fn morph_target_animation_decodes_to_the_frames() {
    let seq = common::bending_capsule(9, 0.7, 0.2);
    for (stride, quantize, tol) in [(1, false, 1e-6), (4, false, 1e-6), (2, true, 2e-4)] {
        let opts = GlbOptions {
            stride,
            quantize,
            fps: 25.0,
            ..Default::default()
        };
        let bytes = encode_glb(&seq, "walk", &opts).unwrap();
        let kept: Vec<usize> = (0..9).step_by(stride).collect();
        let (frames, times, weights) = decoded_frames(&bytes);
        let err = max_error(&frames, &seq, &kept);
        assert!(
            err < tol,
            "stride {stride} quantize {quantize}: max error {err}"
        );
        // Keys at k / fps, one-hot on target k - 1 (all zero at the first key).
        let n_t = kept.len() - 1;
        // ... plus a closing key one stride later repeating the last frame.
        let mut keys: Vec<(f64, Option<usize>)> = kept
            .iter()
            .enumerate()
            .map(|(j, &k)| (k as f64 / 25.0, j.checked_sub(1)))
            .collect();
        keys.push(((kept[kept.len() - 1] + stride) as f64 / 25.0, Some(n_t - 1)));
        assert_eq!(times.len(), keys.len());
        for (j, (t, on)) in keys.iter().enumerate() {
            assert!(
                (times[j] - t).abs() < 1e-6,
                "key {j}: time {} != {t}",
                times[j]
            );
            for i in 0..n_t {
                assert_eq!(
                    weights[j * n_t + i],
                    if Some(i) == *on { 1.0 } else { 0.0 },
                    "key {j} target {i}"
                );
            }
        }
    }
}

#[test]
fn khronos_validator_reports_no_errors() {
    let dir = tempfile::tempdir().unwrap();
    let seq = common::bending_capsule(20, 0.7, 0.2);
    let variants = [
        ("default.glb", GlbOptions::default()),
        (
            "stride.glb",
            GlbOptions {
                stride: 3,
                interpolation: Interpolation::Linear,
                ..Default::default()
            },
        ),
        (
            "quantized.glb",
            GlbOptions {
                quantize: true,
                ..Default::default()
            },
        ),
    ];
    let mut paths = Vec::new();
    for (name, opts) in &variants {
        let p = dir.path().join(name);
        write_glb(&p, &seq, opts).unwrap();
        paths.push(p);
    }
    let one = MeshSequence::new(seq.faces.clone(), vec![seq.frames[0].clone()]);
    let p = dir.path().join("single-frame.glb");
    write_glb(&p, &one, &GlbOptions::default()).unwrap();
    paths.push(p);
    let args: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
    let out = common::node("validate.mjs", &args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "validator found errors:\n{stdout}");
    let lines: Vec<Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), paths.len());
    for l in &lines {
        assert_eq!(l["errors"], 0, "{l}");
        assert_eq!(l["warnings"], 0, "{l}");
    }
    // three.js (the report's viewer) loads every file and its animation drives
    // the morph weights one-hot, frame by frame.
    let out = common::node("three-load.mjs", &args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "three.js could not load or play the files:\n{stdout}"
    );
}

/// `mesh-export` writes the animation at the sequence's own rate: a capture-set motion folder
/// plays at its subject's `fps`, a stage output at its rate file's, `--fps` overrides both, and
/// a folder with neither falls back to 30 fps with a warning. Read back from the glb's times.
#[test]
fn cli_export_keeps_the_sequence_rate() {
    let seq = common::bending_capsule(6, 0.7, 0.2);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let subject = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/tiny-set/A/subject.json");
    let capture_fps = mesh_core::capture_set::SubjectSpec::load(&subject).unwrap().fps;
    std::fs::create_dir_all(d.join("set/A")).unwrap();
    std::fs::copy(&subject, d.join("set/A/subject.json")).unwrap();
    seq.write_dir(d.join("set/A/walk")).unwrap();
    seq.write_dir(d.join("set/A/test/run")).unwrap();
    seq.write_dir_at(d.join("pred"), Some(50.0)).unwrap();
    seq.write_dir(d.join("bare")).unwrap();
    let cases: [(&str, Option<&str>, f64, bool); 5] = [
        ("set/A/walk", None, capture_fps, false),
        ("set/A/test/run", None, capture_fps, false),
        ("pred", None, 50.0, false),
        ("pred", Some("12"), 12.0, false),
        ("bare", None, 30.0, true),
    ];
    for (input, given, fps, warned) in cases {
        let out = d.join("out.glb");
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_mesh-export"));
        cmd.arg(d.join(input)).arg("--out").arg(&out);
        if let Some(f) = given {
            cmd.args(["--fps", f]);
        }
        let res = cmd.output().unwrap();
        let err = String::from_utf8_lossy(&res.stderr);
        assert!(res.status.success(), "{input}: {err}");
        assert_eq!(err.contains("no frame rate recorded"), warned, "{input}: {err:?}");
        let bytes = std::fs::read(&out).unwrap();
        let (_, times, _) = decoded_frames(&bytes);
        for (k, t) in times.iter().enumerate() {
            assert!((t - k as f64 / fps).abs() < 1e-5, "{input}: key {k} at {t} s, expected {fps} fps");
        }
    }
    assert_ne!(capture_fps, 30.0, "the fixture must not hide the fallback");
}
