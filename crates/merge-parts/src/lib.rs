//! The `merge-parts` stage: joins the pieces of one model, written by `pca-fit`, `gpr-train` or
//! `gpdm-train` with `--part NAME`, into the whole model, byte-identical to what the stage
//! writes without `--part` (`mesh_core::part_merge` holds the checks and the join; each kind's
//! crate says how its pieces join).

use std::path::PathBuf;

use capture::part_pca::PcaModel;
use clap::Parser;
use mesh_core::artifact::read_header;
use mesh_core::cli::CommonArgs;
use mesh_core::part_merge::{merge, Partitioned};
use transfer::gpr_model::GprModel;
use variation::train::VariationModel;

/// Join the per-part artifacts of one model (pca-fit, gpr-train or gpdm-train run with --part) into the whole model
#[derive(Parser, Debug)]
#[command(
    name = "merge-parts",
    version,
    after_help = "e.g.: merge-parts work/A/pca.model.torso work/A/pca.model.arm_l work/A/pca.model.arm_r --out work/A/pca.model"
)]
pub struct Params {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Pieces of one model (kind pca-model-part, gpr-model-part or variation-model-part), one per part, in any order
    #[arg(required = true)]
    pub pieces: Vec<PathBuf>,
    /// Output artifact: the whole model (kind pca-model, gpr-model or variation-model)
    #[arg(short, long)]
    pub out: PathBuf,
}

/// Joins pieces of one kind into the whole model at a path.
type Merge = fn(&[PathBuf], &std::path::Path) -> mesh_core::Result<()>;

/// The piece kinds this stage joins, each with its merge.
const KINDS: &[(&str, Merge)] = &[
    (PcaModel::PIECE_KIND, merge::<PcaModel>),
    (GprModel::PIECE_KIND, merge::<GprModel>),
    (VariationModel::PIECE_KIND, merge::<VariationModel>),
];

/// Merges `p.pieces` into `p.out`, by the kind of the first piece.
pub fn run(p: &Params) -> anyhow::Result<()> {
    let first = &p.pieces[0];
    let (kind, _, _) = read_header(first)?;
    match KINDS.iter().find(|(k, _)| *k == kind) {
        Some((_, merge)) => Ok(merge(&p.pieces, &p.out)?),
        None => Err(mesh_core::Error::file(
            first,
            format!(
                "kind '{kind}' is not a piece of a model (merge-parts joins {})",
                KINDS.iter().map(|(k, _)| *k).collect::<Vec<_>>().join(", ")
            ),
        )
        .into()),
    }
}
