//! The training pairs of a `make transfer` run for the limb and stitch studies, encoded in the
//! direction SOURCE -> TARGET (reversed when SOURCE is the set's target).

use capture::align::{align_motion_on, AlignedMotion};
use capture::part_pca::PcaModel;
use mesh_core::artifact::Artifact;
use mesh_core::mesh::TriMesh;
use mesh_core::sequence::MeshSequence;
use nalgebra::DMatrix;
use std::path::PathBuf;
use transfer::gpr_model::{GprModel, PairData, PairFiles};

/// A study's command line: `WORK SET SOURCE TARGET MOTION... -- TRAIN...` (after `make
/// transfer`; the pairs are read in the set's order, reversed when SOURCE is the set's target).
#[derive(clap::Args, Debug, Clone)]
pub struct StudyArgs {
    /// The run's work folder (e.g. out/demo-run/work).
    pub work: String,
    /// The capture set (e.g. out/demo/set).
    pub set: String,
    /// The source subject.
    pub source: String,
    /// The target subject.
    pub target: String,
    /// The test motions.
    #[arg(required = true)]
    pub motions: Vec<String>,
    /// The training motions, after `--`.
    #[arg(last = true, required = true)]
    pub train: Vec<String>,
    /// Trains on the set's true frame correspondences in place of the run's DTW pairs.
    #[arg(long)]
    pub true_pairs: bool,
}

/// A study's command line and the PCA models and default gpr-nn model of that direction in WORK.
pub struct Study {
    pub work: String,
    pub set: String,
    pub s: String,
    pub t: String,
    pub tests: Vec<String>,
    pub train: Vec<String>,
    pub spca: PcaModel,
    pub tpca: PcaModel,
    pub model: GprModel,
    /// The target's template mesh (its walk's first frame).
    pub template: TriMesh,
    /// Train on the set's true correspondences ([`StudyArgs::true_pairs`]).
    pub true_pairs: bool,
}

/// A test motion of a study: the source's PCA coefficients per part and root displacements,
/// and the target's truth aligned as the target's training motions are.
pub struct TestMotion {
    pub xs: Vec<DMatrix<f64>>,
    pub xd: DMatrix<f64>,
    pub truth: MeshSequence,
}

impl Study {
    /// Reads the models of the direction `args` names.
    pub fn open(args: &StudyArgs) -> anyhow::Result<Study> {
        let StudyArgs { work, set, source: s, target: t, .. } = args.clone();
        Ok(Study {
            spca: PcaModel::load(format!("{work}/{s}/pca.model"))?,
            tpca: PcaModel::load(format!("{work}/{t}/pca.model"))?,
            model: GprModel::load(format!("{work}/models/{s}-to-{t}/gpr-nn.model"))?,
            template: mesh_core::io::read_mesh(format!("{set}/{t}/walk/000000.ply"))?,
            tests: args.motions.clone(),
            train: args.train.clone(),
            true_pairs: args.true_pairs,
            work,
            set,
            s,
            t,
        })
    }

    /// Parses the command line of a study with no switches of its own (`name` and `about` for
    /// its `--help`) and reads its models.
    pub fn from_command_line(name: &'static str, about: &'static str) -> anyhow::Result<Study> {
        use clap::{Args, FromArgMatches};
        let matches = StudyArgs::augment_args(clap::Command::new(name)).about(about).get_matches();
        Study::open(&StudyArgs::from_arg_matches(&matches)?)
    }

    /// Test motion `m`, read from WORK and SET.
    pub fn test_motion(&self, m: &str) -> anyhow::Result<TestMotion> {
        let (work, set, s, t) = (&self.work, &self.set, &self.s, &self.t);
        let motion = AlignedMotion::load(format!("{work}/{s}/{m}.aligned"))?;
        let truth = align_motion_on(&self.template, &MeshSequence::load_dir(format!("{set}/truth/{t}/{m}"))?, &self.tpca.anchor)?;
        Ok(TestMotion {
            xs: self.spca.encode(&motion)?,
            xd: transfer::predict::displacement_matrix(&motion.displacements),
            truth: MeshSequence::new(self.template.faces.clone(), truth.frames),
        })
    }
}

/// The pairs of the training motions `train` from `WORK` (`{work}/{subject}/{m}.aligned`,
/// `{work}/pairs/{m}.corr`), and the target-over-source frame-rate ratio of the first pair;
/// with `true_pairs`, the set's true frame correspondences in place of the run's DTW pairs.
#[allow(clippy::too_many_arguments)]
pub fn load(work: &str, set: &str, s: &str, t: &str, spca: &PcaModel, tpca: &PcaModel, train: &[String], true_pairs: bool) -> anyhow::Result<(Vec<PairData>, f64)> {
    let set_json: serde_json::Value = serde_json::from_slice(&std::fs::read(format!("{set}/set.json"))?)?;
    let reversed = set_json["source"].as_str().unwrap_or("") != s;
    let (first, second) = if reversed { (t, s) } else { (s, t) };
    let mut pairs = Vec::new();
    let mut ratio = None;
    for m in train {
        let files: Vec<PathBuf> =
            vec![format!("{work}/{first}/{m}.aligned").into(), format!("{work}/{second}/{m}.aligned").into(), format!("{work}/pairs/{m}.corr").into()];
        let pf = PairFiles::load(&files)?;
        let (fs, ft) = (pf.source.capture.require_fps()?, pf.target.capture.require_fps()?);
        ratio.get_or_insert(if reversed { fs / ft } else { ft / fs });
        let (p1, p2) = if reversed { (tpca, spca) } else { (spca, tpca) };
        let mut d = pf.encode(p1, p2)?;
        if true_pairs {
            let entry = set_json["train"].as_array().into_iter().flatten().find(|e| e["source"] == m.as_str());
            let corr = entry.and_then(|e| e["correspondences"].as_array()).ok_or_else(|| anyhow::anyhow!("{m}: no correspondences"))?;
            d.pairs = corr.iter().map(|p| [p[0].as_u64().unwrap() as usize, p[1].as_u64().unwrap() as usize]).collect();
        }
        pairs.push(if reversed { d.reversed() } else { d });
    }
    Ok((pairs, ratio.unwrap_or(1.0)))
}
