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
                "anim.pc2" => assert_eq!(export::pc2::read_pc2(&out).unwrap().samples.len(), 120),
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
