//! The report page: built from a tiny generated run, opened from disk in
//! headless Chromium (no console errors, the 3D canvas draws, Play advances).
mod common;

use std::path::{Path, PathBuf};

use export::report::{write_report, ReportOptions};

/// A PNG of `w x h` pixels with a gradient (a stand-in contact sheet or plot).
fn write_png(path: &Path, w: u32, h: u32) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut enc = png::Encoder::new(file, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let data: Vec<u8> = (0..w * h)
        .flat_map(|i| [(i % w * 255 / w) as u8, (i / w * 255 / h) as u8, 128])
        .collect();
    enc.write_header().unwrap().write_image_data(&data).unwrap();
}

/// Luminance variance of an RGB(A) PNG, decoded independently of the browser.
fn png_variance(path: &Path) -> f64 {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let ch = info.color_type.samples();
    assert!(ch >= 3 && info.bit_depth == png::BitDepth::Eight);
    let ys: Vec<f64> = buf[..info.buffer_size()]
        .chunks(ch)
        .map(|p| 0.299 * p[0] as f64 + 0.587 * p[1] as f64 + 0.114 * p[2] as f64)
        .collect();
    let mean = ys.iter().sum::<f64>() / ys.len() as f64;
    ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / ys.len() as f64
}

/// OUT of a fake transfer run: sequences, results.json, variation.json,
/// a contact sheet, a plot, a numbered frame image (to be skipped), an artifact.
fn fake_run(root: &Path) -> (PathBuf, Vec<(String, PathBuf)>) {
    let out = root.join("out");
    let _ = std::fs::remove_dir_all(root);
    let data = root.join("data");
    let views = [
        ("source", 0.5, 0.0),
        ("transfer", 0.8, 0.3),
        ("truth", 0.7, 0.2),
    ]
    .iter()
    .map(|(label, amp, ph)| {
        let d = data.join(label);
        common::bending_capsule(24, *amp, *ph)
            .write_dir(&d)
            .unwrap();
        (label.to_string(), d)
    })
    .collect();
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(
        out.join("results.json"),
        r#"[{"direction":"A->B","motion":"walk","method":"gpr-nn","rms_pose_m":0.0123,"rms_placed_m":0.0456,"frames":24},
            {"direction":"A->B","motion":"walk","method":"gpr-se","rms_pose_m":0.0234,"rms_placed_m":0.0567,"frames":24}]"#,
    )
    .unwrap();
    std::fs::write(out.join("variation/variation.json"), "").ok();
    std::fs::create_dir_all(out.join("variation")).unwrap();
    std::fs::write(
        out.join("variation/variation.json"),
        r#"{"hmc_acceptance":0.71,"variations":5}"#,
    )
    .unwrap();
    write_png(&out.join("transfer/A-to-B/walk/contact.png"), 64, 32);
    write_png(&out.join("curves/learning-curve.png"), 40, 30);
    write_png(&out.join("transfer/A-to-B/walk/frames/000000.png"), 8, 8);
    let header = mesh_core::artifact::Header::new("pca-fit", "0.1.0").with_seed(7);
    mesh_core::artifact::write_artifact(
        out.join("model.art"),
        "pca-model",
        1,
        &header,
        &vec![1.0f64, 2.0],
    )
    .unwrap();
    (out, views)
}

#[test]
fn page_lists_what_the_run_produced() {
    let dir = tempfile::tempdir().unwrap();
    let (out, views) = fake_run(dir.path());
    let page = write_report(&ReportOptions {
        out: out.clone(),
        views,
        title: "walk <test>".into(),
        fps: 30.0,
        max_frames: 10,
        max_data_bytes: 12_000_000,
        three_dir: export::viewer::DEFAULT_THREE_DIR.into(),
    })
    .unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("<title>walk &lt;test&gt;</title>"));
    for needle in [
        "<th>rms_pose_m</th>",
        "gpr-se",
        "<th>hmc_acceptance</th>",
        "0.7100",
        "src=\"transfer/A-to-B/walk/contact.png\"",
        "src=\"curves/learning-curve.png\"",
        "pca-model",
        "type=\"importmap\"",
        "report-assets/view-data.js",
    ] {
        assert!(html.contains(needle), "page lacks {needle}");
    }
    assert!(
        !html.contains("frames/000000.png"),
        "numbered frame images are not listed"
    );
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "no network references"
    );
    let data = std::fs::read_to_string(out.join("report-assets/view-data.js")).unwrap();
    assert!(
        data.contains("\"nFrames\":8") && data.contains("\"stride\":3"),
        "24 frames, at most 10 kept"
    );
}

#[test]
fn page_works_in_headless_chromium_from_disk() {
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("export-report");
    let (out, views) = fake_run(&root);
    let page = write_report(&ReportOptions {
        out,
        views,
        title: "surfcap report test".into(),
        fps: 25.0,
        max_frames: 60,
        max_data_bytes: 12_000_000,
        three_dir: export::viewer::DEFAULT_THREE_DIR.into(),
    })
    .unwrap();
    let shot = root.join("screenshot.png");
    let res = common::node("browser-test.mjs", &[&page, &shot]);
    let stdout = String::from_utf8_lossy(&res.stdout);
    eprintln!("{stdout}{}", String::from_utf8_lossy(&res.stderr));
    assert!(
        res.status.success(),
        "browser test failed: {stdout}{}",
        String::from_utf8_lossy(&res.stderr)
    );
    let json: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();
    let open = json["openSeconds"].as_f64().unwrap();
    assert!(open < 2.0, "the page opened in {open} s");
    let rate = &json["rate"];
    assert_eq!(rate["fps"].as_f64(), Some(25.0), "{rate}");
    let played = rate["playedFps"].as_f64().unwrap();
    assert!((played - 25.0).abs() <= 0.15 * 25.0, "played at {played} fps: {rate}");
    let var = png_variance(&shot);
    assert!(
        var > 10.0,
        "screenshot of the canvas is blank (luminance variance {var})"
    );
}

#[test]
fn data_budget_limits_the_viewer_frames() {
    let dir = tempfile::tempdir().unwrap();
    let (out, views) = fake_run(dir.path());
    // 3 sequences x 290 vertices x 6 bytes = 5220 bytes per frame: 20000 bytes keep 3 frames.
    write_report(&ReportOptions {
        out: out.clone(),
        views,
        title: "budget".into(),
        fps: 30.0,
        max_frames: 60,
        max_data_bytes: 20_000,
        three_dir: export::viewer::DEFAULT_THREE_DIR.into(),
    })
    .unwrap();
    let data = std::fs::read_to_string(out.join("report-assets/view-data.js")).unwrap();
    assert!(
        data.contains("\"nFrames\":3,"),
        "24 frames under a 3-frame budget"
    );
}
