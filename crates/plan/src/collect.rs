//! The pipelines' last step: every evaluation record into one table.
//! - transfer: the records (one JSON object each) as one list sorted by direction, motion,
//!   method, training and placement → `results.json`;
//! - variation: per group its `<g>-train.json`, `<g>-eval.json`, `<g>-samples.json` →
//!   `variation.json` (`{group: {train, eval, samples}}`).
//!
//! Written atomically, in the layout of [`crate::json_text`].

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::json_text::{dumps_indent1, parse, Value};

fn load(path: &Path) -> Result<Value> {
    let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    parse(&text).with_context(|| path.display().to_string())
}

fn save(out: &Path, v: &Value) -> Result<()> {
    let text = dumps_indent1(v) + "\n";
    mesh_core::atomic::write_bytes_atomic(out, text.as_bytes())?;
    Ok(())
}

/// The sort key of a transfer record (missing text fields sort as "").
fn record_key(v: &Value) -> [String; 5] {
    ["direction", "motion", "method", "training", "placement"]
        .map(|k| v.get(k).and_then(Value::as_str).unwrap_or("").to_string())
}

/// The keys a cross-validation report gives each record of its direction: the pooled estimate
/// and the estimate per training motion.
const ESTIMATE_KEYS: [(&str, &str); 2] = [("cv_rms_pose_m", "cv_rms_pose_m"), ("motions", "cv_motions")];

/// Merges transfer evaluation records into one sorted list at `out`; each record of a direction
/// named in `cross_validations` (`DIRECTION=REPORT`) gets the report's `cv_rms_pose_m` and its
/// per-motion errors as `cv_motions`.
pub fn transfer(records: &[PathBuf], cross_validations: &[String], out: &Path) -> Result<()> {
    let mut estimates: Vec<(String, Vec<(&str, Value)>)> = Vec::new();
    for cv in cross_validations {
        let Some((direction, report)) = cv.split_once('=') else {
            anyhow::bail!("--cross-validation {cv}: expected DIRECTION=REPORT");
        };
        let value = load(Path::new(report))?;
        let fields = ESTIMATE_KEYS
            .iter()
            .map(|&(from, to)| value.get(from).cloned().map(|v| (to, v)).with_context(|| format!("{report}: no {from}")))
            .collect::<Result<Vec<_>>>()?;
        estimates.push((direction.to_string(), fields));
    }
    let mut recs = records
        .iter()
        .map(|p| {
            let v = load(p)?;
            if !matches!(v, Value::Object(_)) {
                anyhow::bail!("{}: an evaluation record must be a JSON object", p.display());
            }
            Ok(v)
        })
        .collect::<Result<Vec<_>>>()?;
    for r in &mut recs {
        let direction = r.get("direction").and_then(Value::as_str).unwrap_or("").to_string();
        if let (Some((_, cv)), Value::Object(fields)) = (estimates.iter().find(|(d, _)| *d == direction), r) {
            fields.retain(|(k, _)| !cv.iter().any(|(key, _)| k == key));
            fields.extend(cv.iter().map(|(k, v)| (k.to_string(), v.clone())));
        }
    }
    recs.sort_by_cached_key(record_key);
    save(out, &Value::Array(recs))
}

/// Merges every group's training, evaluation and sampling records (`<work>/<g>-<k>.json`).
pub fn variation(work: &Path, groups: &[String], out: &Path) -> Result<()> {
    let mut table: Vec<(String, Value)> = Vec::new();
    for g in groups {
        let mut entry = Vec::new();
        for k in ["train", "eval", "samples"] {
            entry.push((k.to_string(), load(&work.join(format!("{g}-{k}.json")))?));
        }
        match table.iter_mut().find(|(name, _)| name == g) {
            Some(slot) => slot.1 = Value::Object(entry),
            None => table.push((g.clone(), Value::Object(entry))),
        }
    }
    save(out, &Value::Object(table))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records of two directions, a cross-validation report for one: its records get the
    /// report's `cv_rms_pose_m` and its `motions` as `cv_motions`, the other direction's none; a
    /// report without either, or an argument without `=`, is an error naming it.
    #[test]
    fn each_record_of_a_cross_validated_direction_gets_its_estimate() {
        let dir = tempfile::tempdir().unwrap();
        let file = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            p
        };
        let records = [
            file("a.json", r#"{"direction": "B->A", "motion": "m", "method": "gpr-nn"}"#),
            file("b.json", r#"{"direction": "A->B", "motion": "m", "method": "gpr-nn"}"#),
            file("c.json", r#"{"direction": "A->B", "motion": "n", "method": "gpr-nn"}"#),
        ];
        let cv = file("cv.json", r#"{"config": "default", "cv_rms_pose_m": 0.0512, "motions": [{"motion": "walk", "frames": 9, "rms_pose_m": 0.04}]}"#);
        let out = dir.path().join("results.json");
        transfer(&records, &[format!("A->B={}", cv.display())], &out).unwrap();
        let table = load(&out).unwrap();
        let Value::Array(rows) = table else { panic!("{table:?}") };
        let estimates: Vec<Option<&Value>> = rows.iter().map(|r| r.get("cv_rms_pose_m")).collect();
        assert_eq!(estimates, vec![Some(&Value::Number("0.0512".into())), Some(&Value::Number("0.0512".into())), None]);
        let per_motion: Vec<Option<&Value>> = rows.iter().map(|r| r.get("cv_motions")).collect();
        let walk = load(&cv).unwrap().get("motions").cloned().unwrap();
        assert_eq!(per_motion, vec![Some(&walk), Some(&walk), None]);
        for (name, text, missing) in [
            ("bad.json", r#"{"config": "default", "motions": []}"#, "cv_rms_pose_m"),
            ("old.json", r#"{"config": "default", "cv_rms_pose_m": 0.05}"#, "motions"),
        ] {
            let bad = file(name, text);
            let e = transfer(&records, &[format!("A->B={}", bad.display())], &out).unwrap_err();
            assert!(format!("{e:#}").contains(name) && format!("{e:#}").contains(missing), "{e:#}");
        }
        assert!(transfer(&records, &["A->B".into()], &out).is_err());
    }
}
