//! Makes a large training motion for measuring `pca-fit`'s memory (`scripts/bench-memory`):
//! the template and the frames of some aligned motions, each midpoint-subdivided `--levels`
//! times (every triangle into four; new vertices at edge midpoints, as `synth` subdivides its
//! bodies), the frames repeated in turn until the motion has `--frames` frames.
//!
//! e.g.: subdivided_motion --template set/A/walk/000000.ply --levels 2 --frames 250 \
//!           --out /tmp/big work/A/walk.aligned work/A/run.aligned
//! writes /tmp/big/template.ply and /tmp/big/motion.aligned (aligned to that template on every
//! vertex); give `pca-fit` that motion k times for k x 250 frames. With `--ply`, the frames are
//! also written as /tmp/big/frames/000000.ply, ... (a motion folder for `align`).

use std::path::PathBuf;

use capture::align::{AlignedMotion, CaptureInfo};
use clap::Parser;
use mesh_core::artifact::{sha256_file, Artifact, Header};
use mesh_core::io::{read_mesh, write_ply};
use mesh_core::mesh::TriMesh;
use mesh_core::rigid::RigidMotion;

#[derive(Parser)]
struct Args {
    /// The aligned motions' template mesh
    #[arg(long)]
    template: PathBuf,
    /// Subdivision levels (each multiplies the vertex count by about four)
    #[arg(long, default_value_t = 1)]
    levels: usize,
    /// Frames of the motion written
    #[arg(long)]
    frames: usize,
    /// Output folder (template.ply, motion.aligned)
    #[arg(short, long)]
    out: PathBuf,
    /// Also write the frames as PLY files in OUT/frames
    #[arg(long)]
    ply: bool,
    /// Aligned motions of that template
    #[arg(required = true)]
    motions: Vec<PathBuf>,
}

fn main() -> anyhow::Result<()> {
    let a = Args::parse();
    let template = read_mesh(&a.template)?;
    // The faces at each level: a frame is subdivided level by level on the same faces.
    let mut level_faces = vec![template.faces.clone()];
    let mut vertices = template.vertices.clone();
    for l in 0..a.levels {
        let (v, f) = synth::subject::subdivide(&vertices, &level_faces[l]);
        vertices = v;
        level_faces.push(f);
    }
    let faces = level_faces.pop().expect("level 0 at least");
    std::fs::create_dir_all(&a.out)?;
    let template_out = a.out.join("template.ply");
    write_ply(&template_out, &TriMesh::new(vertices, faces.clone()))?;
    let sources: Vec<AlignedMotion> = a.motions.iter().map(AlignedMotion::load).collect::<Result<_, _>>()?;
    let originals: Vec<&Vec<nalgebra::Vector3<f64>>> = sources.iter().flat_map(|m| &m.frames).collect();
    let frames = (0..a.frames)
        .map(|i| {
            let mut v = originals[i % originals.len()].clone();
            for f in &level_faces {
                v = synth::subject::subdivide(&v, f).0;
            }
            v
        })
        .collect();
    let frames: Vec<Vec<nalgebra::Vector3<f64>>> = frames;
    if a.ply {
        mesh_core::sequence::MeshSequence::new(faces.clone(), frames.clone()).write_dir(a.out.join("frames"))?;
    }
    let motion = AlignedMotion {
        faces,
        frames,
        poses: vec![RigidMotion::identity(); a.frames],
        displacements: vec![[0.0; 6]; a.frames],
        anchor: Vec::new(),
        capture: CaptureInfo { fps: 25.0, up: [0.0, 1.0, 0.0], template_sha256: sha256_file(&template_out)? },
    };
    motion.save(a.out.join("motion.aligned"), &Header::new("subdivided_motion", env!("CARGO_PKG_VERSION")))?;
    Ok(())
}
