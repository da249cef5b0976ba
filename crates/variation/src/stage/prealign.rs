//! The `prealign` stage: the motions of one movement group time-aligned to a reference by
//! contact-guided DTW, with pre-blended sequences between pairs of them (by default the first
//! two; 3DV §4 and §7).

use std::path::PathBuf;

use clap::Parser;
use anyhow::bail;
use capture::align::AlignedMotion;
use mesh_core::artifact::{sha256_file, Artifact};
use mesh_core::capture_set::{CaptureSet, SubjectSpec};
use mesh_core::io::read_mesh;
use mesh_core::segmentation::Segmentation;
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::group::{build, FrontEnd, GroupSpec};
use crate::prealign::PrealignOptions;

/// Time-align the motions of one movement group to a reference by contact-guided DTW and add pre-blended sequences
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "prealign",
    version,
    after_help = "e.g.: prealign --set out/demo/set --subject-name A --segmentation out/work/A/parts.seg --group-name locomotion --gait-cycles --blend-weights 0.5 out/work/A/walk.aligned out/work/A/run.aligned --out out/work/variation/locomotion.group\n      prealign --set out/demo/set --segmentation out/work/A/parts.seg --group-name moves --blend-weights 0.25,0.5,0.75 --blend-pairs walk:run,walk:kick out/work/A/walk.aligned out/work/A/run.aligned out/work/A/kick.aligned --out out/work/variation/moves.group"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Capture-set folder
    #[arg(long)]
    pub set: PathBuf,
    /// Subject, by its name in set.json (default: the set's source subject)
    #[arg(long, value_name = "NAME")]
    pub subject_name: Option<String>,
    /// The subject's description in place of the set's subject.json (e.g. one written by
    /// propose-curves for a set without curves)
    #[arg(long, value_name = "SUBJECT_JSON")]
    pub subject: Option<PathBuf>,
    /// Segmentation artifact of the subject (from `segment`): the group's body parts
    /// [required unless --whole-body or --fallback-whole-body]
    #[arg(long)]
    pub segmentation: Option<PathBuf>,
    /// Name of the group written (e.g. locomotion)
    #[arg(long, value_name = "NAME")]
    pub group_name: String,
    /// Aligned motions of the group (artifacts from `align`, of the subject's template), in
    /// order; each named by its file name, `<motion>.aligned`
    #[arg(required = true)]
    pub motions: Vec<PathBuf>,
    /// Reference motion [default: the first present]
    #[arg(long)]
    pub reference: Option<String>,
    /// Blend weights W of every pre-blended pair (non-linear mesh blends), comma-separated
    #[arg(long, value_delimiter = ',', default_value = "0.5")]
    pub blend_weights: Vec<f64>,
    /// Pairs of motions to pre-blend at every weight, `A:B` comma-separated; the first is the
    /// group's blend pair [default: the first two motions]
    #[arg(long, value_name = "A:B", value_delimiter = ',', value_parser = super::parse_pair)]
    #[serde(serialize_with = "pairs_as_text")]
    pub blend_pairs: Vec<(String, String)>,
    /// Cost of one foot-contact disagreement in the DTW (metres) [default: median pose cost]
    #[arg(long)]
    pub contact_weight: Option<f64>,
    /// Model the whole body as one part (no segmentation)
    #[arg(long)]
    pub whole_body: bool,
    /// Without --segmentation (a subject whose curves do not give usable body parts), warn and
    /// model the whole body [default: fail]
    #[arg(long)]
    pub fallback_whole_body: bool,
    /// Cut every motion to the same number of whole gait cycles (period from the poses) before
    /// the DTW, so locomotion pairs cycle for cycle
    #[arg(long)]
    pub gait_cycles: bool,
    /// Also write every time-aligned training sequence (pre-blends included) as meshes,
    /// `<DIR>/<sequence>/NNNNNN.ply` (world coordinates), for inspection
    #[arg(long, value_name = "DIR")]
    pub export: Option<PathBuf>,
    /// Output artifact (kind variation-group)
    #[arg(short, long)]
    pub out: PathBuf,
}

/// `--blend-pairs` as written on the command line (`["A:B", ...]`).
fn pairs_as_text<S: serde::Serializer>(pairs: &[(String, String)], ser: S) -> Result<S::Ok, S::Error> {
    ser.collect_seq(pairs.iter().map(|(a, b)| format!("{a}:{b}")))
}

