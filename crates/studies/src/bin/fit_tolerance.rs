//! Where `gpdm-train`'s objective evaluations go: the group fitted with the default settings
//! at several value tolerances (`LbfgsOptions::value_tol`, the relative decrease per iteration
//! over the 10-iteration window below which the fit stops), each part fitted alone on one
//! thread (wall seconds: its cost on one core when the machine is quiet), then 3DV fig. 4 (reconstruction) and
//! fig. 7b (guided blend) of each model (`variation::evaluate`).
//!
//! Usage: fit_tolerance GROUP [TOL[:MAX_ITER] ...]   (default tolerances 1e-10 1e-8 1e-7, the
//! default iteration limit)
//! e.g.: OPENBLAS_NUM_THREADS=1 target/release/fit_tolerance out/work/variation/locomotion.group

use clap::Parser;
use mesh_core::artifact::Artifact;
use variation::group::Group;
use variation::train::{train, TrainConfig};

/// The group fitted with the default settings at several value tolerances, each part alone on
/// one thread, then 3DV figs. 4 and 7b of each model.
#[derive(Parser)]
struct Cli {
    /// The prealigned group (prealign's output).
    group: String,
    /// Value tolerances, each optionally with an iteration limit, `TOL[:MAX_ITER]` [default:
    /// 1e-10 1e-8 1e-7 at the default iteration limit].
    settings: Vec<String>,
}

fn main() {
    let cli = Cli::parse();
    let group = Group::load(&cli.group).unwrap_or_else(|e| panic!("{e}"));
    let max_iter = TrainConfig::default().options.lbfgs.max_iter;
    let settings: Vec<(f64, usize)> = match cli.settings.len() {
        0 => [1e-10, 1e-8, 1e-7].map(|t| (t, max_iter)).to_vec(),
        _ => cli
            .settings
            .iter()
            .map(|a| match a.split_once(':') {
                Some((t, n)) => (t.parse().expect("a tolerance"), n.parse().expect("an iteration limit")),
                None => (a.parse().expect("a tolerance"), max_iter),
            })
            .collect(),
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    for (tol, max_iter) in settings {
        let mut cfg = TrainConfig::default();
        cfg.options.lbfgs.value_tol = tol;
        cfg.options.lbfgs.max_iter = max_iter;
        let (model, reports) = pool.install(|| train(&group, &cfg)).unwrap_or_else(|e| panic!("{e}"));
        for r in &reports {
            println!(
                "tol {tol:e} max {max_iter} {:>6}: N {} evaluations {:>5} seconds {:>6.2} ({:.2} ms each) objective {:.6e}",
                r.part,
                r.frames,
                r.report.evaluations,
                r.seconds,
                1e3 * r.seconds / r.report.evaluations.max(1) as f64,
                r.report.final_value
            );
        }
        let (ev, _) = variation::evaluate::evaluate(&model, &group, false, 0).unwrap_or_else(|e| panic!("{e}"));
        let blends: Vec<String> = ev
            .latent_blend
            .iter()
            .map(|b| format!("w {} guided {:.3} mm unguided {:.3} mm", b.w, 1e3 * b.guided_m, 1e3 * b.unguided_m))
            .collect();
        println!(
            "tol {tol:e} max {max_iter} fig. 4 reconstruction GPDM {:.3} mm (PCA {:.3} mm); fig. 7b {}",
            1e3 * ev.reconstruction_gpdm_m,
            1e3 * ev.reconstruction_pca_m,
            blends.join("; ")
        );
    }
}
