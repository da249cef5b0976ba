//! What one task of each stage kind needs from a scheduler: CPUs and memory. The figures are
//! the measured peaks (`/usr/bin/time -v`, "Maximum resident set size" and "Percent of CPU")
//! of every task of `make transfer` and `make variation` on the capture sets named in
//! docs/CLUSTER.md (`scripts/slurm-measure` repeats the measurement), with a margin: memory
//! ×1.5 rounded up to 50 MB, CPUs the ceiling of the CPU share.

/// CPUs and memory (MB) of one task.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resources {
    pub cpus: u32,
    pub mem_mb: u32,
}

/// The needs of one task of `kind`.
pub fn for_kind(kind: &str) -> Resources {
    let (cpus, mem_mb) = match kind {
        "segment" => (1, 100),
        "align" => (2, 150),
        "pca-fit" => (2, 300),
        "dtw-densify" => (1, 150),
        "gpr-train" => (2, 200),
        "gpr-predict" => (2, 400),
        "evaluate" => (1, 150),
        "render" => (2, 200),
        "paper-figure" => (2, 300),
        "learning-curves" => (2, 300),
        "prealign" => (2, 300),
        "gpdm-train" => (2, 300),
        "hmc-sample" => (2, 400),
        "variation-eval" => (2, 300),
        "collect" => (1, 50),
        _ => (1, 500),
    };
    Resources { cpus, mem_mb }
}
