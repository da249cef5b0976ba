//! Round trips through the export formats and the CLI: what is written reads back.
mod common;

use std::process::Command;

use export::frames::{read_frames, write_frames, FrameFormat};
use mesh_core::io::pc2::{read_obj_pc2, write_obj_pc2};
use mesh_core::sequence::MeshSequence;

fn f32_rounded(seq: &MeshSequence) -> Vec<Vec<nalgebra::Vector3<f64>>> {
    seq.frames
        .iter()
        .map(|f| f.iter().map(|v| v.cast::<f32>().cast::<f64>()).collect())
        .collect()
}

#[test]
fn pc2_with_template_keeps_float32_positions_and_faces() {
    let dir = tempfile::tempdir().unwrap();
    let seq = common::bending_capsule(12, 0.6, 0.3);
    let (obj, pc2) = (dir.path().join("walk.obj"), dir.path().join("walk.pc2"));
    write_obj_pc2(&obj, &pc2, &seq).unwrap();
    let n = seq.n_vertices();
    assert_eq!(
        std::fs::metadata(&pc2).unwrap().len() as usize,
        32 + 12 * 12 * n
    );
    let back = read_obj_pc2(&obj, &pc2).unwrap();
    assert_eq!(back.faces, seq.faces);
    assert_eq!(
        back.frames,
        f32_rounded(&seq),
        "PC2 must hold exactly the f32-rounded positions"
    );
    let worst = back
        .frames
        .iter()
        .flatten()
        .zip(seq.frames.iter().flatten())
        .map(|(a, b)| (a - b).amax() / b.amax().max(1e-30))
        .fold(0.0, f64::max);
    assert!(worst <= f32::EPSILON as f64, "relative error {worst}");
}

#[test]
fn frame_folders_round_trip_in_both_formats_and_drop_stale_frames() {
    let dir = tempfile::tempdir().unwrap();
    let long = common::bending_capsule(7, 0.4, 0.0);
    let short = common::bending_capsule(4, 0.9, 1.0);
    for format in [FrameFormat::Obj, FrameFormat::Ply] {
        let d = dir.path().join(format!("{format:?}"));
        write_frames(&d, &long, format).unwrap();
        assert_eq!(read_frames(&d, None).unwrap(), long, "{format:?}");
        // A shorter sequence in the other format replaces every old frame.
        let other = if format == FrameFormat::Obj {
            FrameFormat::Ply
        } else {
            FrameFormat::Obj
        };
        write_frames(&d, &short, other).unwrap();
        assert_eq!(read_frames(&d, None).unwrap(), short, "{format:?} then {other:?}");
    }
}

#[test]
fn cli_export_then_import_through_pc2() {
    let dir = tempfile::tempdir().unwrap();
    let seq = common::bending_capsule(5, 0.5, 0.0);
    let src = dir.path().join("src");
    seq.write_dir(&src).unwrap();
    let pc2 = dir.path().join("out/walk.pc2");
    let st = Command::new(env!("CARGO_BIN_EXE_mesh-export"))
        .arg(&src)
        .arg("--out")
        .arg(&pc2)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert!(
        st.stdout.is_empty() && st.stderr.is_empty(),
        "quiet on success"
    );
    assert!(dir.path().join("out/walk.obj").is_file());
    let back = dir.path().join("back");
    let st = Command::new(env!("CARGO_BIN_EXE_mesh-import"))
        .arg(&pc2)
        .arg("--out")
        .arg(&back)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let got = MeshSequence::load_dir(&back).unwrap();
    assert_eq!(got.faces, seq.faces);
    assert_eq!(got.frames, f32_rounded(&seq));
}

#[test]
fn cli_rejects_a_truncated_pc2_with_one_line_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let seq = common::bending_capsule(3, 0.5, 0.0);
    let (obj, pc2) = (dir.path().join("w.obj"), dir.path().join("w.pc2"));
    write_obj_pc2(&obj, &pc2, &seq).unwrap();
    let bytes = std::fs::read(&pc2).unwrap();
    std::fs::write(&pc2, &bytes[..bytes.len() - 5]).unwrap();
    let back = dir.path().join("back");
    let st = Command::new(env!("CARGO_BIN_EXE_mesh-import"))
        .arg(&pc2)
        .arg("--out")
        .arg(&back)
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(1));
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("mesh-import: ") && err.contains("w.pc2") && err.contains("bytes follow"),
        "{err}"
    );
    assert!(!back.exists(), "no partial output");
}

#[test]
fn cli_refuses_unknown_formats_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    common::bending_capsule(2, 0.5, 0.0)
        .write_dir(&src)
        .unwrap();
    let fbx = dir.path().join("walk.fbx");
    let st = Command::new(env!("CARGO_BIN_EXE_mesh-export"))
        .arg(&src)
        .arg("--out")
        .arg(&fbx)
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(1));
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(
        err.starts_with("mesh-export: ")
            && err.contains("walk.fbx")
            && err.contains("unknown output format"),
        "{err}"
    );
    assert!(!fbx.exists());
    let glb = dir.path().join("walk.glb");
    std::fs::write(&glb, b"glTF").unwrap();
    let st = Command::new(env!("CARGO_BIN_EXE_mesh-import"))
        .arg(&glb)
        .arg("--out")
        .arg(dir.path().join("b"))
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(1));
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("walk.glb") && err.contains("cannot import"),
        "{err}"
    );
}
