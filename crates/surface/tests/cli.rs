//! The `blend` and `correct` binaries: outputs match the library, errors are one line, exit 1.
mod common;
use common::*;
use mesh_core::io::{read_mesh, write_mesh};
use mesh_core::sequence::MeshSequence;
use mesh_core::TriMesh;
use std::process::Command;
use surface::blend::Blender;
use surface::correct::Corrector;
use mesh_core::segmentation::{Part as SegmentPart, Segmentation};

fn run(bin: &str, args: &[&str]) -> (i32, String) {
    let out = Command::new(bin)
        .args(args)
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn blend_binary_matches_library_and_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let (rest, f) = tube(16, 21, 0.5, 0.1, true);
    let bent = bend(&rest, 0.5, 0.8, 1.6);
    let (pa, pb, po) = (
        dir.path().join("a.ply"),
        dir.path().join("b.ply"),
        dir.path().join("o.ply"),
    );
    write_mesh(&pa, &TriMesh::new(rest.clone(), f.clone())).unwrap();
    write_mesh(&pb, &TriMesh::new(bent.clone(), f.clone())).unwrap();
    let bin = env!("CARGO_BIN_EXE_blend");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (code, err) = run(bin, &[&s(&pa), &s(&pb), "-w", "0.25", "-o", &s(&po)]);
    assert_eq!(code, 0, "{err}");
    assert!(err.is_empty(), "quiet on success: {err}");
    let got = read_mesh(&po).unwrap();
    let want = Blender::new(rest.clone(), f.clone())
        .unwrap()
        .blend(&rest, &bent, 0.25)
        .unwrap();
    assert!(max_dist(&got.vertices, &want) < 1e-9);
    assert_eq!(got.faces, f);

    let (code, err) = run(bin, &[&s(&pa), &s(&pb), "-w", "1.5", "-o", &s(&po)]);
    assert_eq!((code, err.lines().count()), (1, 1), "{err}");
    assert!(
        err.starts_with("blend: ") && err.contains("weight"),
        "{err}"
    );
    let missing = dir.path().join("nope.ply");
    let (code, err) = run(
        bin,
        &[&s(&pa), &s(&missing), "-o", &s(&dir.path().join("x.ply"))],
    );
    assert_eq!((code, err.lines().count()), (1, 1), "{err}");
    assert!(err.contains("nope.ply"), "{err}");
    assert!(!dir.path().join("x.ply").exists(), "no output on failure");
    let other = dir.path().join("other.ply");
    let (v2, f2) = tube(10, 5, 0.5, 0.1, true);
    write_mesh(&other, &TriMesh::new(v2, f2)).unwrap();
    let (code, err) = run(bin, &[&s(&pa), &s(&other), "-o", &s(&po)]);
    assert_eq!(code, 1);
    assert!(
        err.contains("other.ply") && err.contains("topology"),
        "{err}"
    );
}

