//! The training pairs of a `make transfer` run for the study examples, encoded in the
//! direction SOURCE -> TARGET (reversed when SOURCE is the set's target).

use capture::part_pca::PcaModel;
use std::path::PathBuf;
use transfer::gpr_model::{PairData, PairFiles};

/// The pairs of the training motions `train` from `WORK` (`{work}/{subject}/{m}.aligned`,
/// `{work}/pairs/{m}.corr`), and the target-over-source frame-rate ratio of the first pair.
pub fn load(work: &str, set: &str, s: &str, t: &str, spca: &PcaModel, tpca: &PcaModel, train: &[String]) -> anyhow::Result<(Vec<PairData>, f64)> {
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
        let d = pf.encode(p1, p2)?;
        pairs.push(if reversed { d.reversed() } else { d });
    }
    Ok((pairs, ratio.unwrap_or(1.0)))
}
