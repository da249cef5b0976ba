//! Variants of the limb orientation map, scored on the raw transfer (parts assembled, no §6)
//! of every test motion of a run (docs/studies/06-limb-orientation.md). `LogRotation Count(0.5)
//! w0.5` is
//! the default (`transfer::limb_orientation`).
//!
//! cargo run --release -p studies --bin limb_map_study -- WORK SET SOURCE TARGET MOTION... -- TRAIN...
//! e.g. `limb_map_study out/demo-run/work out/demo/set A B punch spinkick cmu_jump -- walk run jump kick dance`
//! (after `make transfer`; the pairs are read in the set's order, reversed when SOURCE is the set's target).
//! With `--only-all` only the default and the all-limbs rows run; with `--sweep` the ridge and
//! weight sweep of the log-rotation map, measured from the PCA mean, from a canonical pose, with
//! second-order terms and in the attachment's frame (`Chest`, the share of root vertices
//! `--chest-share`, default 0.2; only on parts whose name holds `--chest-parts`; the target's
//! attachment from its pose GP, or with `--chest-target source` the source's, `mid` half way).
//! `--true-pairs` trains on the set's true correspondences.

use studies::study_pairs;

use clap::{Parser, ValueEnum};

use capture::assemble::{assemble, plan};
use capture::part_pca::PcaModel;
use mesh_core::rigid::{so3_exp, so3_log};
use mesh_core::sequence::MeshSequence;
use nalgebra::{DMatrix, Rotation3, Unit, Vector3};
use transfer::gpr_model::training_set;
use transfer::limb_orientation::{attachment, limbs, orientation, orientations, reference, turn_to, Limb, LimbMap};

#[derive(Clone, Copy, Debug)]
enum Space {
    /// Affine map of log-rotations (the default).
    LogRotation,
    /// Affine map of the limb's axis direction; the GP's twist is kept.
    Axis,
    /// The affine map of log-rotations plus a squared-exponential GP on its residuals.
    LogRotationGp,
    /// An affine map from every source limb's log-rotation (the limb's own shrunk toward the
    /// identity, the others toward zero) to the target limb's.
    AllLimbs,
    /// The affine map of log-rotations measured from a canonical pose of each body's limb: its
    /// mean shape turned by the shortest arc that points its axis straight down (-y).
    Canonical,
    /// Log-rotations with their second-order terms as the map's inputs (shrunk toward the
    /// identity on the linear terms, toward zero on the others).
    Quadratic,
    /// The affine map of log-rotations relative to the torso's region next to the limb's joint
    /// (the chest for an arm, the pelvis for a leg), the target's region as its pose GP predicts it.
    Chest,
}

#[derive(Clone, Copy, Debug)]
enum Proximal {
    /// The share of vertices nearest the joint.
    Count(f64),
    /// The vertices within this share of the largest joint distance.
    Length(f64),
}

#[derive(Clone, Copy, Debug)]
struct Variant {
    space: Space,
    proximal: Proximal,
    ridge: f64,
    weight: f64,
}

fn points(flat: &[f64]) -> Vec<Vector3<f64>> {
    flat.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect()
}

fn centroid(p: impl Iterator<Item = Vector3<f64>>) -> Vector3<f64> {
    let (s, n) = p.fold((Vector3::zeros(), 0), |(s, n), q| (s + q, n + 1));
    s / n.max(1) as f64
}

fn with_proximal(limb: &Limb, mean: &[Vector3<f64>], proximal: Proximal) -> Limb {
    let pivot = centroid(limb.joint.iter().map(|&i| mean[i]));
    let mut d: Vec<(f64, usize)> = mean.iter().enumerate().map(|(i, p)| ((p - pivot).norm(), i)).collect();
    d.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let keep: Vec<usize> = match proximal {
        Proximal::Count(s) => d.iter().take(((mean.len() as f64) * s).ceil() as usize).map(|x| x.1).collect(),
        Proximal::Length(s) => {
            let max = d.last().unwrap().0;
            d.iter().filter(|x| x.0 <= s * max).map(|x| x.1).collect()
        }
    };
    let mut keep = keep;
    keep.sort_unstable();
    Limb { part: limb.part, joint: limb.joint.clone(), proximal: keep }
}

