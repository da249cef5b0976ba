//! DTW (CVPR eq. 7): known paths, brute-force optimality on small matrices, key-poses forced, and
//! the run-length limit as a property.
mod common;
use common::Rng;
use gp::dtw::{dtw_path, path_cost, DtwOptions, Endpoints};
use nalgebra::DMatrix;
use proptest::prelude::*;

/// Checks every structural constraint of a path; returns the longest vertical and horizontal
/// runs.
fn check_path(
    path: &[(usize, usize)],
    fs: usize,
    ft: usize,
    keys: &[(usize, usize)],
) -> (usize, usize) {
    assert_eq!(path[0], (0, 0));
    assert_eq!(*path.last().unwrap(), (fs - 1, ft - 1));
    let (mut v, mut h, mut vmax, mut hmax) = (0, 0, 0, 0);
    for w in path.windows(2) {
        let (di, dj) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
        match (di, dj) {
            (1, 1) => (v, h) = (0, 0),
            (1, 0) => (v, h) = (v + 1, 0),
            (0, 1) => (v, h) = (0, h + 1),
            _ => panic!("invalid step {w:?}"),
        }
        vmax = vmax.max(v);
        hmax = hmax.max(h);
    }
    for k in keys {
        assert!(path.contains(k), "key {k:?} missed");
    }
    (vmax, hmax)
}

/// Exhaustive search of the best constrained path (independent of the crate's DP).
fn brute(c: &DMatrix<f64>, keys: &[(usize, usize)], r: usize) -> f64 {
    fn go(
        c: &DMatrix<f64>,
        keys: &[(usize, usize)],
        r: usize,
        i: usize,
        j: usize,
        v: usize,
        h: usize,
        acc: f64,
        path: &mut Vec<(usize, usize)>,
        best: &mut f64,
    ) {
        let acc = acc + c[(i, j)];
        path.push((i, j));
        if (i, j) == (c.nrows() - 1, c.ncols() - 1) {
            if keys.iter().all(|k| path.contains(k)) && acc < *best {
                *best = acc;
            }
        } else {
            if i + 1 < c.nrows() && j + 1 < c.ncols() {
                go(c, keys, r, i + 1, j + 1, 0, 0, acc, path, best);
            }
            if i + 1 < c.nrows() && v < r {
                go(c, keys, r, i + 1, j, v + 1, 0, acc, path, best);
            }
            if j + 1 < c.ncols() && h < r {
                go(c, keys, r, i, j + 1, 0, h + 1, acc, path, best);
            }
        }
        path.pop();
    }
    let mut best = f64::INFINITY;
    go(c, keys, r, 0, 0, 0, 0, 0.0, &mut Vec::new(), &mut best);
    best
}

#[test]
fn recovers_a_known_slope_two_path() {
    // 50 fps source against 25 fps target: the true map is j = i / 2 (diagonal, vertical, ...).
    let (fs, ft) = (40, 20);
    let truth: Vec<(usize, usize)> = (0..fs).map(|i| (i, i / 2)).collect();
    let mut c = DMatrix::from_element(fs, ft, 1.0);
    for &p in &truth {
        c[p] = 0.0;
    }
    let path = dtw_path(&c, &[(10, 5)], &DtwOptions::default()).unwrap();
    assert_eq!(path, truth);
}

#[test]
fn matches_brute_force_on_small_random_matrices() {
    let mut rng = Rng::new(50);
    for trial in 0..40 {
        let fs = 3 + (rng.next_u64() % 5) as usize;
        let ft = 3 + (rng.next_u64() % 5) as usize;
        let c = DMatrix::from_fn(fs, ft, |_, _| rng.uniform());
        let keys = if trial % 2 == 0 {
            vec![]
        } else {
            vec![(fs / 2, ft / 2)]
        };
        let r = 1 + trial % 3;
        let opts = DtwOptions {
            max_run: r,
            ..Default::default()
        };
        let expect = brute(&c, &keys, r);
        match dtw_path(&c, &keys, &opts) {
            Ok(p) => {
                check_path(&p, fs, ft, &keys);
                assert!(
                    (path_cost(&c, &p) - expect).abs() < 1e-12,
                    "trial {trial}: {} vs {expect}",
                    path_cost(&c, &p)
                );
            }
            Err(e) => assert!(
                expect.is_infinite(),
                "trial {trial}: {e} but brute force found {expect}"
            ),
        }
    }
}

#[test]
fn key_poses_are_forced_even_when_expensive() {
    let mut c = DMatrix::from_element(10, 10, 0.0);
    c[(2, 7)] = 100.0;
    let path = dtw_path(&c, &[(2, 7)], &DtwOptions::default()).unwrap();
    assert!(path.contains(&(2, 7)));
    // With key-pose endpoints the path spans the keys only.
    let opts = DtwOptions {
        endpoints: Endpoints::KeyPoses,
        ..Default::default()
    };
    let p = dtw_path(&c, &[(1, 1), (6, 8)], &opts).unwrap();
    assert_eq!((p[0], *p.last().unwrap()), ((1, 1), (6, 8)));
}

#[test]
fn infeasible_and_invalid_inputs_are_errors() {
    // Ratio 5 > max_run + 1 = 4: no path.
    assert!(dtw_path(&DMatrix::zeros(50, 10), &[], &DtwOptions::default()).is_err());
    // Ratio 4 is the steepest feasible slope.
    assert!(dtw_path(&DMatrix::zeros(37, 10), &[], &DtwOptions::default()).is_ok());
    assert!(dtw_path(
        &DMatrix::zeros(5, 5),
        &[(1, 3), (3, 1)],
        &DtwOptions::default()
    )
    .is_err());
    assert!(dtw_path(&DMatrix::zeros(5, 5), &[(5, 0)], &DtwOptions::default()).is_err());
    let mut c = DMatrix::zeros(4, 4);
    c[(1, 1)] = f64::NAN;
    assert!(dtw_path(&c, &[], &DtwOptions::default()).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]
    #[test]
    fn run_length_limit_and_keys_hold(fs in 2usize..40, ratio in 0.4f64..2.5, seed in 0u64..1000, nkeys in 0usize..4) {
        let ft = ((fs as f64 * ratio).round() as usize).max(2);
        let mut rng = Rng::new(seed);
        let c = DMatrix::from_fn(fs, ft, |_, _| rng.uniform());
        // Keys on the proportional diagonal (always reachable with slope <= 4).
        let keys: Vec<(usize, usize)> = (1..=nkeys).map(|k| {
            let i = k * (fs - 1) / (nkeys + 1);
            (i, (i as f64 * (ft - 1) as f64 / (fs - 1) as f64).round() as usize)
        }).collect();
        let path = dtw_path(&c, &keys, &DtwOptions::default()).unwrap();
        let (v, h) = check_path(&path, fs, ft, &keys);
        prop_assert!(v <= 3 && h <= 3, "runs {} {}", v, h);
    }
}
