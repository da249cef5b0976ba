//! The `paper-figure` figures: the cost-matrix figure's pixels, the correction figure's panels,
//! the per-frame confidence figure from its JSON files.

use figures::{CorrectionFigure, CostFigure, PATH_COLOUR, TRUTH_COLOUR};
use mesh_core::shapes::cylinder;
use nalgebra::{DMatrix, Vector3};

fn near(a: [u8; 3], b: [u8; 3], tol: i32) -> bool {
    a.iter().zip(&b).all(|(x, y)| (*x as i32 - *y as i32).abs() <= tol)
}

/// The cost-matrix PNG has the announced size, the path's cells are drawn in
/// the path colour, cells far from it are not, and the true correspondences
/// show where they leave the path.
#[test]
fn cost_matrix_figure_draws_the_path_where_it_is() {
    let (fs, ft) = (30usize, 50usize);
    let path: Vec<[usize; 2]> = (0..fs).map(|i| [i, (i * (ft - 1) + (fs - 1) / 2) / (fs - 1)]).collect();
    let target_of = |i: usize| path.iter().filter(|q| q[0] == i).map(|q| q[1]).max().unwrap();
    let cost = DMatrix::from_fn(fs, ft, |i, j| ((j as f64 - target_of(i) as f64).abs() + 1.0).powi(3));
    // Truth: the path shifted by 8 target frames on the second half.
    let truth: Vec<[usize; 2]> = (0..fs)
        .map(|i| [i, if i >= 15 { (target_of(i) + 8).min(ft - 1) } else { target_of(i) }])
        .collect();
    let fig = CostFigure {
        title: "test".into(),
        cost,
        path: path.clone(),
        keyposes: vec![],
        truth: Some(truth.clone()),
    };
    let dir = tempfile::tempdir().unwrap();
    let (png_path, svg_path) = (dir.path().join("fig3.png"), dir.path().join("fig3.svg"));
    let layout = fig.write(&png_path, Some(&svg_path)).unwrap();
    assert!(std::fs::metadata(&svg_path).unwrap().len() > 1000);
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png_path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), fig.size());
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let px = |(x, y): (u32, u32)| {
        let o = ((y * info.width + x) * 3) as usize;
        [buf[o], buf[o + 1], buf[o + 2]]
    };
    assert!(layout.cell_w >= 2.0 && layout.cell_h >= 2.0, "{layout:?}");
    // Some pixel within one of the cell centre has the colour (lines are 3 px wide).
    let around = |(x, y): (u32, u32), colour: [u8; 3], tol: i32| {
        (x - 1..=x + 1).any(|x| (y - 1..=y + 1).any(|y| near(px((x, y)), colour, tol)))
    };
    for p in &path {
        let c = layout.centre(p[0], p[1]);
        if !around(c, PATH_COLOUR, 30) {
            let mut m = String::new();
            for y in c.1 - 8..=c.1 + 8 {
                for x in c.0 - 8..=c.0 + 8 {
                    m.push(if near(px((x, y)), PATH_COLOUR, 30) { '#' } else { '.' });
                }
                m.push('\n');
            }
            panic!("path cell {p:?} at {c:?} is {:?}\n{m}", px(c));
        }
    }
    let mut far = 0;
    for i in 0..fs {
        for j in 0..ft {
            let d = path.iter().chain(&truth).map(|q| (q[0].abs_diff(i)).max(q[1].abs_diff(j))).min().unwrap();
            // Above the path only: the legend sits in the lower right corner.
            if d >= 3 && j > target_of(i) + 3 {
                let c = px(layout.centre(i, j));
                assert!(!near(c, PATH_COLOUR, 30) && !near(c, TRUTH_COLOUR, 30), "cell ({i}, {j}) is {c:?}");
                far += 1;
            }
        }
    }
    assert!(far > fs * ft / 4, "{far}");
    for t in truth.iter().filter(|t| t[0] >= 17 && t[0] + 2 < fs && t[1] + 1 < ft) {
        let c = layout.centre(t[0], t[1]);
        assert!(around(c, TRUTH_COLOUR, 40), "truth cell {t:?} at {c:?} is {:?}", px(c));
    }
}

/// The correction figure has one panel per mesh (before, after, nearest,
/// truth), each with the mesh drawn at its centre.
#[test]
fn correction_figure_has_one_panel_per_mesh() {
    let t = cylinder(6, 10, 0.1, 1.0);
    let bent: Vec<Vector3<f64>> = t.vertices.iter().map(|v| v + Vector3::new(0.1 * v.y * v.y, 0.0, 0.0)).collect();
    let fig = CorrectionFigure {
        title: "leg_l, frame 3".into(),
        faces: t.faces.clone(),
        before: bent.clone(),
        after: t.vertices.clone(),
        nearest: vec![(t.vertices.clone(), 0.02), (bent.clone(), 0.03)],
        truth: Some(t.vertices.clone()),
    };
    let cell = 120;
    let img = fig.render(cell, &render::camera::View::FRONT);
    assert_eq!(img.width, 5 * cell);
    assert!(img.height > cell);
    for k in 0..5 {
        let (cx, cy) = (k * cell + cell / 2, 28 + cell / 2);
        let c = img.get(cx, cy);
        assert_ne!(c, render::colour::WHITE, "panel {k} is empty at its centre");
    }
}

