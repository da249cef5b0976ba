//! Writes a Poisson problem and its solution for `scripts/compare/poisson_libigl.py`.
//!
//! `cargo build --release -p studies --bin poisson_export` builds it; run
//! `target/release/poisson_export <dir>`. Problem: rest mesh `V`, `F`
//! (`mesh_core::shapes::capsule_body(170, 64, ...)`, 12 930 vertices); target gradients
//! `J = G X` of a deformed pose `X` on the rest geometry; Dirichlet vertices `fixed` held at
//! `X`. Files (text, 17 significant digits): V.txt, F.txt, X.txt, fixed.txt, solution.txt,
//! timing.json (seconds: symbolic+numeric factorisation, one 3-column solve).

use clap::Parser;
use mesh_core::shapes::capsule_body;
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::time::Instant;
use surface::deformation_gradient::GradientOperator;
use surface::poisson::PoissonSolver;

fn write_rows<const N: usize>(path: &std::path::Path, rows: impl Iterator<Item = [String; N]>) {
    let mut s = String::new();
    for r in rows {
        writeln!(s, "{}", r.join(" ")).unwrap();
    }
    std::fs::write(path, s).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// Writes a Poisson problem and its solution for scripts/compare/poisson_libigl.py.
#[derive(Parser)]
struct Cli {
    /// The output folder.
    dir: std::path::PathBuf,
}

fn main() {
    let dir = Cli::parse().dir;
    std::fs::create_dir_all(&dir).expect("output directory");
    let (mesh, _) = capsule_body(170, 64, 1.0, 17.0);
    let (v, f) = (&mesh.vertices, &mesh.faces);
    let x: Vec<Vector3<f64>> = v
        .iter()
        .map(|p| {
            p + Vector3::new(
                0.3 * (0.4 * p.y).sin(),
                0.05 * p.x * p.y,
                0.2 * (0.7 * p.y).cos(),
            )
        })
        .collect();
    let fixed: Vec<usize> = vec![0, v.len() / 2, v.len() - 1];
    let op = GradientOperator::new(v, f);
    let rhs = op.divergence(&op.gradient(&x));
    let l = op.stiffness();
    let t0 = Instant::now();
    let solver = PoissonSolver::new(&l, &fixed).expect("factorisation");
    let t1 = Instant::now();
    let sol = solver
        .solve(&rhs, &fixed.iter().map(|&i| x[i]).collect::<Vec<_>>())
        .expect("solve");
    let t2 = Instant::now();
    let e = |a: f64| format!("{a:.17e}");
    write_rows(
        &dir.join("V.txt"),
        v.iter().map(|p| [e(p.x), e(p.y), e(p.z)]),
    );
    write_rows(
        &dir.join("X.txt"),
        x.iter().map(|p| [e(p.x), e(p.y), e(p.z)]),
    );
    write_rows(
        &dir.join("solution.txt"),
        sol.iter().map(|p| [e(p.x), e(p.y), e(p.z)]),
    );
    write_rows(
        &dir.join("F.txt"),
        f.iter().map(|t| t.map(|i| i.to_string())),
    );
    write_rows(
        &dir.join("fixed.txt"),
        fixed.iter().map(|i| [i.to_string()]),
    );
    let timing = format!(
        "{{\"factor_s\": {}, \"solve_s\": {}, \"n_vertices\": {}}}\n",
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
        v.len()
    );
    std::fs::write(dir.join("timing.json"), timing).expect("timing.json");
}
