use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mesh_core::artifact::Artifact;
use mesh_core::capture_set::{CaptureSet, SubjectSpec};
use mesh_core::cli::{run_stage, CommonArgs};
use variation::group::{build, GroupSpec};
use variation::prealign::PrealignOptions;

/// Time-align the motions of one movement group to a reference by contact-guided DTW and add pre-blended sequences
#[derive(Parser, Debug)]
#[command(
    name = "prealign",
    version,
    after_help = "e.g.: prealign --set out/demo/set --subject-name A --group-name locomotion --motions walk,run --gait-cycles --blend-weights 0.5 --out out/work/variation/locomotion.group"
)]
struct Args {
    #[command(flatten)]
    common: CommonArgs,
    /// Capture-set folder
    #[arg(long)]
    set: PathBuf,
    /// Subject, by its name in set.json (default: the set's source subject)
    #[arg(long, value_name = "NAME")]
    subject_name: Option<String>,
    /// Name of the group written (e.g. locomotion)
    #[arg(long, value_name = "NAME")]
    group_name: String,
    /// Motions of the group, comma-separated; missing motions are skipped with a warning
    #[arg(long, value_delimiter = ',', required = true)]
    motions: Vec<String>,
    /// Reference motion [default: the first present]
    #[arg(long)]
    reference: Option<String>,
    /// Blend weights W between the first two motions (non-linear mesh blends), comma-separated
    #[arg(long, value_delimiter = ',', default_value = "0.5")]
    blend_weights: Vec<f64>,
    /// Cost of one foot-contact disagreement in the DTW (metres) [default: median pose cost]
    #[arg(long)]
    contact_weight: Option<f64>,
    /// Model the whole body as one part (no segmentation)
    #[arg(long)]
    whole_body: bool,
    /// When the subject's curves do not give usable body parts, warn and model the whole body
    /// [default: fail naming subject.json]
    #[arg(long)]
    fallback_whole_body: bool,
    /// Cut every motion to the same number of whole gait cycles (period from the poses) before
    /// the DTW, so locomotion pairs cycle for cycle
    #[arg(long)]
    gait_cycles: bool,
    /// Also write every time-aligned training sequence (pre-blends included) as meshes,
    /// `<DIR>/<sequence>/NNNNNN.ply` (world coordinates), for inspection
    #[arg(long, value_name = "DIR")]
    export: Option<PathBuf>,
    /// Output artifact (kind variation-group)
    #[arg(short, long)]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = mesh_core::cli::parse::<Args>();
    run_stage("prealign", || {
        args.common.init()?;
        let set = CaptureSet::open(&args.set)?;
        let subject = args
            .subject_name
            .clone()
            .unwrap_or_else(|| set.spec.source.clone());
        let spec = GroupSpec {
            name: args.group_name.clone(),
            subject,
            motions: args.motions.clone(),
            reference: args.reference.clone(),
            blend_weights: args.blend_weights.clone(),
            prealign: PrealignOptions {
                contact_weight: args.contact_weight,
                ..Default::default()
            },
            whole_body: args.whole_body,
            fallback_whole_body: args.fallback_whole_body,
            gait_cycles: args.gait_cycles,
        };
        let (group, notes) = build(&set, &spec)?;
        for n in notes {
            mesh_core::warn!("{n}");
        }
        let blends = if group.sequences.len() < 2 {
            Vec::new()
        } else {
            args.blend_weights.clone()
        };
        if group.sequences.iter().filter(|s| s.blend.is_none()).count() < 2
            && !args.blend_weights.is_empty()
        {
            mesh_core::warn!("group '{}' has one motion: no blends", group.name);
        }
        let subject_json = set.subject_json(&spec.subject);
        let subject_spec = SubjectSpec::load(&subject_json)?;
        let mut header = args
            .common
            .header("prealign", env!("CARGO_PKG_VERSION"))
            .with_input(set.set_json())?
            .with_input(&subject_json)?
            .with_input(set.template_path(&spec.subject, &subject_spec)?)?
            .with_params(&serde_json::json!({
                "subject": spec.subject, "group": spec.name, "motions": spec.motions,
                "reference": spec.reference, "blend_weights": blends, "contact_weight": args.contact_weight,
                "whole_body": spec.whole_body, "fallback_whole_body": spec.fallback_whole_body,
                "gait_cycles": spec.gait_cycles,
            }))?;
        for m in &spec.motions {
            for f in set.frames(&spec.subject, m)? {
                header = header.with_input(f)?;
            }
        }
        group.save(&args.out, &header)?;
        if let Some(dir) = &args.export {
            for s in &group.sequences {
                let seq = mesh_core::sequence::MeshSequence {
                    faces: group.faces.clone(),
                    frames: s.motion.world_frames(),
                };
                seq.write_dir(dir.join(&s.name))?;
            }
        }
        Ok(())
    })
}
