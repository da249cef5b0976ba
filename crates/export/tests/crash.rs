//! `mesh-export` killed while it writes (SIGKILL at random moments): every output
//! kind (frame folder, `.glb`, `.pc2`) is absent or complete under its final
//! name, and the next run leaves no temporary behind.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use rand::{RngExt, SeedableRng};

fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".surfcap-"))
        .collect()
}

#[test]
fn killed_export_leaves_absent_or_complete_outputs_and_no_temporary_after_the_next_run() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    let seq = common::bending_capsule(120, 0.6, 0.0);
    seq.write_dir(&src).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let export = env!("CARGO_BIN_EXE_mesh-export");
    for (k, name) in ["frames", "anim.glb", "anim.pc2"].iter().cycle().take(15).enumerate() {
        let out = dir.path().join(name);
        let mut child = Command::new(export)
            .arg("-q")
            .arg(&src)
            .arg("--out")
            .arg(&out)
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(rng.random_range(1..60)));
        let _ = child.kill();
        let killed = !child.wait().unwrap().success();
        if out.exists() {
            match *name {
                "frames" => assert_eq!(mesh_core::sequence::MeshSequence::load_dir(&out).unwrap().frames, seq.frames),
                "anim.pc2" => assert_eq!(mesh_core::io::pc2::read_pc2(&out).unwrap().samples.len(), 120),
                _ => {
                    let bytes = std::fs::read(&out).unwrap();
                    let total = u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
                    assert_eq!(bytes.len(), total, "trial {k}: partial .glb");
                }
            }
        }
        let again = Command::new(export).arg("-q").arg(&src).arg("--out").arg(&out).status().unwrap();
        assert!(again.success());
        assert_eq!(temporaries(dir.path()), Vec::<String>::new(), "trial {k} (killed: {killed})");
    }
}

/// `html-report` killed at random moments: `index.html` and `report-assets/view-data.js` are each
/// absent or complete (the bytes a whole run writes), and the next run leaves no temporary.
#[test]
fn killed_html_report_leaves_absent_or_complete_pages_and_no_temporary_after_the_next_run() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    common::bending_capsule(120, 0.6, 0.0).write_dir(&src).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("results.json"), r#"{"rows": [{"motion": "walk", "rms_cm": 1.5}]}"#).unwrap();
    let report = env!("CARGO_BIN_EXE_html-report");
    let run = || {
        let mut c = Command::new(report);
        c.arg("-q").arg("--view").arg(format!("source={}", src.display())).arg("--out").arg(&out);
        c
    };
    assert!(run().status().unwrap().success());
    let (page, data) = (out.join("index.html"), out.join("report-assets/view-data.js"));
    let (whole_page, whole_data) = (std::fs::read(&page).unwrap(), std::fs::read(&data).unwrap());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for k in 0..12 {
        std::fs::remove_file(&page).unwrap();
        std::fs::remove_file(&data).unwrap();
        let mut child = run().stderr(Stdio::null()).spawn().unwrap();
        std::thread::sleep(Duration::from_millis(rng.random_range(1..40)));
        let _ = child.kill();
        let killed = !child.wait().unwrap().success();
        for (path, whole) in [(&page, &whole_page), (&data, &whole_data)] {
            if path.exists() {
                assert!(std::fs::read(path).unwrap() == *whole, "trial {k}: {} is partial (killed: {killed})", path.display());
            }
        }
        assert!(run().status().unwrap().success());
        let mut left = temporaries(&out);
        left.extend(temporaries(&out.join("report-assets")));
        assert_eq!(left, Vec::<String>::new(), "trial {k} (killed: {killed})");
    }
}
