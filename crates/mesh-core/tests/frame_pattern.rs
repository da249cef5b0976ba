//! Frame files named by other tools: detected prefixes (`frame_0001.ply`, `walk.0001.obj`),
//! 0- and 1-based numbering, Blender's unpadded `punch0.obj ... punch10.obj`, explicit
//! printf patterns, and the ambiguities (two prefixes, gaps) as one-line errors naming the
//! folder. Each sequence is read back and compared with what was written.

use std::path::Path;

use mesh_core::frame_pattern::{detect, list, FramePattern};
use mesh_core::io::{write_obj, write_ply};
use mesh_core::sequence::{frame_files, MeshSequence};
use mesh_core::shapes::cylinder;
use nalgebra::Vector3;

fn bending(n: usize) -> MeshSequence {
    let base = cylinder(6, 10, 0.2, 1.0);
    let frames = (0..n)
        .map(|k| base.vertices.iter().map(|v| Vector3::new(v.x + 0.1 * k as f64 * v.y, v.y, v.z)).collect())
        .collect();
    MeshSequence::new(base.faces, frames)
}

/// Writes `seq`'s frame k as `name(k + first)`.
fn write_named(dir: &Path, seq: &MeshSequence, first: usize, name: impl Fn(usize) -> String) {
    for k in 0..seq.n_frames() {
        let p = dir.join(name(k + first));
        if p.extension().unwrap() == "obj" {
            write_obj(&p, &seq.frame_mesh(k)).unwrap();
        } else {
            write_ply(&p, &seq.frame_mesh(k)).unwrap();
        }
    }
}

fn names(dir: &Path) -> Vec<String> {
    frame_files(dir).unwrap().iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect()
}

#[test]
fn blender_unpadded_sequences_load_in_numeric_order() {
    let dir = tempfile::tempdir().unwrap();
    let seq = bending(12);
    write_named(dir.path(), &seq, 0, |n| format!("punch{n}.obj"));
    let l = detect(dir.path()).unwrap();
    assert_eq!(l.pattern.to_string(), "punch%d.obj");
    assert_eq!((l.first, l.files.len()), (0, 12));
    // Numeric, not lexical, order: punch2 before punch10.
    assert_eq!(names(dir.path())[2..4], ["punch2.obj", "punch3.obj"]);
    assert_eq!(names(dir.path())[10], "punch10.obj");
    assert_eq!(MeshSequence::load_dir(dir.path()).unwrap(), seq);
    assert!(l.describe().contains("punch%d.obj") && l.describe().contains("0-based"));
}

#[test]
fn prefixed_padded_and_one_based_frames_are_detected() {
    let seq = bending(5);
    for (name, first, shown) in [
        (Box::new(|n| format!("frame_{n:04}.ply")) as Box<dyn Fn(usize) -> String>, 1, "frame_%04d.ply"),
        (Box::new(|n| format!("walk.{n:04}.obj")), 1, "walk.%04d.obj"),
        (Box::new(|n| format!("walk.{n:04}.obj")), 0, "walk.%04d.obj"),
        (Box::new(|n| format!("{n:04}.PLY")), 1, "%04d.PLY"),
        (Box::new(|n| format!("cam2_take{n}.ply")), 7, "cam2_take%d.ply"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        write_named(dir.path(), &seq, first, &name);
        let l = detect(dir.path()).unwrap();
        assert_eq!((l.pattern.to_string().as_str(), l.first), (shown, first));
        assert_eq!(l.is_native(), false);
        assert_eq!(MeshSequence::load_dir(dir.path()).unwrap(), seq, "{shown}");
    }
}

#[test]
fn surfcap_folders_read_as_before_and_other_mesh_files_are_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let seq = bending(4);
    seq.write_dir(dir.path()).unwrap();
    write_ply(dir.path().join("template1.ply"), &seq.frame_mesh(0)).unwrap();
    let l = detect(dir.path()).unwrap();
    assert!(l.is_native());
    assert_eq!(l.pattern.to_string(), "%06d.ply");
    assert_eq!(MeshSequence::load_dir(dir.path()).unwrap(), seq);
}

#[test]
fn two_prefixes_and_gaps_are_one_line_errors_naming_the_folder() {
    let dir = tempfile::tempdir().unwrap();
    let seq = bending(3);
    write_named(dir.path(), &seq, 1, |n| format!("walk.{n:04}.obj"));
    write_named(dir.path(), &seq, 1, |n| format!("run_{n:04}.obj"));
    let msg = detect(dir.path()).unwrap_err().to_string();
    assert!(msg.starts_with(&dir.path().display().to_string()), "{msg}");
    assert!(msg.contains("2 different prefixes") && msg.contains("'run_…'") && msg.contains("'walk.…'"), "{msg}");
    assert!(!msg.contains('\n'));
    // A pattern picks one of them.
    let p: FramePattern = "walk.%04d.obj".parse().unwrap();
    let l = list(dir.path(), &p).unwrap();
    assert_eq!(l.files.len(), 3);
    assert!(l.files.iter().all(|f| f.file_name().unwrap().to_string_lossy().starts_with("walk.")));

    let gap = tempfile::tempdir().unwrap();
    write_named(gap.path(), &bending(6), 1, |n| format!("frame_{n:04}.ply"));
    std::fs::remove_file(gap.path().join("frame_0004.ply")).unwrap();
    let msg = frame_files(gap.path()).unwrap_err().to_string();
    assert!(msg.starts_with(&gap.path().display().to_string()), "{msg}");
    assert!(msg.contains("frame_0004.ply is missing") && msg.contains("frame_0003.ply is followed by frame_0005.ply"), "{msg}");
    // A duplicate number under two widths.
    let dup = tempfile::tempdir().unwrap();
    write_named(dup.path(), &bending(2), 0, |n| format!("punch{n}.obj"));
    write_obj(dup.path().join("punch01.obj"), &bending(1).frame_mesh(0)).unwrap();
    let msg = frame_files(dup.path()).unwrap_err().to_string();
    assert!(msg.contains("frame 1 appears twice"), "{msg}");
}

#[test]
fn printf_patterns_parse_print_and_reject_nonsense() {
    let p: FramePattern = "walk.%04d.obj".parse().unwrap();
    assert_eq!((p.prefix.as_str(), p.width, p.suffix.as_str()), ("walk.", Some(4), ".obj"));
    assert_eq!(p.example(7), "walk.0007.obj");
    assert_eq!(p.number_of("walk.0012.obj"), Some(12));
    assert_eq!(p.number_of("walk.12.obj"), None);
    let q: FramePattern = "punch%d.obj".parse().unwrap();
    assert_eq!((q.width, q.example(10), q.number_of("punch10.obj")), (None, "punch10.obj".into(), Some(10)));
    assert_eq!(q.to_string(), "punch%d.obj");
    for bad in ["walk.obj", "walk%s.obj", "walk%4d.obj", "a%d%d.obj", "walk%d.txt", "dir/walk%d.obj"] {
        let e = bad.parse::<FramePattern>().unwrap_err();
        assert!(e.contains(bad) && !e.contains('\n'), "{e}");
    }
    let dir = tempfile::tempdir().unwrap();
    let msg = list(dir.path(), &p).unwrap_err().to_string();
    assert!(msg.contains("no frame files match 'walk.%04d.obj'"), "{msg}");
}
