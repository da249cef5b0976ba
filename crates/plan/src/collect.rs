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

/// Merges transfer evaluation records into one sorted list at `out`.
pub fn transfer(records: &[PathBuf], out: &Path) -> Result<()> {
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
