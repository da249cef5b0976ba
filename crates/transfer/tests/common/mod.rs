//! A small synthetic capture set with known answers: two capsule "bodies" of
//! different topology and size, each with a torso and one limb that bends
//! (angle θ) and bulges (φ). The target performs every motion in its own
//! style (`θ_B = 1.2 θ + 0.25 θ²`, `φ_B = 0.8 φ`), at twice the frame rate,
//! and moves 1.1 times further per second than the height ratio alone would
//! give. Ground truth is the target performing the test motion, one frame per
//! source frame, starting at the source's first pose.
//!
//! The meshes have over 1000 vertices on purpose: mesh-core's artifact reader
//! (bincode limit below 4x the payload, while bincode claims 4 bytes for every
//! u32 even when it is encoded in 1) rejects segmentations of small meshes.
//! NOTE(next): shrink back once the limit accounts for varint u32.

#![allow(dead_code)]

use std::path::Path;
use std::process::Command;

use mesh_core::rigid::{so3_exp, RigidMotion};
use mesh_core::sequence::MeshSequence;
use mesh_core::shapes::capsule_body;
use mesh_core::TriMesh;
use nalgebra::Vector3;

pub struct Body {
    pub mesh: TriMesh,
    pub height: f64,
    pub near: Vec<u32>,
    pub far: Vec<u32>,
    pub pivot: f64,
    pub fps: f64,
}

pub fn body_a() -> Body {
    let (mesh, l) = capsule_body(60, 24, 0.15, 1.6);
    Body {
        mesh,
        height: 1.6,
        near: l.ring(l.body_ring(25)),
        far: l.ring(l.body_ring(35)),
        pivot: 1.6 * 25.0 / 59.0,
        fps: 25.0,
    }
}

pub fn body_b() -> Body {
    let (mesh, l) = capsule_body(50, 20, 0.2, 1.9);
    Body {
        mesh,
        height: 1.9,
        near: l.ring(l.body_ring(20)),
        far: l.ring(l.body_ring(30)),
        pivot: 1.9 * 20.0 / 49.0,
        fps: 50.0,
    }
}

/// A motion's latent trajectory: bend angle, bulge, heading rate, speed.
#[derive(Clone, Copy)]
pub struct Latent {
    pub a: f64,
    pub f: f64,
    pub p: f64,
    pub b: f64,
    pub g: f64,
    pub omega: f64,
    pub speed: f64,
}

impl Latent {
    fn theta(&self, t: f64) -> f64 {
        self.a * (std::f64::consts::TAU * self.f * t + self.p).sin()
    }
    fn phi(&self, t: f64) -> f64 {
        self.b * (std::f64::consts::TAU * self.g * t).cos()
    }
}

fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// The body's vertices bent by `theta` about z at its pivot and bulged by `phi`.
pub fn pose(body: &Body, theta: f64, phi: f64) -> Vec<Vector3<f64>> {
    let ramp = 0.3 * body.height;
    body.mesh
        .vertices
        .iter()
        .map(|v| {
            let s = smoothstep((v.y - body.pivot) / ramp);
            let r = 1.0 + 0.15 * phi * s;
            let q = Vector3::new(v.x * r, v.y - body.pivot, v.z * r);
            let rot = so3_exp(&Vector3::new(0.0, 0.0, theta * s));
            rot * q + Vector3::new(0.0, body.pivot, 0.0)
        })
        .collect()
}

/// World pose at time `t` for a subject moving `scale` times the source's speed.
fn world(l: &Latent, t: f64, scale: f64) -> RigidMotion {
    RigidMotion::new(
        so3_exp(&Vector3::new(0.0, l.omega * t, 0.0)),
        Vector3::new(l.speed * scale * t, 0.0, 0.3 * l.speed * scale * t),
    )
}

/// Frames of `body` performing `l` in its style (`target` or not) at times `times`.
pub fn frames(
    body: &Body,
    l: &Latent,
    times: &[f64],
    target: bool,
    scale: f64,
) -> Vec<Vec<Vector3<f64>>> {
    times
        .iter()
        .map(|&t| {
            let (th, ph) = (l.theta(t), l.phi(t));
            let (th, ph) = if target {
                (1.2 * th + 0.25 * th * th, 0.8 * ph)
            } else {
                (th, ph)
            };
            world(l, t, scale).apply_all(&pose(body, th, ph))
        })
        .collect()
}