/// The limb's axis in its mean shape: joint centroid to proximal centroid.
fn axis(limb: &Limb, mean: &[Vector3<f64>]) -> Vector3<f64> {
    let j = centroid(limb.joint.iter().map(|&i| mean[i]));
    let p = centroid(limb.proximal.iter().map(|&i| mean[i]));
    (p - j).normalize()
}

/// The feature of one frame's limb in `space`.
fn feature(space: Space, r: &Rotation3<f64>, a: &Vector3<f64>) -> Vector3<f64> {
    match space {
        Space::LogRotation | Space::LogRotationGp | Space::AllLimbs | Space::Quadratic | Space::Chest => so3_log(r),
        Space::Axis => r * a,
        Space::Canonical => so3_log(&(r * canonical(a).inverse())),
    }
}

fn features(pca: &PcaModel, limb: &Limb, coeffs: &DMatrix<f64>, space: Space) -> Vec<Vector3<f64>> {
    let part = &pca.parts[limb.part];
    let rows = part.pca.decode(coeffs).unwrap();
    let mean = reference(pca, limb.part);
    let a = axis(limb, &mean);
    (0..rows.nrows())
        .map(|r| {
            let row: Vec<f64> = rows.row(r).iter().copied().collect();
            feature(space, &orientation(&mean, &points(&row), &limb.proximal), &a)
        })
        .collect()
}

/// The turn of a limb's mean shape, of axis `a`, to its canonical pose (axis straight down).
fn canonical(a: &Vector3<f64>) -> Rotation3<f64> {
    arc(a, &-Vector3::y())
}

/// The rotation taking unit `from` to unit `to` by the shortest arc.
fn arc(from: &Vector3<f64>, to: &Vector3<f64>) -> Rotation3<f64> {
    Rotation3::rotation_between(from, to).unwrap_or_else(|| {
        let perp = from.cross(&Vector3::x()).try_normalize(1e-9).unwrap_or_else(|| from.cross(&Vector3::y()).normalize());
        Rotation3::from_axis_angle(&Unit::new_normalize(perp), std::f64::consts::PI)
    })
}

fn slerp(a: &Vector3<f64>, b: &Vector3<f64>, w: f64) -> Vector3<f64> {
    let r = arc(a, b);
    so3_exp(&(w * so3_log(&r))) * a
}

/// Ridge least squares `[x, 1] W = y` over the rows of `x` (`d` inputs), shrunk toward `w0`
/// with `λ = ridge ×` the mean diagonal of the normal equations.
fn fit_wide(x: &DMatrix<f64>, y: &DMatrix<f64>, w0: &DMatrix<f64>, ridge: f64) -> DMatrix<f64> {
    let n = x.nrows();
    let x1 = DMatrix::from_fn(n, x.ncols() + 1, |r, c| if c < x.ncols() { x[(r, c)] } else { 1.0 });
    let xtx = x1.transpose() * &x1;
    let lambda = ridge * xtx.trace() / xtx.nrows() as f64;
    let lhs = &xtx + DMatrix::identity(xtx.nrows(), xtx.nrows()) * lambda;
    let rhs = x1.transpose() * y + w0 * lambda;
    lhs.cholesky().expect("positive definite").solve(&rhs)
}

/// Turns each frame's limb the geodesic share `weight` of the way from its orientation toward
/// `mapped(frame index)`.
fn turn_toward(frames: &mut [Vec<Vector3<f64>>], limb: &Limb, mean: &[Vector3<f64>], weight: f64, mapped: impl Fn(usize) -> Rotation3<f64>) {
    for (fi, frame) in frames.iter_mut().enumerate() {
        let now = orientation(mean, frame, &limb.proximal);
        let want = now * so3_exp(&(weight * so3_log(&(now.inverse() * mapped(fi)))));
        turn_to(frame, limb, &now, &want);
    }
}

/// The orientation of the root part's `near` vertices in each decoded frame of `coeffs`.
fn root_orientations(pca: &PcaModel, near: &[usize], coeffs: &DMatrix<f64>) -> Vec<Rotation3<f64>> {
    orientations(&pca.parts[0], near, coeffs).unwrap()
}

