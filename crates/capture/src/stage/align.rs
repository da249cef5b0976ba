//! The `align` stage: every frame of a motion Procrustes-aligned to the subject's template, with
//! the per-frame root displacements and the capture's frame rate, up axis and template hash.

use std::path::PathBuf;

use anyhow::bail;
use clap::Parser;
use mesh_core::artifact::{sha256_file, Artifact};
use mesh_core::capture_set::SubjectSpec;
use mesh_core::cli::CommonArgs;
use mesh_core::io::read_mesh;
use mesh_core::segmentation::Segmentation;
use mesh_core::sequence::frame_files;
use serde::Serialize;

use crate::align::{anchor_vertices, AlignFrame, CaptureInfo};
use crate::align_stream::FrameFiles;

/// Rigidly align every frame of a motion to the subject's template and record per-frame displacements
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "align",
    version,
    after_help = "e.g.: align --subject set/A/subject.json --template set/A/walk/000000.ply --segmentation work/A/parts.seg set/A/walk --out work/A/walk.aligned\n      align --frame body --subject set/A/subject.json --template set/A/walk/000000.ply set/A/walk --out work/A/walk.aligned"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// The subject's subject.json: its frame rate and up axis, recorded in the output
    #[arg(long, value_name = "SUBJECT_JSON")]
    pub subject: PathBuf,
    /// Template mesh of the subject (PLY or OBJ); every frame must share its topology
    #[arg(long)]
    pub template: PathBuf,
    /// Vertices each frame's rigid pose is fitted on: `root` = the root part without the
    /// bands it shares with the limbs (needs --segmentation); `body` = every vertex (the paper)
    #[arg(long, value_enum, default_value_t = AlignFrame::default())]
    pub frame: AlignFrame,
    /// Segmentation artifact of the subject (from `segment`), for --frame root
    #[arg(long)]
    pub segmentation: Option<PathBuf>,
    /// Motion folder of frames 000000.ply, 000001.ply, ...
    pub motion: PathBuf,
    /// Output artifact (kind aligned-motion)
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Writes the aligned motion; the header records `p`, `subject.json`, the template, the
/// segmentation and every frame file.
pub fn run(p: &Params) -> anyhow::Result<()> {
    if p.frame == AlignFrame::Root && p.segmentation.is_none() {
        bail!("--frame root needs --segmentation (the subject's parts from `segment`), or use --frame body");
    }
    let subject = SubjectSpec::load(&p.subject)?;
    let template = read_mesh(&p.template)?;
    let seg = p.segmentation.as_ref().map(Segmentation::load).transpose()?;
    if let (Some(s), Some(path)) = (&seg, &p.segmentation) {
        if s.n_vertices != template.n_vertices() {
            bail!(
                "{}: made for {} vertices but the template {} has {}",
                path.display(),
                s.n_vertices,
                p.template.display(),
                template.n_vertices()
            );
        }
    }
    let anchor = anchor_vertices(p.frame, seg.as_ref())?;
    let files = frame_files(&p.motion)?;
    // SubjectSpec::load has checked `up`: the fallback is unreachable.
    let up = subject.up_vector().unwrap_or_else(nalgebra::Vector3::y);
    let capture = CaptureInfo {
        fps: subject.fps,
        up: up.into(),
        template_sha256: sha256_file(&p.template)?,
    };
    // The header comes before the frames in the file: every frame file is hashed first.
    let mut header = p
        .common
        .header("align", env!("CARGO_PKG_VERSION"))
        .with_params(p)?
        .with_input(&p.subject)?
        .with_input(&p.template)?;
    if let Some(path) = &p.segmentation {
        header = header.with_input(path)?;
    }
    for f in &files {
        header = header.with_input(f)?;
    }
    FrameFiles::new(&template, &anchor, &files)
        .align_into(&capture, &header, &p.out)
        .map_err(|e| match e {
            // A problem of the motion as a whole names its folder; a frame's names its file.
            mesh_core::Error::Invalid(msg) => mesh_core::Error::file(&p.motion, msg),
            e => e,
        })?;
    Ok(())
}