pub const TRAIN: [(&str, Latent); 4] = [
    (
        "walk",
        Latent {
            a: 0.6,
            f: 1.0,
            p: 0.0,
            b: 0.5,
            g: 1.0,
            omega: 0.0,
            speed: 1.0,
        },
    ),
    (
        "run",
        Latent {
            a: 0.9,
            f: 1.6,
            p: 0.5,
            b: -0.6,
            g: 0.7,
            omega: 0.3,
            speed: 2.0,
        },
    ),
    (
        "wave",
        Latent {
            a: 1.1,
            f: 0.8,
            p: 1.0,
            b: 0.8,
            g: 1.3,
            omega: -0.4,
            speed: 0.3,
        },
    ),
    (
        "turn",
        Latent {
            a: 0.4,
            f: 1.2,
            p: 2.0,
            b: -0.3,
            g: 0.5,
            omega: 1.0,
            speed: 0.6,
        },
    ),
];
pub const TEST: (&str, Latent) = (
    "probe",
    Latent {
        a: 0.8,
        f: 1.1,
        p: 0.7,
        b: 0.4,
        g: 0.9,
        omega: 0.2,
        speed: 1.2,
    },
);

/// Source frames (frame `i` at `i / 25` s): 31 per motion; target 61 (`j = 2 i`).
pub const N_SOURCE: usize = 31;

/// Writes the capture set to `dir` (set.json, A/, B/, truth/B/probe).
pub fn write_set(dir: &Path) {
    let (a, b) = (body_a(), body_b());
    let ratio = 1.1 * b.height / a.height;
    let ts: Vec<f64> = (0..N_SOURCE).map(|i| i as f64 / a.fps).collect();
    let tt: Vec<f64> = (0..2 * N_SOURCE - 1).map(|j| j as f64 / b.fps).collect();
    for (name, l) in TRAIN {
        MeshSequence::new(a.mesh.faces.clone(), frames(&a, &l, &ts, false, 1.0))
            .write_dir(dir.join("A").join(name))
            .unwrap();
        MeshSequence::new(b.mesh.faces.clone(), frames(&b, &l, &tt, true, ratio))
            .write_dir(dir.join("B").join(name))
            .unwrap();
    }
    let (name, l) = TEST;
    MeshSequence::new(a.mesh.faces.clone(), frames(&a, &l, &ts, false, 1.0))
        .write_dir(dir.join("A").join(name))
        .unwrap();
    MeshSequence::new(b.mesh.faces.clone(), frames(&b, &l, &ts, true, ratio))
        .write_dir(dir.join("truth").join("B").join(name))
        .unwrap();
    for (s, body) in [("A", &a), ("B", &b)] {
        let json = serde_json::json!({
            "fps": body.fps, "parts": {"torso": null, "limb": "torso"},
            "curves": {"limb": [body.near, body.far]},
        });
        std::fs::write(dir.join(s).join("subject.json"), json.to_string()).unwrap();
    }
    let keys = [[0, 0], [8, 16], [15, 30], [23, 46], [30, 60]];
    let train: Vec<_> = TRAIN
        .iter()
        .map(|(n, _)| serde_json::json!({"source": n, "target": n, "keyposes": keys}))
        .collect();
    let set = serde_json::json!({"source": "A", "target": "B", "train": train, "test": [name]});
    std::fs::write(dir.join("set.json"), set.to_string()).unwrap();
}

/// The stage binary `name`: this crate's own, or one of the front end (`align`, `segment`,
/// `pca-fit`, crate `capture`) or the tools `check-set` and `mesh-export`, which cargo builds into the same folder when the workspace is
/// built (`cargo test --release --workspace`, or `cargo build --release --workspace` first).
pub fn bin(name: &str) -> String {
    match name {
        "align" | "segment" | "pca-fit" | "hmc-sample" | "check-set" | "mesh-export" => return front_end_bin(name),
        "dtw-densify" => env!("CARGO_BIN_EXE_dtw-densify"),
        "gpr-train" => env!("CARGO_BIN_EXE_gpr-train"),
        "gpr-predict" => env!("CARGO_BIN_EXE_gpr-predict"),
        "transfer-eval" => env!("CARGO_BIN_EXE_transfer-eval"),
        _ => unreachable!(),
    }
    .to_string()
}

/// A front-end stage binary, next to this test's own folder (`target/<profile>/deps/..`).
fn front_end_bin(name: &str) -> String {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().and_then(|d| d.parent()).unwrap();
    let path = dir.join(name);
    assert!(
        path.is_file(),
        "{} is missing: build the workspace first (cargo build --release --workspace)",
        path.display()
    );
    path.to_string_lossy().into_owned()
}

/// Runs stage `name` with `args` (one BLAS thread); panics with its stderr on failure.
pub fn run<S: AsRef<std::ffi::OsStr> + std::fmt::Debug>(name: &str, args: &[S]) -> String {
    let out = Command::new(bin(name))
        .args(args)
        .env("OPENBLAS_NUM_THREADS", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{name} {args:?} failed: {err}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