/// A hand-made confidence of `frames` frames: the body parts far from the
/// training inputs on frames 10..20 (the pose error rises there too), the
/// displacement without a GP (null).
fn confidence_files(dir: &std::path::Path, frames: usize, eval_frames: usize) -> (std::path::PathBuf, std::path::PathBuf) {
    use std::collections::BTreeMap;
    use transfer::confidence::Confidence;
    use transfer::evaluate::EvalRecord;
    let bump = |f: usize| if (10..20).contains(&f) { 1.0 } else { 0.0 };
    let parts = ["torso", "arm_l", "displacement"];
    let mut variance_ratio = BTreeMap::new();
    let mut nearest_distance = BTreeMap::new();
    for (k, p) in parts.iter().enumerate() {
        let (v, d) = if *p == "displacement" {
            (None, None)
        } else {
            (
                Some((0..frames).map(|f| 0.1 + 0.7 * bump(f) + 0.01 * k as f64).collect()),
                Some((0..frames).map(|f| 0.2 + 1.3 * bump(f) + 0.05 * k as f64).collect()),
            )
        };
        variance_ratio.insert(p.to_string(), v);
        nearest_distance.insert(p.to_string(), d);
    }
    let c = Confidence {
        parts: parts.iter().map(|p| p.to_string()).collect(),
        frames,
        variance_ratio,
        nearest_distance,
    };
    let frame_pose_m: Vec<f64> = (0..eval_frames).map(|f| 0.03 + 0.04 * bump(f) + 0.001 * (f % 3) as f64).collect();
    let r = EvalRecord {
        direction: "A->B".into(),
        motion: "punch".into(),
        method: "gpr-nn".into(),
        placement: "regressed".into(),
        training: "dense".into(),
        rms_pose_m: Some(0.05),
        rms_placed_m: Some(0.07),
        frames: eval_frames,
        foot_sliding_m: None,
        truth_foot_sliding_m: None,
        source_foot_sliding_m: None,
        floor_offset_m: None,
        frame_pose_m,
        reference_frames: None,
        still_rms_pose_m: None,
        dtw_rms_pose_m: None,
        still_dtw_rms_pose_m: None,
    };
    let (cp, ep) = (dir.join("punch-confidence.json"), dir.join("punch-eval.json"));
    std::fs::write(&cp, serde_json::to_string(&c).unwrap()).unwrap();
    std::fs::write(&ep, serde_json::to_string(&r).unwrap()).unwrap();
    (cp, ep)
}

fn paper_figure(args: &[&std::ffi::OsStr]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_paper-figure")).args(args).output().unwrap()
}

/// `paper-figure confidence` draws three panels of the announced size, with
/// the extrapolating frames shaded, reports the correlation with -v, and
/// writes no PNG without an SVG.
#[test]
fn confidence_figure_is_drawn_from_the_json_files() {
    use figures::{confidence_figure_size, EXTRAPOLATING_COLOUR};
    let dir = tempfile::tempdir().unwrap();
    let (cp, ep) = confidence_files(dir.path(), 40, 40);
    let png_path = dir.path().join("conf.png");
    let out = paper_figure(&[
        "confidence".as_ref(),
        "-v".as_ref(),
        "--confidence".as_ref(),
        cp.as_os_str(),
        "--eval".as_ref(),
        ep.as_os_str(),
        "--out".as_ref(),
        png_path.as_os_str(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("pearson r = 0.9"), "{stderr}");
    assert!(std::fs::metadata(dir.path().join("conf.svg")).unwrap().len() > 1000);
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png_path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), confidence_figure_size(40, true));
    let shaded = buf.chunks(3).filter(|p| near([p[0], p[1], p[2]], EXTRAPOLATING_COLOUR, 4)).count();
    let total = (info.width * info.height) as usize;
    // Frames 10..20 of 40 in three panels: a good part of the image, far from all of it.
    assert!(shaded > total / 30 && shaded < total / 4, "{shaded} of {total} pixels shaded");

    // Without --eval: two panels, and --no-svg writes the PNG only.
    let two = dir.path().join("two.png");
    let out = paper_figure(&[
        "confidence".as_ref(),
        "--confidence".as_ref(),
        cp.as_os_str(),
        "--no-svg".as_ref(),
        "--out".as_ref(),
        two.as_os_str(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!dir.path().join("two.svg").exists());
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&two).unwrap()));
    let info = decoder.read_info().unwrap().info().clone();
    assert_eq!((info.width, info.height), confidence_figure_size(40, false));
}

/// An evaluate record of another frame count, or a confidence file with a
/// missing field, fails with one line naming the file, exit 1, no output.
#[test]
fn confidence_figure_rejects_mismatched_inputs_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let (cp, ep) = confidence_files(dir.path(), 40, 39);
    let png_path = dir.path().join("conf.png");
    let run = |conf: &std::path::Path| {
        paper_figure(&[
            "confidence".as_ref(),
            "--confidence".as_ref(),
            conf.as_os_str(),
            "--eval".as_ref(),
            ep.as_os_str(),
            "--out".as_ref(),
            png_path.as_os_str(),
        ])
    };
    let out = run(&cp);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("paper-figure: "), "{stderr}");
    assert!(stderr.contains(&*ep.to_string_lossy()) && stderr.contains("39") && stderr.contains("40"), "{stderr}");
    assert!(!stderr.contains("panic") && !stderr.contains("internal error"), "{stderr}");
    assert!(!png_path.exists());

    // A confidence file without its nearest distances.
    let text = std::fs::read_to_string(&cp).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v.as_object_mut().unwrap().remove("nearest_distance");
    let bad = dir.path().join("bad-confidence.json");
    std::fs::write(&bad, v.to_string()).unwrap();
    let out = run(&bad);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains(&*bad.to_string_lossy()) && stderr.contains("nearest_distance"), "{stderr}");
    assert!(!png_path.exists());
}
