use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Parser;
use mesh_core::artifact::{sha256_file, Artifact};
use mesh_core::capture_set::SubjectSpec;
use mesh_core::cli::{run_stage, CommonArgs};
use mesh_core::io::read_mesh;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::{frame_files, MeshSequence};
use capture::align::{align_motion_on, anchor_vertices, AlignFrame, CaptureInfo};

/// Rigidly align every frame of a motion to the subject's template and record per-frame displacements
#[derive(Parser, Debug)]
#[command(
    name = "align",
    version,
    after_help = "e.g.: align --subject set/A/subject.json --template set/A/walk/000000.ply --segmentation work/A/parts.seg set/A/walk --out work/A/walk.aligned\n      align --frame body --subject set/A/subject.json --template set/A/walk/000000.ply set/A/walk --out work/A/walk.aligned"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// The subject's subject.json: its frame rate and up axis, recorded in the output
    #[arg(long)]
    subject: PathBuf,
    /// Template mesh of the subject (PLY or OBJ); every frame must share its topology
    #[arg(long)]
    template: PathBuf,
    /// Vertices each frame's rigid pose is fitted on: `root` = the root part without the
    /// bands it shares with the limbs (needs --segmentation); `body` = every vertex (the paper)
    #[arg(long, value_enum, default_value_t = AlignFrame::Root)]
    frame: AlignFrame,
    /// Segmentation artifact of the subject (from `segment`), for --frame root
    #[arg(long)]
    segmentation: Option<PathBuf>,
    /// Motion folder of frames 000000.ply, 000001.ply, ...
    motion: PathBuf,
    /// Output artifact (kind aligned-motion)
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("align", || {
        args.common.init()?;
        if args.frame == AlignFrame::Root && args.segmentation.is_none() {
            bail!("--frame root needs --segmentation (the subject's parts from `segment`), or use --frame body");
        }
        let subject = SubjectSpec::load(&args.subject)?;
        let template = read_mesh(&args.template)?;
        let seg = args.segmentation.as_ref().map(Segmentation::load).transpose()?;
        if let (Some(s), Some(path)) = (&seg, &args.segmentation) {
            if s.n_vertices != template.n_vertices() {
                bail!(
                    "{}: made for {} vertices but the template {} has {}",
                    path.display(),
                    s.n_vertices,
                    args.template.display(),
                    template.n_vertices()
                );
            }
        }
        let anchor = anchor_vertices(args.frame, seg.as_ref())?;
        let files = frame_files(&args.motion)?;
        let motion = MeshSequence::load_files(&files)?;
        let mut aligned = align_motion_on(&template, &motion, &anchor)
            .with_context(|| args.motion.display().to_string())?;
        // SubjectSpec::load has checked `up`: the fallback is unreachable.
        let up = subject.up_vector().unwrap_or_else(nalgebra::Vector3::y);
        aligned.capture = CaptureInfo {
            fps: subject.fps,
            up: up.into(),
            template_sha256: sha256_file(&args.template)?,
        };
        let mut header = args
            .common
            .header("align", env!("CARGO_PKG_VERSION"))
            .with_params(&serde_json::json!({ "frame": args.frame }))?
            .with_input(&args.subject)?
            .with_input(&args.template)?;
        if let Some(path) = &args.segmentation {
            header = header.with_input(path)?;
        }
        for f in &files {
            header = header.with_input(f)?;
        }
        aligned.save(&args.out, &header)?;
        Ok(())
    })
}