#[test]
fn correct_binary_processes_a_frame_directory() {
    let dir = tempfile::tempdir().unwrap();
    let (rest, f) = tube(12, 15, 0.5, 0.1, true);
    let training: Vec<_> = (0..5)
        .map(|k| bend(&rest, 0.3, 0.8, 0.3 * k as f64))
        .collect();
    MeshSequence::new(f.clone(), training.clone())
        .write_dir(dir.path().join("train"))
        .unwrap();
    let preds: Vec<_> = [0.45, 0.75]
        .iter()
        .map(|&a| {
            bend(&rest, 0.3, 0.8, a)
                .iter()
                .map(|p| p * 0.92)
                .collect::<Vec<_>>()
        })
        .collect();
    MeshSequence::new(f.clone(), preds.clone())
        .write_dir(dir.path().join("pred"))
        .unwrap();
    let p = |x: &str| dir.path().join(x).to_str().unwrap().to_string();
    let (code, err) = run(
        env!("CARGO_BIN_EXE_correct"),
        &[
            "--training",
            &p("train"),
            &p("pred"),
            "-m",
            "2",
            "-o",
            &p("out"),
        ],
    );
    assert_eq!(code, 0, "{err}");
    let got = MeshSequence::load_dir(dir.path().join("out")).unwrap();
    let c = Corrector::new(f.clone(), training.clone()).unwrap();
    for (g, pr) in got.frames.iter().zip(&preds) {
        assert!(max_dist(g, &c.correct(pr, 2).unwrap()) < 1e-9);
    }
    // A budget of 0 MiB holds no training mesh: the first alone is kept (every 8th of five),
    // which a warning says; the corrections are those of that one mesh.
    let (code, err) = run(
        env!("CARGO_BIN_EXE_correct"),
        &["--training", &p("train"), &p("pred"), "-m", "2", "-o", &p("strided"), "--memory-budget", "0"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("every 8th"), "{err}");
    let got = MeshSequence::load_dir(dir.path().join("strided")).unwrap();
    let first_only = Corrector::new(f.clone(), vec![training[0].clone()]).unwrap();
    for (g, pr) in got.frames.iter().zip(&preds) {
        assert_eq!(g, &first_only.correct(pr, 2).unwrap());
    }
    let (code, err) = run(
        env!("CARGO_BIN_EXE_correct"),
        &[
            "--training",
            &p("pred/000000.ply"),
            &p("pred"),
            "-o",
            &p("o2"),
        ],
    );
    assert_eq!((code, err.lines().count()), (1, 1), "{err}");
    assert!(
        err.starts_with("correct: ") && err.contains("000000.ply"),
        "{err}"
    );
}

#[test]
fn stitch_binary_merges_parts_from_a_segmentation() {
    use mesh_core::artifact::{Artifact, Header};
    let dir = tempfile::tempdir().unwrap();
    let (around, rings) = (12, 20);
    let (v, f) = tube(around, rings, 0.5, 0.1, true);
    let ring = |a: usize, b: usize| (a * around..(b + 1) * around).map(|i| i as u32);
    // Child listed before its root, as `segment` orders parts by name.
    let parts = vec![
        (
            Some("torso".to_string()),
            "arm",
            ring(8, rings - 1)
                .chain([(rings * around + 1) as u32])
                .collect::<Vec<u32>>(),
        ),
        (
            None,
            "torso",
            ring(0, 11)
                .chain([(rings * around) as u32])
                .collect::<Vec<u32>>(),
        ),
    ];
    let seg = Segmentation {
        n_vertices: v.len(),
        parts: parts
            .iter()
            .map(|(parent, name, vs)| SegmentPart {
                name: name.to_string(),
                parent: parent.clone(),
                vertices: vs.clone(),
                faces: vec![],
                overlap: vec![],
                loops: vec![],
            })
            .collect(),
    };
    seg.save(dir.path().join("parts.seg"), &Header::new("test", "0"))
        .unwrap();
    write_mesh(
        dir.path().join("template.ply"),
        &TriMesh::new(v.clone(), f.clone()),
    )
    .unwrap();
    std::fs::create_dir(dir.path().join("p")).unwrap();
    let r = rot([0.0, 1.0, 1.0], 0.4);
    for (parent, name, vs) in &parts {
        let pos = vs
            .iter()
            .map(|&i| {
                if parent.is_some() {
                    r * v[i as usize]
                } else {
                    v[i as usize]
                }
            })
            .collect();
        write_mesh(
            dir.path().join(format!("p/{name}.ply")),
            &TriMesh::new(pos, vec![]),
        )
        .unwrap();
    }
    let p = |x: &str| dir.path().join(x).to_str().unwrap().to_string();
    let bin = env!("CARGO_BIN_EXE_stitch");
    let args = [
        "--segmentation",
        &p("parts.seg"),
        "--template",
        &p("template.ply"),
        &p("p"),
        "-o",
        &p("out.ply"),
    ];
    let (code, err) = run(bin, &args);
    assert_eq!(code, 0, "{err}");
    let got = read_mesh(dir.path().join("out.ply")).unwrap();
    assert!(
        max_dist(&got.vertices, &v) < 1e-6,
        "{}",
        max_dist(&got.vertices, &v)
    );
    assert_eq!(got.faces, f);
    // The same parts as frame directories of three frames: a folder of three stitched frames,
    // each the single frame's; a part with another frame count is one line.
    for (_, name, _) in &parts {
        let m = read_mesh(dir.path().join(format!("p/{name}.ply"))).unwrap();
        MeshSequence::new(vec![], vec![m.vertices; 3]).write_dir(dir.path().join(format!("q/{name}"))).unwrap();
    }
    let dir_args = ["--segmentation", &p("parts.seg"), "--template", &p("template.ply"), &p("q"), "-o", &p("out")];
    let (code, err) = run(bin, &dir_args);
    assert_eq!(code, 0, "{err}");
    let frames = MeshSequence::load_dir(dir.path().join("out")).unwrap();
    assert_eq!((frames.n_frames(), &frames.faces), (3, &f));
    assert!(frames.frames.iter().all(|x| x == &got.vertices));
    let (_, first, _) = &parts[0];
    std::fs::remove_file(dir.path().join(format!("q/{first}/000002.ply"))).unwrap();
    let (code, err) = run(bin, &dir_args);
    assert_eq!((code, err.lines().count()), (1, 1), "{err}");
    assert!(err.contains("disagree on the number of frames"), "{err}");
    std::fs::remove_file(dir.path().join("p/arm.ply")).unwrap();
    let (code, err) = run(bin, &args);
    assert_eq!((code, err.lines().count()), (1, 1), "{err}");
    assert!(
        err.starts_with("stitch: ") && err.contains("arm.ply"),
        "{err}"
    );
}
