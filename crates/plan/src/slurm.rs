//! The task graph as Slurm batch scripts: one job array per stage kind (a task table, one line
//! per array task, see [`crate::task_table`]), each array submitted with
//! `--dependency=afterok` on the arrays whose outputs it reads, and a top script `run.sbatch`
//! that submits them all. Every task logs to `slurm/logs/<kind>/<index>.log`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use crate::resources::Table;
use crate::task::{Graph, Task};

/// The stage kinds in submission order (each after every kind it reads from) with their tasks.
pub fn arrays(graph: &Graph) -> Result<Vec<(String, Vec<&Task>, BTreeSet<String>)>> {
    let producer: BTreeMap<&str, &str> =
        graph.tasks.iter().map(|t| (t.target.as_str(), t.kind.as_str())).collect();
    let mut kinds: Vec<String> = Vec::new();
    let mut deps: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for t in &graph.tasks {
        if !kinds.contains(&t.kind) {
            kinds.push(t.kind.clone());
        }
        let d = deps.entry(t.kind.clone()).or_default();
        for i in &t.inputs {
            if let Some(&k) = producer.get(i.as_str()) {
                if k == t.kind {
                    bail!("task {} reads {i}, written by a task of its own kind {k}: one array cannot hold both", t.target);
                }
                d.insert(k.to_string());
            }
        }
    }
    // Kahn's algorithm, taking kinds in their first-appearance order when several are ready.
    let mut done: Vec<String> = Vec::new();
    while done.len() < kinds.len() {
        let next = kinds
            .iter()
            .find(|k| !done.contains(k) && deps[*k].iter().all(|d| done.contains(d)))
            .cloned();
        match next {
            Some(k) => done.push(k),
            None => bail!("the stage kinds depend on each other in a cycle"),
        }
    }
    Ok(done
        .into_iter()
        .map(|k| {
            let tasks = graph.tasks.iter().filter(|t| t.kind == k).collect();
            let d = deps.remove(&k).unwrap_or_default();
            (k, tasks, d)
        })
        .collect())
}

fn var(kind: &str) -> String {
    kind.replace('-', "_")
}

/// Where the scripts go and what they run.
pub struct Layout {
    /// The directory jobs start in (the pipelines' paths are relative to it).
    pub workdir: PathBuf,
    /// The stage binaries.
    pub bin: PathBuf,
    /// `run.sbatch` goes here; arrays, tables and logs under `<out>/slurm/`.
    pub out: PathBuf,
    /// CPUs and memory per stage.
    pub resources: Table,
}

/// Every file to write: `(path, text)`.
pub fn scripts(graph: &Graph, layout: &Layout) -> Result<Vec<(PathBuf, String)>> {
    let dir = layout.out.join("slurm");
    let q = |p: &Path| crate::make_fragment::shell_quote(&p.to_string_lossy());
    let mut files = Vec::new();
    let mut run = format!(
        "#!/bin/bash\n\
         #SBATCH --job-name=surfcap-run\n\
         #SBATCH --cpus-per-task=1\n\
         #SBATCH --mem=50M\n\
         #SBATCH --chdir={wd}\n\
         #SBATCH --output={log}\n\
         # Written by `plan slurm`: submits one job array per stage kind, each after the arrays\n\
         # whose outputs it reads. Task i of array K runs line i of slurm/K.tasks.\n\
         set -euo pipefail\n",
        wd = q(&layout.workdir),
        log = q(&dir.join("logs").join("run.log")),
    );
    let mut ids = Vec::new();
    for (kind, tasks, deps) in arrays(graph)? {
        let table = dir.join(format!("{kind}.tasks"));
        files.push((table.clone(), crate::task_table::write_table(&tasks)?));
        // The array's request covers its most demanding task.
        let bins: Vec<&str> = tasks.iter().flat_map(|t| t.bins()).collect();
        let r = layout.resources.for_bins(&bins);
        let script = dir.join(format!("{kind}.sbatch"));
        files.push((
            script.clone(),
            format!(
                "#!/bin/bash\n\
                 #SBATCH --job-name=surfcap-{kind}\n\
                 #SBATCH --array=0-{last}\n\
                 #SBATCH --cpus-per-task={cpus}\n\
                 #SBATCH --mem={mem}M\n\
                 #SBATCH --chdir={wd}\n\
                 #SBATCH --output={log}\n\
                 exec {plan} run-task -v --bin {bin} --table {table} --task \"$SLURM_ARRAY_TASK_ID\"\n",
                last = tasks.len() - 1,
                cpus = r.cpus,
                mem = r.mem_mb,
                wd = q(&layout.workdir),
                log = q(&dir.join("logs").join(&kind).join("%a.log")),
                plan = q(&layout.bin.join("plan")),
                bin = q(&layout.bin),
                table = q(&table),
            ),
        ));
        let after: Vec<String> = deps.iter().map(|d| format!("${}", var(d))).collect();
        let dep = if after.is_empty() {
            String::new()
        } else {
            format!(" --dependency=afterok:{}", after.join(":"))
        };
        run.push_str(&format!("{}=$(sbatch --parsable{dep} {})\n", var(&kind), q(&script)));
        ids.push(format!("{kind}=${}", var(&kind)));
    }
    // The job ids, one `kind=id` per line, for whoever waits on the run.
    run.push_str(&format!("printf '%s\\n' {} > {}\n", ids.join(" "), q(&dir.join("jobs"))));
    files.push((layout.out.join("run.sbatch"), run));
    Ok(files)
}

/// The log directories the scripts name (Slurm does not create them).
pub fn log_dirs(graph: &Graph, layout: &Layout) -> Vec<PathBuf> {
    let logs = layout.out.join("slurm").join("logs");
    let mut dirs = vec![logs.clone()];
    let mut kinds: Vec<&str> = graph.tasks.iter().map(|t| t.kind.as_str()).collect();
    kinds.sort();
    kinds.dedup();
    dirs.extend(kinds.into_iter().map(|k| logs.join(k)));
    dirs
}
