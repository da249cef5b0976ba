//! End to end: the `render` binary on tiny generated sequences.

use std::path::Path;
use std::process::Command;

use mesh_core::{shapes, TriMesh};
use nalgebra::Vector3;

const BIN: &str = env!("CARGO_BIN_EXE_render");

/// Writes `n` frames of a swaying, walking capsule into `dir`.
fn write_sequence(dir: &Path, n: usize, shift: f64) {
    let (m, _) = shapes::capsule_body(5, 12, 0.15, 1.2);
    for i in 0..n {
        let t = i as f64 / n as f64;
        let v = m
            .vertices
            .iter()
            .map(|p| {
                Vector3::new(
                    p.x + shift + 0.4 * t + 0.2 * p.y * (6.0 * t).sin(),
                    p.y,
                    p.z,
                )
            })
            .collect();
        mesh_core::io::write_ply(
            dir.join(format!("{i:06}.ply")),
            &TriMesh::new(v, m.faces.clone()),
        )
        .unwrap();
    }
}

fn png_size(path: &Path) -> (u32, u32) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let r = dec.read_info().unwrap();
    (r.info().width, r.info().height)
}

fn gif_frames(path: &Path) -> (usize, u16, u16) {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut d = opts.read_info(std::fs::File::open(path).unwrap()).unwrap();
    let (w, h) = (d.width(), d.height());
    let mut n = 0;
    while d.read_next_frame().unwrap().is_some() {
        n += 1;
    }
    (n, w, h)
}

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn renders_frames_contact_sheet_and_gif_deterministically() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    write_sequence(&a, 7, 0.0);
    write_sequence(&b, 7, 0.5);
    let run = |out: &Path, threads: &str| {
        let o = Command::new(BIN)
            .args([
                a.to_str().unwrap(),
                b.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .args([
                "--size",
                "96x80",
                "--stride",
                "2",
                "--contact-columns",
                "3",
                "--labels",
                "source,transfer",
                "--threads",
                threads,
            ])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "render failed: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            o.stdout.is_empty() && o.stderr.is_empty(),
            "not quiet on success"
        );
    };
    let (o1, o2) = (tmp.path().join("o1"), tmp.path().join("o2"));
    run(&o1, "1");
    run(&o2, "2");
    // Frames 0, 2, 4, 6 -> 000000..000003.
    assert_eq!(
        files(&o1.join("frames")),
        ["000000.png", "000001.png", "000002.png", "000003.png"]
    );
    assert_eq!(png_size(&o1.join("frames/000002.png")), (96, 80));
    assert_eq!(gif_frames(&o1.join("anim.gif")), (4, 96, 80));
    let (cw, ch) = png_size(&o1.join("contact.png"));
    assert!(cw >= 3 * 64 && ch >= 64, "contact sheet {cw}x{ch}");
    assert_eq!(files(&o1), ["anim.gif", "contact.png", "frames"]);
    for f in [
        "frames/000000.png",
        "frames/000003.png",
        "anim.gif",
        "contact.png",
    ] {
        assert_eq!(
            std::fs::read(o1.join(f)).unwrap(),
            std::fs::read(o2.join(f)).unwrap(),
            "{f} differs between thread counts"
        );
    }
}

#[test]
fn options_select_outputs_and_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let a = tmp.path().join("walk");
    std::fs::create_dir_all(&a).unwrap();
    write_sequence(&a, 5, 0.0);
    let out = tmp.path().join("o");
    let o = Command::new(BIN)
        .arg(&a)
        .args([
            "--out",
            out.to_str().unwrap(),
            "--frames",
            "1:3",
            "--no-gif",
            "--contact-columns",
            "0",
            "--camera",
            "side",
            "--perspective",
            "35",
            "--flat",
            "--size",
            "40",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(files(&out), ["frames"]);
    assert_eq!(files(&out.join("frames")), ["000000.png", "000001.png"]);
    assert_eq!(png_size(&out.join("frames/000000.png")), (40, 40));

    // A longer earlier run's frames do not linger after a shorter run.
    let run = |extra: &[&str]| {
        let o = Command::new(BIN)
            .arg(&a)
            .args(["--out", out.to_str().unwrap(), "--size", "24", "--no-gif"])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    std::fs::write(out.join("frames/notes.txt"), "mine").unwrap();
    run(&[]);
    assert_eq!(files(&out.join("frames")).len(), 6);
    run(&["--stride", "3"]);
    assert_eq!(
        files(&out.join("frames")),
        ["000000.png", "000001.png", "notes.txt"]
    );
}

/// Runs the binary expecting exit 1 with exactly one `render: ...` line that contains `needle`.
fn expect_failure(args: &[&str], needle: &str) {
    let o = Command::new(BIN).args(args).output().unwrap();
    assert_eq!(o.status.code(), Some(1), "args {args:?}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "not one line: {err}");
    assert!(
        err.starts_with("render: ") && err.contains(needle),
        "{err:?} lacks {needle:?}"
    );
}

#[test]
fn bad_input_fails_with_one_line_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let missing = tmp.path().join("no_such_dir");
    expect_failure(
        &[missing.to_str().unwrap(), "--out", out.to_str().unwrap()],
        "no_such_dir",
    );
    assert!(!out.exists(), "output folder created for a failed run");

    // A frame whose vertex count differs from the first.
    let bad = tmp.path().join("bad");
    std::fs::create_dir_all(&bad).unwrap();
    write_sequence(&bad, 3, 0.0);
    let (small, _) = shapes::capsule_body(3, 8, 0.1, 1.0);
    mesh_core::io::write_ply(bad.join("000001.ply"), &small).unwrap();
    expect_failure(
        &[bad.to_str().unwrap(), "--out", out.to_str().unwrap()],
        "000001.ply",
    );
    assert!(!out.exists(), "output folder created for a failed run");

    // A truncated PLY.
    let trunc = tmp.path().join("trunc");
    std::fs::create_dir_all(&trunc).unwrap();
    write_sequence(&trunc, 2, 0.0);
    let bytes = std::fs::read(trunc.join("000001.ply")).unwrap();
    std::fs::write(trunc.join("000001.ply"), &bytes[..bytes.len() / 2]).unwrap();
    expect_failure(
        &[trunc.to_str().unwrap(), "--out", out.to_str().unwrap()],
        "000001.ply",
    );

    // An empty folder and a frame range past the end.
    let empty = tmp.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    expect_failure(
        &[empty.to_str().unwrap(), "--out", out.to_str().unwrap()],
        "no frame files",
    );
    let good = tmp.path().join("good");
    std::fs::create_dir_all(&good).unwrap();
    write_sequence(&good, 2, 0.0);
    expect_failure(
        &[
            good.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--frames",
            "5:9",
        ],
        "2 frames",
    );
    expect_failure(
        &[
            good.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--labels",
            "a,b",
        ],
        "2 labels for 1",
    );
    assert!(!out.exists(), "output folder created for a failed run");

    // Curves with an out-of-range vertex in --parts.
    let subj = tmp.path().join("subject.json");
    std::fs::write(
        &subj,
        r#"{"fps": 25, "parts": {"torso": null, "arm": "torso"}, "curves": {"arm": [[0, 1, 99999], [5, 6, 7]]}}"#,
    )
    .unwrap();
    expect_failure(
        &[
            good.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--subject",
            subj.to_str().unwrap(),
        ],
        "subject.json",
    );
    assert!(!out.exists());
}

#[test]
fn usage_errors_exit_2() {
    let o = Command::new(BIN)
        .args(["x", "--out", "y", "--camera", "top"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}