/// Writes the group; the header records `p` with the subject it resolved to (`subject_name`), set.json,
/// the subject's subject.json and template, the segmentation and every aligned motion.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let set = CaptureSet::open(&p.set)?;
    let subject = p
        .subject_name
        .clone()
        .unwrap_or_else(|| set.spec.source.clone());
    let subject_json = p.subject.clone().unwrap_or_else(|| set.subject_json(&subject));
    let subject_spec = SubjectSpec::load(&subject_json)?;
    let template = set.template_path(&subject, &subject_spec)?;
    let front = front_end(p, &template)?;
    let spec = GroupSpec {
        name: p.group_name.clone(),
        subject,
        subject_json: p.subject.clone(),
        motions: front.motions.iter().map(|(m, _)| m.clone()).collect(),
        reference: p.reference.clone(),
        blend_weights: p.blend_weights.clone(),
        blend_pairs: p.blend_pairs.clone(),
        prealign: PrealignOptions {
            contact_weight: p.contact_weight,
            ..Default::default()
        },
        whole_body: p.whole_body,
        fallback_whole_body: p.fallback_whole_body,
        gait_cycles: p.gait_cycles,
    };
    let (group, notes) = build(&set, &spec, front)?;
    for n in notes {
        mesh_core::warn!("{n}");
    }
    if group.sequences.iter().filter(|s| s.blend.is_none()).count() < 2
        && !p.blend_weights.is_empty()
    {
        mesh_core::warn!("group '{}' has one motion: no blends", group.name);
    }
    let mut params = serde_json::to_value(p)?;
    params["subject_name"] = spec.subject.clone().into();
    let mut header = p
        .common
        .header("prealign", env!("CARGO_PKG_VERSION"))
        .with_params(&params)?
        .with_input(set.set_json())?
        .with_input(&subject_json)?
        .with_input(&template)?;
    if let Some(seg) = &p.segmentation {
        header = header.with_input(seg)?;
    }
    for f in &p.motions {
        header = header.with_input(f)?;
    }
    group.save(&p.out, &header)?;
    if let Some(dir) = &p.export {
        for s in &group.sequences {
            let seq = mesh_core::sequence::MeshSequence {
                faces: group.faces.clone(),
                frames: s.motion.world_frames(),
            };
            seq.write_dir(dir.join(&s.name))?;
        }
    }
    Ok(())
}

/// The segmentation and the aligned motions of `p`, each named by its file name; a motion named
/// twice, or aligned to another template than `template`, is an error naming its file.
fn front_end(p: &Params, template: &std::path::Path) -> anyhow::Result<FrontEnd> {
    if p.segmentation.is_none() && !p.whole_body && !p.fallback_whole_body {
        bail!("the group's body parts need --segmentation (the subject's parts from `segment`), or --whole-body");
    }
    let segmentation = match (&p.segmentation, p.whole_body) {
        (Some(path), false) => {
            let seg = Segmentation::load(path)?;
            let n = read_mesh(template)?.n_vertices();
            if seg.n_vertices != n {
                bail!("{}: made for {} vertices but the template {} has {n}", path.display(), seg.n_vertices, template.display());
            }
            Some(seg)
        }
        _ => None,
    };
    let template_sha = sha256_file(template)?;
    let mut motions: Vec<(String, AlignedMotion)> = Vec::new();
    for f in &p.motions {
        let name = f
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_suffix(".aligned"))
            .filter(|n| !n.is_empty())
            .ok_or_else(|| anyhow::anyhow!("{}: not named <motion>.aligned", f.display()))?;
        if motions.iter().any(|(m, _)| m == name) {
            bail!("{}: motion '{name}' is given twice", f.display());
        }
        let m = AlignedMotion::load(f)?;
        if !m.capture.template_sha256.is_empty() && m.capture.template_sha256 != template_sha {
            bail!(
                "{}: aligned to template {} but the subject's template {} is {}",
                f.display(),
                short(&m.capture.template_sha256),
                template.display(),
                short(&template_sha)
            );
        }
        motions.push((name.to_string(), m));
    }
    Ok(FrontEnd { segmentation, motions })
}

/// The first 12 hex digits of a SHA-256, as messages show it.
fn short(sha: &str) -> &str {
    &sha[..sha.len().min(12)]
}
