//! The `prealign` stage: the motions of one movement group time-aligned to a reference by
//! contact-guided DTW, with pre-blended sequences between pairs of them (by default the first
//! two; 3DV §4 and §7).

use std::path::PathBuf;

use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::{CaptureSet, SubjectSpec};
use mesh_core::cli::CommonArgs;
use serde::Serialize;

use crate::group::{build, GroupSpec};
use crate::prealign::PrealignOptions;

/// Time-align the motions of one movement group to a reference by contact-guided DTW and add pre-blended sequences
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "prealign",
    version,
    after_help = "e.g.: prealign --set out/demo/set --subject-name A --group-name locomotion --motions walk,run --gait-cycles --blend-weights 0.5 --out out/work/variation/locomotion.group\n      prealign --set out/demo/set --group-name moves --motions walk,run,kick --blend-weights 0.25,0.5,0.75 --blend-pairs walk:run,walk:kick --out out/work/variation/moves.group"
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
    /// Name of the group written (e.g. locomotion)
    #[arg(long, value_name = "NAME")]
    pub group_name: String,
    /// Motions of the group, comma-separated; missing motions are skipped with a warning
    #[arg(long, value_delimiter = ',', required = true)]
    pub motions: Vec<String>,
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
    /// When the subject's curves do not give usable body parts, warn and model the whole body
    /// [default: fail naming subject.json]
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
/// the subject's subject.json and template and every frame of the grouped motions.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let set = CaptureSet::open(&p.set)?;
    let subject = p
        .subject_name
        .clone()
        .unwrap_or_else(|| set.spec.source.clone());
    let spec = GroupSpec {
        name: p.group_name.clone(),
        subject,
        subject_json: p.subject.clone(),
        motions: p.motions.clone(),
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
    let (group, notes) = build(&set, &spec)?;
    for n in notes {
        mesh_core::warn!("{n}");
    }
    if group.sequences.iter().filter(|s| s.blend.is_none()).count() < 2
        && !p.blend_weights.is_empty()
    {
        mesh_core::warn!("group '{}' has one motion: no blends", group.name);
    }
    let subject_json = p.subject.clone().unwrap_or_else(|| set.subject_json(&spec.subject));
    let subject_spec = SubjectSpec::load(&subject_json)?;
    let mut params = serde_json::to_value(p)?;
    params["subject_name"] = spec.subject.clone().into();
    let mut header = p
        .common
        .header("prealign", env!("CARGO_PKG_VERSION"))
        .with_params(&params)?
        .with_input(set.set_json())?
        .with_input(&subject_json)?
        .with_input(set.template_path(&spec.subject, &subject_spec)?)?;
    for m in &spec.motions {
        for f in set.frames(&spec.subject, m)? {
            header = header.with_input(f)?;
        }
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
