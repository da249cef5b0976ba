//! Helpers shared by the comparison binaries (`gpr_compare`, `sgpr_compare`).
#![allow(dead_code)]
use gp::kernel::Kernel;
use nalgebra::DMatrix;
use std::io::Write;

pub fn write_csv(path: &std::path::Path, m: &DMatrix<f64>) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    for r in m.row_iter() {
        let line: Vec<String> = r.iter().map(|v| format!("{v:.17e}")).collect();
        writeln!(f, "{}", line.join(","))?;
    }
    Ok(())
}

/// CPU time (user + system, all threads) of this process in seconds, from /proc/self/stat
/// (Linux; NaN elsewhere): the machine is shared, so wall time alone misleads.
pub fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse().ok())
        .collect();
    if f.len() == 2 {
        (f[0] + f[1]) / 100.0 // USER_HZ is 100 on Linux
    } else {
        f64::NAN
    }
}

/// CPU time of the calling thread in seconds (`clock_gettime(CLOCK_THREAD_CPUTIME_ID)`, to the
/// nanosecond; NaN if the clock fails): exact for one model trained on one thread, where
/// [`cpu_seconds`]'s 10 ms ticks are too coarse. (`/proc/thread-self/schedstat` is only brought
/// up to date at scheduler events: it read 0 for a 3.5 ms training run.)
pub fn thread_cpu_seconds() -> f64 {
    let mut t = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `t` is a valid, writable timespec for the duration of the call.
    if unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) } == 0 {
        t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
    } else {
        f64::NAN
    }
}

pub fn l_sf(k: &Kernel) -> (f64, f64) {
    match *k {
        Kernel::NeuralNetwork { l, sigma_f, .. } | Kernel::SquaredExponential { l, sigma_f } => {
            (l, sigma_f)
        }
        Kernel::Linear { sigma_f } => (f64::NAN, sigma_f),
    }
}

/// Peak resident set size of this process in MiB (`VmHWM` in /proc/self/status; NaN elsewhere).
pub fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse::<f64>().ok()))
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// The conjugate-gradient settings the GP timing programs can override (`gp::optim::CgOptions`;
/// absent: the library's defaults).
#[derive(clap::Args, Debug)]
pub struct CgArgs {
    /// Relative gradient tolerance of the stopping rule.
    #[arg(long)]
    pub grad_tol: Option<f64>,
    /// Curvature constant of the line search's Wolfe conditions.
    #[arg(long)]
    pub c2: Option<f64>,
    /// Largest step of the line search.
    #[arg(long)]
    pub max_step: Option<f64>,
}

impl CgArgs {
    /// `cg` with the settings given on the command line.
    pub fn apply(&self, cg: &mut gp::optim::CgOptions) {
        if let Some(v) = self.grad_tol {
            cg.grad_tol = v;
        }
        if let Some(v) = self.c2 {
            cg.c2 = v;
        }
        if let Some(v) = self.max_step {
            cg.max_step = v;
        }
    }
}
