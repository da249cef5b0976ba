//! What one task of each stage kind needs from a scheduler: CPUs and memory, from measured
//! peaks. `scripts/slurm-measure` runs both pipelines with every stage under `/usr/bin/time -v`
//! and prints per stage its peak resident set ("Maximum resident set size") and CPU share
//! ("Percent of CPU"); [`Resources::from_peaks`] turns a row into a request: memory ×1.5
//! rounded up to 50 MB, CPUs the ceiling of the share (at least 1). `plan slurm --resources
//! FILE` reads such a table; without it the built-in figures are the tiny preset's
//! (docs/CLUSTER.md).

use std::collections::BTreeMap;

use anyhow::{bail, Result};

/// CPUs and memory (MB) of one task.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resources {
    pub cpus: u32,
    pub mem_mb: u32,
}

impl Resources {
    /// The request for a measured peak: memory (MB) ×1.5 rounded up to 50 MB, CPUs from the
    /// CPU share in percent.
    pub fn from_peaks(peak_mb: f64, cpu_percent: f64) -> Self {
        let mem = (peak_mb * 1.5 / 50.0).ceil().max(1.0) * 50.0;
        let cpus = (cpu_percent / 100.0).ceil().max(1.0);
        Resources { cpus: cpus as u32, mem_mb: mem as u32 }
    }
}

/// Peaks of `scripts/slurm-measure` on the tiny preset (2-core VM, shared with four other
/// builds): `(stage, peak MB, CPU %)`. A stage's figure covers its per-part tasks too
/// (`pca-fit`, `gpr-train`, `gpdm-train --part`: one part of the model takes no more than the
/// whole), and `merge-parts` covers the merge arrays of all three (measured idle).
const TINY_PEAKS: [(&str, f64, f64); 16] = [
    ("align", 15.0, 80.0),
    ("dtw-densify", 13.0, 40.0),
    ("transfer-eval", 9.0, 100.0),
    ("gpdm-train", 19.0, 49.0),
    ("gpr-predict", 101.0, 66.0),
    ("gpr-train", 35.0, 57.0),
    ("hmc-sample", 30.0, 48.0),
    ("learning-curves", 75.0, 40.0),
    ("merge-parts", 13.0, 75.0),
    ("paper-figure", 42.0, 50.0),
    ("pca-fit", 55.0, 48.0),
    ("plan", 4.0, 40.0),
    ("prealign", 16.0, 48.0),
    ("render", 47.0, 53.0),
    ("segment", 5.0, 41.0),
    ("variation-eval", 23.0, 48.0),
];

/// The requests per stage binary.
#[derive(Clone, Debug, PartialEq)]
pub struct Table(BTreeMap<String, Resources>);

impl Default for Table {
    fn default() -> Self {
        Table(TINY_PEAKS.iter().map(|&(k, m, c)| (k.to_string(), Resources::from_peaks(m, c))).collect())
    }
}

impl Table {
    /// Parses `scripts/slurm-measure`'s output: a header line, then `stage tasks peak_MB cpu_% max_s`.
    pub fn parse(text: &str) -> Result<Self> {
        let mut map = BTreeMap::new();
        for (i, line) in text.lines().enumerate() {
            let f: Vec<&str> = line.split_whitespace().collect();
            if f.is_empty() || f[0] == "stage" {
                continue;
            }
            let num = |k: usize| f.get(k).and_then(|x| x.parse::<f64>().ok()).filter(|x| x.is_finite() && *x >= 0.0);
            let (Some(mb), Some(cpu)) = (num(2), num(3)) else {
                bail!("line {}: expected `stage tasks peak_MB cpu_% max_s`", i + 1);
            };
            if mb > 1.0e7 {
                bail!("line {}: {mb} MB is not a plausible peak", i + 1);
            }
            map.insert(f[0].to_string(), Resources::from_peaks(mb, cpu));
        }
        Ok(Table(map))
    }

    /// The request of one stage binary, if the table has it.
    pub fn get(&self, bin: &str) -> Option<Resources> {
        self.0.get(bin).copied()
    }

    /// The needs of one task that runs these stage binaries: the largest of each (500 MB for a
    /// binary the table lacks).
    pub fn for_bins(&self, bins: &[&str]) -> Resources {
        let mut r = Resources { cpus: 1, mem_mb: 50 };
        for b in bins {
            let x = self.get(b).unwrap_or(Resources { cpus: 1, mem_mb: 500 });
            r.cpus = r.cpus.max(x.cpus);
            r.mem_mb = r.mem_mb.max(x.mem_mb);
        }
        r
    }
}
