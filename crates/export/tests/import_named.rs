//! `import` on frame folders named as other tools name them: Blender's own OBJ sequence export
//! (`punch0.obj ... punch10.obj`, unpadded), a 1-based prefixed sequence, and an explicit
//! `--frames` pattern picking one of two sequences. The reading is stated in one line on
//! stderr (none with `-q`), and the imported folder reads back as the frames written.
mod common;

use std::path::Path;
use std::process::{Command, Output};

use mesh_core::io::write_obj;
use mesh_core::sequence::MeshSequence;

fn import(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mesh-import")).args(args).output().unwrap()
}

fn write_named(dir: &Path, seq: &MeshSequence, first: usize, name: impl Fn(usize) -> String) {
    std::fs::create_dir_all(dir).unwrap();
    for k in 0..seq.n_frames() {
        write_obj(dir.join(name(k + first)), &seq.frame_mesh(k)).unwrap();
    }
}

/// The frames as OBJ stores them (the writer prints coordinates that round-trip exactly).
fn same(a: &MeshSequence, b: &MeshSequence) {
    assert_eq!(a.faces, b.faces);
    assert_eq!(a.frames, b.frames);
}

#[test]
fn blender_sequence_export_is_imported_in_numeric_order() {
    let dir = tempfile::tempdir().unwrap();
    let seq = common::bending_capsule(11, 0.6, 0.3);
    let src = dir.path().join("blender");
    write_named(&src, &seq, 0, |n| format!("punch{n}.obj"));
    let out = dir.path().join("punch");
    let st = import(&[src.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let err = String::from_utf8(st.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("mesh-import: ") && err.contains("punch%d.obj") && err.contains("0 to 10") && err.contains("0-based"), "{err}");
    same(&MeshSequence::load_dir(&out).unwrap(), &seq);
    assert!(out.join("000010.ply").is_file());
    // -q: nothing on stderr.
    let st = import(&["-q".as_ref(), src.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(st.status.success() && st.stderr.is_empty());
}

#[test]
fn one_based_prefixed_frames_and_an_explicit_pattern() {
    let dir = tempfile::tempdir().unwrap();
    let walk = common::bending_capsule(6, 0.4, 0.1);
    let run = common::bending_capsule(4, 0.8, 0.2);
    let src = dir.path().join("shots");
    write_named(&src, &walk, 1, |n| format!("walk.{n:04}.obj"));
    let out = dir.path().join("walk");
    let st = import(&[src.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    assert!(String::from_utf8_lossy(&st.stderr).contains("walk.%04d.obj, numbers 1 to 6 (6 files, 1-based)"));
    same(&MeshSequence::load_dir(&out).unwrap(), &walk);

    // Two sequences in one folder: detection refuses, naming the folder; --frames picks one.
    write_named(&src, &run, 1, |n| format!("run_{n:03}.obj"));
    let st = import(&[src.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert_eq!(st.status.code(), Some(1));
    let err = String::from_utf8(st.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(&*src.to_string_lossy()) && err.contains("2 different prefixes"), "{err}");
    let out2 = dir.path().join("run");
    let st = import(&["--pattern".as_ref(), "run_%03d.obj".as_ref(), src.as_os_str(), "--out".as_ref(), out2.as_os_str()]);
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    same(&MeshSequence::load_dir(&out2).unwrap(), &run);
    // A bad pattern is a usage error.
    let st = import(&["--pattern".as_ref(), "run.obj".as_ref(), src.as_os_str(), "--out".as_ref(), out2.as_os_str()]);
    assert_eq!(st.status.code(), Some(2));
}
