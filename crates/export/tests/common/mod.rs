//! Shared test fixtures: a small bending capsule sequence and the node runner.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

use mesh_core::sequence::MeshSequence;
use nalgebra::Vector3;

/// A capsule of height 1 bending to and fro about z (vertex at height y
/// turned by `amp * sin(phase) * y`) while walking along x.
pub fn bending_capsule(n_frames: usize, amp: f64, phase0: f64) -> MeshSequence {
    let (mesh, _) = mesh_core::shapes::capsule_body(10, 16, 0.12, 1.0);
    let frames = (0..n_frames)
        .map(|t| {
            let theta =
                amp * (phase0 + 2.0 * std::f64::consts::PI * t as f64 / n_frames as f64).sin();
            let shift = 0.01 * t as f64;
            mesh.vertices
                .iter()
                .map(|p| {
                    let a = theta * p.y.clamp(0.0, 1.0);
                    let (s, c) = a.sin_cos();
                    Vector3::new(c * p.x - s * p.y + shift, s * p.x + c * p.y, p.z)
                })
                .collect()
        })
        .collect();
    MeshSequence::new(mesh.faces, frames)
}

pub fn web_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("web")
}

/// Runs `node web/<script> args...`; fails the test with a clear message
/// when node or the npm packages are missing (never skips).
pub fn node(script: &str, args: &[&Path]) -> std::process::Output {
    let web = web_dir();
    assert!(
        web.join("node_modules/gltf-validator").is_dir()
            && web.join("node_modules/playwright-core").is_dir(),
        "npm packages missing in {}: run scripts/setup-web (npm ci --prefix crates/export/web)",
        web.display()
    );
    match Command::new("node")
        .arg(web.join(script))
        .args(args)
        .output()
    {
        Ok(out) => out,
        Err(e) => {
            panic!("cannot run node (install Node.js >= 18; scripts/setup-web checks it): {e}")
        }
    }
}
