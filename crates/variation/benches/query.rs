//! Speed goal (docs/PERFORMANCE.md, "One query in the stage"): one `hmc-sample` query of 10
//! variations x 100 frames of the demo body in <= 1 s on 2 cores, end to end in the stage
//! (`variation::stage::hmc_sample::run`: both artifacts read and checked, decoder set up,
//! exact ancestral draws, fused decoding, DTW correspondence, grounding, foot clean-ups, 1,000
//! PLY files written and flushed to disk). Only process start-up is outside the timing.
//!
//! Needs a trained demo model: `make variation` (or `prealign` + `gpdm-train` of the demo set's
//! locomotion group) writes `out/work/variation/locomotion.{group,model}`; other paths through
//! `SURFCAP_QUERY_MODEL` and `SURFCAP_QUERY_GROUP`. Without them the bench says so and measures
//! nothing. The frames go to a temporary folder under `SURFCAP_QUERY_OUT` (default: the system
//! temporary folder; a tmpfs such as /dev/shm separates the disk flush from the computation).
//! Cases: the query as a user runs it, and with `--report` (the statistics of the pipeline).
//! Run: `scripts/bench variation:query`.

use std::path::PathBuf;

use clap::Parser;
use criterion::{criterion_group, criterion_main, Criterion};
use variation::stage::hmc_sample::{run, Params};

fn input(var: &str, default: &str) -> PathBuf {
    std::env::var_os(var).map_or_else(|| PathBuf::from(default), PathBuf::from)
}

fn query(c: &mut Criterion) {
    let model = input("SURFCAP_QUERY_MODEL", "out/work/variation/locomotion.model");
    let group = input("SURFCAP_QUERY_GROUP", "out/work/variation/locomotion.group");
    // Benches run in the crate's folder: paths are taken from the workspace root.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let (model, group) = (root.join(model), root.join(group));
    if !model.is_file() || !group.is_file() {
        eprintln!(
            "query: {} or {} missing (run `make variation`, or set SURFCAP_QUERY_MODEL and SURFCAP_QUERY_GROUP): nothing measured",
            model.display(),
            group.display()
        );
        return;
    }
    let base = std::env::var_os("SURFCAP_QUERY_OUT").map_or_else(std::env::temp_dir, PathBuf::from);
    let tmp = tempfile::tempdir_in(base).expect("a temporary output folder");
    let motion = std::env::var("SURFCAP_QUERY_MOTION").unwrap_or_else(|_| "walk".into());
    let params = |report: bool| {
        let mut args: Vec<String> = [
            "hmc-sample", "-q", "--model", &model.to_string_lossy(), "--group",
            &group.to_string_lossy(), "--motion", &motion, "-n", "10", "--frame-count", "100",
            "--sampler", "ancestral", "--seed", "0", "--out",
            &tmp.path().join("q").to_string_lossy(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        if report {
            args.extend(["--report".into(), tmp.path().join("q.json").to_string_lossy().into_owned()]);
        }
        Params::parse_from(args)
    };
    let (plain, with_report) = (params(false), params(true));
    plain.common.init().expect("stage set-up");
    let mut g = c.benchmark_group("hmc-sample query 10 x 100 frames, demo body");
    g.sample_size(10);
    g.bench_function("meshes", |b| b.iter(|| run(&plain).expect("query")));
    g.bench_function("meshes + --report", |b| b.iter(|| run(&with_report).expect("query")));
    g.finish();
}

criterion_group!(benches, query);
criterion_main!(benches);
