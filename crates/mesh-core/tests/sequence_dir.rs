//! Mesh sequences on disk: write/load round trip, frame ranges, numbering
//! rules, and frames that disagree with the first (error names the file).

use std::path::Path;

use mesh_core::io::{write_obj, write_ply, write_ply_ascii};
use mesh_core::sequence::{frame_files, FrameRange, MeshSequence};
use mesh_core::shapes::cylinder;
use nalgebra::Vector3;

/// A cylinder bending over `n` frames (distinct positions per frame).
fn bending(n: usize) -> MeshSequence {
    let base = cylinder(6, 10, 0.2, 1.0);
    let frames = (0..n)
        .map(|k| {
            let a = 0.1 * k as f64;
            base.vertices
                .iter()
                .map(|v| Vector3::new(v.x + a * v.y * v.y, v.y, v.z - a / 3.0))
                .collect()
        })
        .collect();
    MeshSequence::new(base.faces, frames)
}

fn err_of(dir: &Path) -> String {
    let msg = MeshSequence::load_dir(dir).unwrap_err().to_string();
    assert!(!msg.contains('\n'), "{msg}");
    msg
}

#[test]
fn write_then_load_round_trips_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let seq = bending(12);
    seq.write_dir(dir.path()).unwrap();
    std::fs::write(dir.path().join("notes.txt"), "ignored").unwrap();
    std::fs::write(dir.path().join("cam0.ply"), "ignored: not a frame number").unwrap();
    let back = MeshSequence::load_dir(dir.path()).unwrap();
    assert_eq!(back, seq);
    assert_eq!(
        (back.n_frames(), back.n_vertices(), back.n_faces()),
        (12, 60, 100)
    );
    assert_eq!(back.frame_mesh(3).vertices, seq.frames[3]);
    assert_eq!(back.topology().euler_characteristic(), 0);
    let names: Vec<String> = frame_files(dir.path())
        .unwrap()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names[0], "000000.ply");
    assert_eq!(names[11], "000011.ply");
}

#[test]
fn rewriting_a_shorter_sequence_removes_stale_frames() {
    let dir = tempfile::tempdir().unwrap();
    bending(8).write_dir(dir.path()).unwrap();
    write_obj(dir.path().join("000002.obj"), &bending(1).frame_mesh(0)).unwrap();
    let short = bending(3);
    short.write_dir(dir.path()).unwrap();
    assert_eq!(MeshSequence::load_dir(dir.path()).unwrap(), short);
}

#[test]
fn frame_ranges_select_frames() {
    let dir = tempfile::tempdir().unwrap();
    let seq = bending(10);
    seq.write_dir(dir.path()).unwrap();
    let r: FrameRange = "3:7".parse().unwrap();
    let part = MeshSequence::load_dir_range(dir.path(), r).unwrap();
    assert_eq!(part.frames, seq.frames[3..7]);
    let tail = MeshSequence::load_dir_range(dir.path(), "8:".parse().unwrap()).unwrap();
    assert_eq!(tail.frames, seq.frames[8..]);
    let one = MeshSequence::load_dir_range(dir.path(), "4".parse().unwrap()).unwrap();
    assert_eq!(one.frames, seq.frames[4..5]);
    assert_eq!(":".parse::<FrameRange>().unwrap(), FrameRange::default());
    assert!("5:5".parse::<FrameRange>().is_err());
    assert!("a:3".parse::<FrameRange>().is_err());
    let msg = MeshSequence::load_dir_range(dir.path(), "5:11".parse().unwrap())
        .unwrap_err()
        .to_string();
    assert!(msg.contains("outside the 10 frames"), "{msg}");
}

#[test]
fn mixed_formats_load_in_numeric_order() {
    let dir = tempfile::tempdir().unwrap();
    let seq = bending(4);
    write_ply(dir.path().join("000000.ply"), &seq.frame_mesh(0)).unwrap();
    write_obj(dir.path().join("000001.obj"), &seq.frame_mesh(1)).unwrap();
    write_ply_ascii(dir.path().join("000002.ply"), &seq.frame_mesh(2)).unwrap();
    write_ply(dir.path().join("000003.PLY"), &seq.frame_mesh(3)).unwrap();
    assert_eq!(MeshSequence::load_dir(dir.path()).unwrap(), seq);
}

#[test]
fn numbering_gaps_duplicates_and_empty_dirs_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let msg = err_of(dir.path());
    assert!(msg.contains("no frame files"), "{msg}");
    let seq = bending(4);
    seq.write_dir(dir.path()).unwrap();
    std::fs::remove_file(dir.path().join("000002.ply")).unwrap();
    let msg = err_of(dir.path());
    assert!(msg.contains("000002") && msg.contains("missing"), "{msg}");
    write_obj(dir.path().join("000002.obj"), &seq.frame_mesh(2)).unwrap();
    write_obj(dir.path().join("000001.obj"), &seq.frame_mesh(1)).unwrap();
    let msg = err_of(dir.path());
    assert!(msg.contains("frame 1 appears twice"), "{msg}");
    let msg = err_of(&dir.path().join("nope"));
    assert!(msg.contains("nope"), "{msg}");
}

#[test]
fn frames_that_disagree_with_the_first_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let seq = bending(6);
    seq.write_dir(dir.path()).unwrap();
    // Frame 4 loses a vertex (and the faces that used it).
    let mut m = seq.frame_mesh(4);
    m.vertices.pop();
    let last = m.vertices.len() as u32;
    m.faces.retain(|f| f.iter().all(|&i| i < last));
    write_ply(dir.path().join("000004.ply"), &m).unwrap();
    // Frame 5 has a different face list; frame 4 is reported first.
    let mut m5 = seq.frame_mesh(5);
    m5.faces.swap(0, 1);
    write_ply(dir.path().join("000005.ply"), &m5).unwrap();
    let msg = err_of(dir.path());
    assert!(
        msg.contains("000004.ply") && msg.contains("59 vertices") && msg.contains("60"),
        "{msg}"
    );
    write_ply(dir.path().join("000004.ply"), &seq.frame_mesh(4)).unwrap();
    let msg = err_of(dir.path());
    assert!(
        msg.contains("000005.ply") && msg.contains("face 0 differs"),
        "{msg}"
    );
    // A broken frame is reported with its own file name.
    std::fs::write(dir.path().join("000005.ply"), b"ply\nformat ascii 1.0\n").unwrap();
    let msg = err_of(dir.path());
    assert!(msg.contains("000005.ply"), "{msg}");
}