fn root_orientations_of(pca: &PcaModel, near: &[usize], frames: &[Vec<Vector3<f64>>]) -> Vec<Rotation3<f64>> {
    let mean = reference(pca, 0);
    frames.iter().map(|f| orientation(&mean, f, near)).collect()
}

/// Variants of the limb orientation map scored on the raw transfer (parts assembled, no §6) of
/// every test motion (docs/studies/06-limb-orientation.md).
#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    study: study_pairs::StudyArgs,
    /// Runs the ridge and weight sweep of the log-rotation map (from the PCA mean, from a
    /// canonical pose, with second-order terms, in the attachment's frame) in place of the
    /// default variants.
    #[arg(long)]
    sweep: bool,
    /// Runs only the default and the all-limbs rows.
    #[arg(long)]
    only_all: bool,
    /// The attachment-frame (`Chest`) variant only on parts whose name holds this [default: every part].
    #[arg(long)]
    chest_parts: Option<String>,
    /// The share of root vertices nearest the joint that make the attachment region.
    #[arg(long, default_value_t = 0.2)]
    chest_share: f64,
    /// The target's attachment in the `Chest` variant.
    #[arg(long, value_enum, default_value_t = ChestTarget::Predicted)]
    chest_target: ChestTarget,
}

/// Where the `Chest` variant takes the target's attachment orientation from.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum ChestTarget {
    /// The target's pose GP.
    Predicted,
    /// The source's attachment.
    Source,
    /// Half way between the two.
    Mid,
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let study = study_pairs::Study::open(&cli.study)?;
    let study_pairs::Study { work, set, s, t, tests, train, spca, tpca, model, template, true_pairs } = &study;
    let (pairs, _) = study_pairs::load(work, set, s, t, &spca, &tpca, train, *true_pairs)?;
    let rows = training_set(&pairs, 1.0, false)?;
    let plan = plan(&tpca)?;

    let mut variants = vec![];
    for space in [Space::LogRotation, Space::Axis] {
        for proximal in [Proximal::Count(0.5), Proximal::Length(0.5), Proximal::Length(0.35)] {
            for weight in [0.5, 1.0] {
                variants.push(Variant { space, proximal, ridge: 0.1, weight });
            }
        }
    }
    for weight in [0.5, 1.0] {
        variants.push(Variant { space: Space::LogRotationGp, proximal: Proximal::Count(0.5), ridge: 0.1, weight });
    }
    for ridge in [0.1, 0.01] {
        for weight in [0.5, 1.0] {
            variants.push(Variant { space: Space::AllLimbs, proximal: Proximal::Count(0.5), ridge, weight });
        }
    }
    if cli.sweep {
        variants.clear();
        for space in [Space::LogRotation, Space::Canonical, Space::Quadratic, Space::Chest] {
            for ridge in [0.1, 0.01, 0.001] {
                for weight in [0.5, 0.75, 1.0] {
                    variants.push(Variant { space, proximal: Proximal::Count(0.5), ridge, weight });
                }
            }
        }
    }
    if cli.only_all {
        variants.retain(|v| matches!(v.space, Space::AllLimbs) || (matches!(v.space, Space::LogRotation) && matches!(v.proximal, Proximal::Count(_)) && v.weight == 0.5));
    }
    let (ls, lt) = (limbs(&spca)?, limbs(&tpca)?);
    let mut totals = vec![(0.0f64, 0usize); variants.len() + 1];
    for m in tests {
        let study_pairs::TestMotion { xs, xd, truth: truth_seq } = study.test_motion(m)?;
        let gp = tpca.decode(&transfer::predict::predict(&model, &xs, &xd, false)?.coeffs)?;
        let score = |parts: &Vec<Vec<Vec<Vector3<f64>>>>| -> f64 {
            let pred = MeshSequence::new(template.faces.clone(), assemble(&plan, &tpca, parts));
            transfer::evaluate::rms_errors(&pred, &truth_seq).unwrap().0
        };
        let base = score(&gp);
        let f = gp[0].len() as f64;
        totals[0].0 += base * base * f;
        totals[0].1 += gp[0].len();
        print!("{s}->{t} {m}: GP {:.2}", 100.0 * base);
        for (vi, v) in variants.iter().enumerate() {
            let mut turned = gp.clone();
            for (sl, tl) in ls.iter().zip(&lt) {
                let k = sl.part;
                let (smean, tmean) = (reference(&spca, k), reference(&tpca, k));
                let (sl, tl) = (with_proximal(sl, &smean, v.proximal), with_proximal(tl, &tmean, v.proximal));
                let xf = features(&spca, &sl, &rows.x_parts[k], v.space);
                let yf = features(&tpca, &tl, &rows.y_parts[k], v.space);
                let map = LimbMap::fit(&xf, &yf, v.ridge)?;
                let chest_here = cli.chest_parts.as_ref().is_none_or(|f| tpca.parts[k].name.contains(f.as_str()));
                if matches!(v.space, Space::Chest) && chest_here {
                    let share = cli.chest_share;
                    let (ns, nt) = (attachment(&spca, 0, &sl, share), attachment(&tpca, 0, &tl, share));
                    let rel = |roots: &[Rotation3<f64>], f: &[Vector3<f64>]| -> Vec<Vector3<f64>> {
                        roots.iter().zip(f).map(|(c, x)| so3_log(&(c.inverse() * so3_exp(x)))).collect()
                    };
                    let xr = rel(&root_orientations(&spca, &ns, &rows.x_parts[0]), &xf);
                    let yr = rel(&root_orientations(&tpca, &nt, &rows.y_parts[0]), &yf);
                    let map = LimbMap::fit(&xr, &yr, v.ridge)?;
                    let src = features(&spca, &sl, &xs[k], v.space);
                    let chest_s = root_orientations(&spca, &ns, &xs[0]);
                    let src = rel(&chest_s, &src);
                    let chest_t = match cli.chest_target {
                        ChestTarget::Source => chest_s.clone(),
                        ChestTarget::Mid => root_orientations_of(&tpca, &nt, &gp[0]).iter().zip(&chest_s).map(|(g, c)| g * so3_exp(&(0.5 * so3_log(&(g.inverse() * c))))).collect(),
                        ChestTarget::Predicted => root_orientations_of(&tpca, &nt, &gp[0]),
                    };
                    turn_toward(&mut turned[k], &tl, &tmean, v.weight, |fi| chest_t[fi] * so3_exp(&map.apply(&src[fi])));
                    continue;
                }
                if let Space::Quadratic = v.space {
                    let quad = |f: &[Vector3<f64>]| {
                        DMatrix::from_fn(f.len(), 9, |r, c| {
                            let x = f[r];
                            match c {
                                0..=2 => x[c],
                                3 => x.x * x.x,
                                4 => x.y * x.y,
                                5 => x.z * x.z,
                                6 => x.x * x.y,
                                7 => x.x * x.z,
                                _ => x.y * x.z,
                            }
                        })
                    };
                    let mut w0 = DMatrix::zeros(10, 3);
                    for i in 0..3 {
                        w0[(i, i)] = 1.0;
                    }
                    let w = fit_wide(&quad(&xf), &DMatrix::from_fn(yf.len(), 3, |r, c| yf[r][c]), &w0, v.ridge);
                    let src = features(&spca, &sl, &xs[k], v.space);
                    let xt = quad(&src);
                    let xt1 = DMatrix::from_fn(xt.nrows(), 10, |r, c| if c < 9 { xt[(r, c)] } else { 1.0 });
                    let pred = xt1 * w;
                    turn_toward(&mut turned[k], &tl, &tmean, v.weight, |fi| so3_exp(&Vector3::new(pred[(fi, 0)], pred[(fi, 1)], pred[(fi, 2)])));
                    continue;
                }
                if let Space::AllLimbs = v.space {
                    // Inputs: every source limb's log-rotation, training rows and this motion's.
                    let wide = |coeffs: &dyn Fn(usize) -> DMatrix<f64>| -> DMatrix<f64> {
                        let cols: Vec<Vec<Vector3<f64>>> = ls
                            .iter()
                            .map(|l| {
                                let m = reference(&spca, l.part);
                                features(&spca, &with_proximal(l, &m, v.proximal), &coeffs(l.part), v.space)
                            })
                            .collect();
                        DMatrix::from_fn(cols[0].len(), 3 * cols.len(), |r, c| cols[c / 3][r][c % 3])
                    };
                    let xw = wide(&|p| rows.x_parts[p].clone());
                    let yw = DMatrix::from_fn(yf.len(), 3, |r, c| yf[r][c]);
                    let own = ls.iter().position(|l| l.part == k).unwrap();
                    let mut w0 = DMatrix::zeros(xw.ncols() + 1, 3);
                    for i in 0..3 {
                        w0[(3 * own + i, i)] = 1.0;
                    }
                    let w = fit_wide(&xw, &yw, &w0, v.ridge);
                    let xt = wide(&|p| xs[p].clone());
                    let xt1 = DMatrix::from_fn(xt.nrows(), xt.ncols() + 1, |r, c| if c < xt.ncols() { xt[(r, c)] } else { 1.0 });
                    let pred = xt1 * w;
                    turn_toward(&mut turned[k], &tl, &tmean, v.weight, |fi| so3_exp(&Vector3::new(pred[(fi, 0)], pred[(fi, 1)], pred[(fi, 2)])));
                    continue;
                }
                let to_matrix = |f: &[Vector3<f64>]| DMatrix::from_fn(f.len(), 3, |r, c| f[r][c]);
                let residual_gp = match v.space {
                    Space::LogRotationGp => {
                        let resid: Vec<Vector3<f64>> = xf.iter().zip(&yf).map(|(x, y)| y - map.apply(x)).collect();
                        let opts = gp::gpr::GprOptions { learn_noise: true, noise_var: 1e-3, ..Default::default() };
                        let (g, _) = gp::gpr::Gpr::train(
                            gp::kernel::Kernel::SquaredExponential { l: 0.3, sigma_f: 0.1 },
                            &to_matrix(&xf),
                            &to_matrix(&resid),
                            &opts,
                        )?;
                        Some(g)
                    }
                    _ => None,
                };
                let src = features(&spca, &sl, &xs[k], v.space);
                let src_resid = match &residual_gp {
                    Some(g) => Some(g.predict_mean(&to_matrix(&src))?),
                    None => None,
                };
                let ta = axis(&tl, &tmean);
                for (fi, (frame, x)) in turned[k].iter_mut().zip(&src).enumerate() {
                    let now = orientation(&tmean, frame, &tl.proximal);
                    let want = match v.space {
                        Space::Canonical => {
                            let mapped = so3_exp(&map.apply(x)) * canonical(&ta);
                            now * so3_exp(&(v.weight * so3_log(&(now.inverse() * mapped))))
                        }
                        Space::LogRotation | Space::LogRotationGp | Space::AllLimbs | Space::Quadratic | Space::Chest => {
                            let extra = src_resid.as_ref().map_or(Vector3::zeros(), |r| Vector3::new(r[(fi, 0)], r[(fi, 1)], r[(fi, 2)]));
                            let mapped = so3_exp(&(map.apply(x) + extra));
                            now * so3_exp(&(v.weight * so3_log(&(now.inverse() * mapped))))
                        }
                        Space::Axis => {
                            let d_gp = now * ta;
                            let d_map = map.apply(x).normalize();
                            let d_want = slerp(&d_gp, &d_map, v.weight);
                            arc(&d_gp, &d_want) * now
                        }
                    };
                    turn_to(frame, &tl, &now, &want);
                }
            }
            let e = score(&turned);
            totals[vi + 1].0 += e * e * f;
            totals[vi + 1].1 += gp[0].len();
            print!(" | {:?} {:?} w{} {:.2}", v.space, v.proximal, v.weight, 100.0 * e);
        }
        println!();
    }
    print!("pooled: GP {:.3}", 100.0 * (totals[0].0 / totals[0].1 as f64).sqrt());
    for (vi, v) in variants.iter().enumerate() {
        print!(" | {:?} {:?} r{} w{} {:.3}", v.space, v.proximal, v.ridge, v.weight, 100.0 * (totals[vi + 1].0 / totals[vi + 1].1 as f64).sqrt());
    }
    println!();
    Ok(())
}
