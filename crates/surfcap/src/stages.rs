//! The stages in pipeline order, each with the group it belongs to and one
//! line saying what it does: the one table `surfcap help`, the dispatcher
//! and the man/completion generator read.

/// One stage: the name users type, the binary it runs (beside `surfcap`),
/// its group and what it does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stage {
    pub name: &'static str,
    pub bin: &'static str,
    pub group: &'static str,
    pub about: &'static str,
}

const fn st(name: &'static str, bin: &'static str, group: &'static str, about: &'static str) -> Stage {
    Stage { name, bin, group, about }
}

const DATA: &str = "capture sets";
const TRANSFER: &str = "transfer (CVPR 2017)";
const VARIATION: &str = "variation (3DV 2017)";
const OUTPUT: &str = "results";
const PIPELINE: &str = "pipelines and tools";

/// Every stage, in the order the pipelines run them.
pub const STAGES: &[Stage] = &[
    st("synth", "synth", DATA, "build a capture set from real bodies and real mocap, with ground truth"),
    st("characters", "characters", DATA, "build capture sets from real animated game characters (Quake 3 MD3 players), with references"),
    st("mesh-import", "mesh-import", DATA, "read OBJ/PLY frames (any naming) or OBJ + PC2 into a folder of PLY frames"),
    st("check-set", "check-set", DATA, "validate a capture set and list every problem, one line each"),
    st("propose-curves", "propose-curves", DATA, "find limb loops on a template without annotation, into a copy of subject.json"),
    st("render", "render", DATA, "draw mesh sequences to PNG frames, a contact sheet and a GIF"),
    st("inspect", "inspect", DATA, "print an artifact's kind, version and provenance header as JSON"),
    st("segment", "segment", TRANSFER, "cut the template into overlapping parts along the subject's curves"),
    st("align", "align", TRANSFER, "Procrustes-align every frame to the template; root displacements"),
    st("pca-fit", "pca-fit", TRANSFER, "per-part (or whole-body) PCA of aligned motions"),
    st("dtw-densify", "dtw-densify", TRANSFER, "dense correspondences of a training pair: BLR cost + constrained DTW"),
    st("gpr-train", "gpr-train", TRANSFER, "per-part GP regression from source to target coefficients"),
    st("gpr-predict", "gpr-predict", TRANSFER, "transfer a source motion onto the target subject"),
    st("correct", "correct", TRANSFER, "body-part correction toward the nearest training meshes"),
    st("stitch", "stitch", TRANSFER, "merge parts along optimal boundaries by Poisson"),
    st("transfer-eval", "transfer-eval", TRANSFER, "RMS per-vertex error against ground truth, foot sliding"),
    st("representation-error", "representation-error", TRANSFER, "a subject's own truth through part PCA and each surface method: the floor of the error"),
    st("surface-quality", "surface-quality", TRANSFER, "seam, closedness, part volume and edge-length statistics against the truth"),
    st("learning-curves", "learning-curves", TRANSFER, "errors against training-set size (CVPR figs. 7-9)"),
    st("paper-figure", "paper-figure", TRANSFER, "CVPR figs. 3, 5 and 10, per-frame confidence"),
    st("prealign", "prealign", VARIATION, "time-align motions of one movement type by contact-guided DTW"),
    st("blend", "blend", VARIATION, "non-linear pose/sequence interpolation (deformation gradients + Poisson)"),
    st("gpdm-train", "gpdm-train", VARIATION, "one GPDM per body part from a prealigned movement group"),
    st("hmc-sample", "hmc-sample", VARIATION, "variations by Hybrid Monte Carlo over latent trajectories"),
    st("variation-eval", "variation-eval", VARIATION, "variation statistics and the papers' comparisons"),
    st("mesh-export", "mesh-export", OUTPUT, "OBJ/PLY frames, OBJ + PC2 point cache, glTF .glb"),
    st("html-report", "html-report", OUTPUT, "a static HTML page with tables, pictures and a 3D player"),
    st("merge-parts", "merge-parts", PIPELINE, "join per-part fits (pca-fit, gpr-train, gpdm-train --part) into the whole model"),
    st("plan", "plan", PIPELINE, "the pipelines' task graph: make fragment, Slurm job arrays"),
    st("fuzz", "fuzz", PIPELINE, "mutation-fuzz every reader in process"),
];

/// The stage a user's word names.
pub fn find(name: &str) -> Option<&'static Stage> {
    STAGES.iter().find(|s| s.name == name)
}
