//! The `merge-parts` stage: joins the pieces of one model, written by `pca-fit`, `gpr-train` or
//! `gpdm-train` with `--part NAME`, into the whole model, byte-identical to what the stage
//! writes without `--part`, and the pieces' `--report`s into the whole run's report
//! (`mesh_core::part_merge` holds the checks and the join; each kind's crate says how its
//! pieces and reports join).

use std::path::{Path, PathBuf};

use capture::part_pca::PcaModel;
use clap::Parser;
use mesh_core::artifact::read_header;
use mesh_core::cli::CommonArgs;
use mesh_core::part_merge::{merge, merge_reporting, Partitioned};
use serde::Serialize;
use transfer::gpr_model::GprModel;
use variation::train::VariationModel;

// The merged model's header is the pieces' (the single-process run's): nothing records these
// `Params`, which serialize like every stage's.
/// Join the per-part artifacts of one model (pca-fit, gpr-train or gpdm-train run with --part) into the whole model
#[derive(Parser, Debug, Serialize)]
#[command(
    name = "merge-parts",
    version,
    after_help = "e.g.: merge-parts work/A/pca.parts/torso.piece work/A/pca.parts/arm_l.piece work/A/pca.parts/arm_r.piece --out work/A/pca.model\n      \
                  merge-parts work/A/pca.parts/*.piece --out work/A/pca.model --piece-report work/A/pca.parts/torso.json ... --report work/A/pca.json"
)]
pub struct Params {
    #[command(flatten)]
    #[serde(skip)]
    pub common: CommonArgs,
    /// Pieces of one model (kind pca-model-part, gpr-model-part or variation-model-part), one per part, in any order
    #[arg(required = true)]
    pub pieces: Vec<PathBuf>,
    /// Output artifact: the whole model (kind pca-model, gpr-model or variation-model)
    #[arg(short, long)]
    pub out: PathBuf,
    /// A piece's report (pca-fit or gpdm-train --report with --part), one per piece, in any
    /// order; repeat
    #[arg(long, value_name = "REPORT", requires = "report")]
    pub piece_report: Vec<PathBuf>,
    /// Output report: the pieces' reports joined into the whole run's (needs --piece-report)
    #[arg(long, requires = "piece_report")]
    pub report: Option<PathBuf>,
}

/// Joins pieces of one kind into the whole model at a path.
type Merge = fn(&[PathBuf], &Path) -> mesh_core::Result<()>;
/// [`Merge`], and the pieces' reports into the whole run's report at a path.
type MergeReporting = fn(&[PathBuf], &Path, &[PathBuf], &Path) -> mesh_core::Result<()>;

/// The piece kinds this stage joins, each with its merge and, where its stage writes a report
/// per part, the merge with reports.
const KINDS: &[(&str, Merge, Option<MergeReporting>)] = &[
    (PcaModel::PIECE_KIND, merge::<PcaModel>, Some(merge_reporting::<PcaModel>)),
    (GprModel::PIECE_KIND, merge::<GprModel>, None),
    (VariationModel::PIECE_KIND, merge::<VariationModel>, Some(merge_reporting::<VariationModel>)),
];

/// Merges `p.pieces` into `p.out` (and `p.piece_report` into `p.report`), by the kind of the
/// first piece.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let first = &p.pieces[0];
    let (kind, _, _) = read_header(first)?;
    match (KINDS.iter().find(|(k, _, _)| *k == kind), &p.report) {
        (Some((_, merge, _)), None) => Ok(merge(&p.pieces, &p.out)?),
        (Some((_, _, Some(merge_reporting))), Some(report)) => {
            Ok(merge_reporting(&p.pieces, &p.out, &p.piece_report, report)?)
        }
        (Some((_, _, None)), Some(_)) => Err(mesh_core::Error::file(
            first,
            format!("pieces of kind '{kind}' have no reports: its stage writes none (drop --report)"),
        )
        .into()),
        (None, _) => Err(mesh_core::Error::file(
            first,
            format!(
                "kind '{kind}' is not a piece of a model (merge-parts joins {})",
                KINDS.iter().map(|(k, _, _)| *k).collect::<Vec<_>>().join(", ")
            ),
        )
        .into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_option_is_recorded_under_its_flag_name() {
        let argv = ["merge-parts", "a.piece", "b.piece", "--out", "m.model", "--piece-report", "a.json", "--report", "r.json"];
        assert_eq!(mesh_core::cli::unrecorded_options::<Params>(&argv).unwrap(), Vec::<String>::new());
    }
}
