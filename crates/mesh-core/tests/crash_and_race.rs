//! Outputs under SIGKILL and under two racing writers: a killed writer
//! leaves its output absent or complete (never partial under its final name)
//! and the next write removes its temporaries; two writers on one output
//! leave one complete winner. The writers are child processes running this
//! test binary's `writer_child` (ignored unless asked for by name).

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use mesh_core::artifact::{read_artifact, write_artifact, Header};
use mesh_core::sequence::MeshSequence;
use mesh_core::shapes::cylinder;
use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};

/// Sequence `tag`: `4 + tag % 5` frames of a cylinder shifted by `tag`, so
/// every tag's folder is recognisable and of its own length.
fn sequence(tag: u64) -> MeshSequence {
    let base = cylinder(20, 24, 0.2, 1.0);
    let frames = (0..4 + tag % 5)
        .map(|k| {
            base.vertices
                .iter()
                .map(|v| v + Vector3::new(tag as f64, k as f64, 0.0))
                .collect()
        })
        .collect();
    MeshSequence::new(base.faces, frames)
}

/// Artifact payload `tag`: 200k numbers, recognisable by their first.
fn payload(tag: u64) -> Vec<f64> {
    (0..200_000).map(|i| tag as f64 + i as f64).collect()
}

/// Run by the parent tests as a child process: writes output kind
/// `SURFCAP_WRITER_KIND` (`folder` or `artifact`) at `SURFCAP_WRITER_OUT`
/// for tags `SURFCAP_WRITER_TAGS` (comma-separated), in order.
#[test]
#[ignore = "a child process of the crash and race tests"]
fn writer_child() {
    let out = PathBuf::from(std::env::var("SURFCAP_WRITER_OUT").unwrap());
    let kind = std::env::var("SURFCAP_WRITER_KIND").unwrap();
    for tag in std::env::var("SURFCAP_WRITER_TAGS").unwrap().split(',') {
        let tag: u64 = tag.parse().unwrap();
        let written = match kind.as_str() {
            "folder" => sequence(tag).write_dir(&out),
            _ => write_artifact(&out, "test", 1, &Header::new("t", "0"), &payload(tag)),
        };
        // The parent reads this (run with --nocapture) when a write fails.
        if let Err(e) = written {
            eprintln!("writer error: {e}");
            std::process::exit(1);
        }
    }
}

fn spawn_writer(kind: &str, out: &Path, tags: &[u64]) -> Child {
    let tags: Vec<String> = tags.iter().map(u64::to_string).collect();
    Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "writer_child", "--ignored", "--test-threads", "1", "--nocapture"])
        .env("SURFCAP_WRITER_OUT", out)
        .env("SURFCAP_WRITER_KIND", kind)
        .env("SURFCAP_WRITER_TAGS", tags.join(","))
        .env("RAYON_NUM_THREADS", "2")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Which tag the output at `out` holds, if it exists; panics if it is partial
/// or mixed.
fn complete_tag(kind: &str, out: &Path) -> Option<u64> {
    if !out.exists() {
        return None;
    }
    if kind == "folder" {
        let seq = MeshSequence::load_dir(out).expect("a partial folder under the final name");
        let tag = seq.frames[0][0].x.round() as u64;
        assert_eq!(seq, sequence(tag), "folder mixes writes");
        Some(tag)
    } else {
        let (_, v): (Header, Vec<f64>) =
            read_artifact(out, "test", 1).expect("a partial artifact under the final name");
        let tag = v[0] as u64;
        assert_eq!(v, payload(tag));
        Some(tag)
    }
}

fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".surfcap-"))
        .collect()
}

fn kill_trials(kind: &str, trials: usize) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join(if kind == "folder" { "seq" } else { "x.art" });
    let mut seen = [0usize; 2];
    for trial in 0..trials {
        let mut child = spawn_writer(kind, &out, &[1, 2, 3, 4, 5, 6]);
        std::thread::sleep(Duration::from_millis(rng.random_range(5..120)));
        let _ = child.kill();
        child.wait().unwrap();
        let tag = complete_tag(kind, &out);
        seen[tag.is_some() as usize] += 1;
        // The next write (in this process) installs and cleans up after the dead one.
        if trial % 2 == 0 {
            let next = spawn_writer(kind, &out, &[9]).wait_with_output().unwrap();
            assert!(next.status.success(), "{}", String::from_utf8_lossy(&next.stderr).trim());
            assert_eq!(complete_tag(kind, &out), Some(9));
            assert_eq!(temporaries(dir.path()), Vec::<String>::new(), "trial {trial}");
        }
    }
    eprintln!("{kind}: {trials} kills, {} complete, {} absent", seen[1], seen[0]);
}

#[test]
fn killed_folder_writer_leaves_an_absent_or_complete_folder() {
    kill_trials("folder", 12);
}

#[test]
fn killed_artifact_writer_leaves_an_absent_or_complete_file() {
    kill_trials("artifact", 12);
}

fn race(kind: &str, trials: usize) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join(if kind == "folder" { "seq" } else { "x.art" });
    for _ in 0..trials {
        let a = spawn_writer(kind, &out, &[1, 3, 1, 3]);
        let b = spawn_writer(kind, &out, &[2, 4, 2, 4]);
        for c in [a, b] {
            let out = c.wait_with_output().unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(out.status.success(), "a racing writer failed: {}", err.trim());
        }
        let tag = complete_tag(kind, &out).expect("no output after two successful writers");
        assert!([3, 4].contains(&tag), "the winner is a last write: {tag}");
        assert_eq!(temporaries(dir.path()), Vec::<String>::new());
    }
}

#[test]
fn two_racing_folder_writers_leave_one_complete_winner() {
    race("folder", 4);
}

#[test]
fn two_racing_artifact_writers_leave_one_complete_winner() {
    race("artifact", 4);
}
