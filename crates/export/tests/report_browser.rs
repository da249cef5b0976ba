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

/// A pipeline's table: `tests/data/results.json` is the demo run's (per-frame arrays cut to 3
/// values), `tests/data/variation.json` the tiny preset's `make variation-results` (seed 0,
/// training settings and most chains left out).
fn data_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn load_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
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
    std::fs::copy(data_file("results.json"), out.join("results.json")).unwrap();
    std::fs::create_dir_all(out.join("variation")).unwrap();
    std::fs::copy(data_file("variation.json"), out.join("variation/variation.json")).unwrap();
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
        "<table class=\"pose-error\">",
        "<svg class=\"error-plot\"",
        "<table class=\"variation-figures\">",
        "<table class=\"variation-sequences\">",
        "src=\"transfer/A-to-B/walk/contact.png\"",
        "src=\"curves/learning-curve.png\"",
        "pca-model",
        "type=\"importmap\"",
        "report-assets/view-data.js",
    ] {
        assert!(html.contains(needle), "page lacks {needle}");
    }
    assert!(!html.contains("frame_pose_m") && !html.contains("guided_per_frame_m"), "no per-frame dumps");
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
    assert!(json["openSeconds"].as_f64().is_some_and(|s| s > 0.0), "no open time: {stdout}");
    let rate = &json["rate"];
    assert_eq!(rate["fps"].as_f64(), Some(25.0), "{rate}");
    let played = rate["playedFps"].as_f64().unwrap();
    assert!((played - 25.0).abs() <= 0.15 * 25.0, "played at {played} fps: {rate}");
    check_pose_table(&json["tables"]["pose-error"], &load_json(&data_file("results.json")));
    check_bars(&json["bars"], &load_json(&data_file("results.json")));
    let variation = load_json(&data_file("variation.json"));
    check_variation_figures(&json["tables"]["variation-figures"], &variation);
    check_variation_sequences(&json["tables"]["variation-sequences"], &variation);
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

/// The cell texts of a table the browser read: rows of cells.
fn rows(table: &serde_json::Value) -> Vec<Vec<String>> {
    let rows = table.as_array().unwrap_or_else(|| panic!("table missing from the page: {table}"));
    rows.iter()
        .map(|r| r.as_array().unwrap().iter().map(|c| c.as_str().unwrap().to_string()).collect())
        .collect()
}

/// The records of `results.json` at the pipelines' default placement, keyed as the page
/// names them: (`direction motion`, method with `-keyposes` for key-pose training) -> (cm, frames).
fn default_records(results: &serde_json::Value) -> Vec<(String, String, f64, f64)> {
    results
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["placement"] == "scaled-source")
        .map(|r| {
            let mut m = r["method"].as_str().unwrap().to_string();
            if r["training"] == "keyposes" {
                m += "-keyposes";
            }
            let row = format!("{} {}", r["direction"].as_str().unwrap(), r["motion"].as_str().unwrap());
            (row, m, 100.0 * r["rms_pose_m"].as_f64().unwrap(), r["frames"].as_f64().unwrap())
        })
        .collect()
}

/// Every default-placement record's pose error is in its row and column, to 0.1 cm, and the
/// pooled row is the RMS over all frames.
fn check_pose_table(table: &serde_json::Value, results: &serde_json::Value) {
    let rows = rows(table);
    let head = &rows[0];
    let recs = default_records(results);
    assert_eq!(head.len(), 1 + 8, "a column per method: {head:?}");
    for (row, method, cm, frames) in &recs {
        let col = head.iter().position(|h| h == method).unwrap_or_else(|| panic!("no column {method}: {head:?}"));
        let r = rows
            .iter()
            .find(|r| r[0] == format!("{row} ({frames})"))
            .unwrap_or_else(|| panic!("no row {row}: {rows:?}"));
        assert_eq!(r[col], format!("{cm:.1}"), "{row} {method}");
    }
    let pooled = rows.last().unwrap();
    assert_eq!(pooled[0], "pooled");
    for (col, method) in head.iter().enumerate().skip(1) {
        let (s, n) = recs
            .iter()
            .filter(|r| &r.1 == method)
            .fold((0.0, 0.0), |(s, n), r| (s + r.2 * r.2 * r.3, n + r.3));
        assert_eq!(pooled[col], format!("{:.1}", (s / n).sqrt()), "pooled {method}");
    }
    assert_eq!(rows.len(), 1 + 4 + 1, "four test motions and the pooled row");
}

/// One bar per default-placement record carrying its value, drawn from a common baseline at a
/// height proportional to the value (the same px per cm for every bar, as rendered).
fn check_bars(bars: &serde_json::Value, results: &serde_json::Value) {
    let bars = bars.as_array().unwrap();
    let recs = default_records(results);
    assert_eq!(bars.len(), recs.len(), "one bar per record");
    let px_per_cm = bars[0]["height"].as_f64().unwrap() / bars[0]["cm"].as_f64().unwrap();
    assert!(px_per_cm > 1.0, "{px_per_cm} px per cm");
    let bottom = bars[0]["bottom"].as_f64().unwrap();
    for (row, method, cm, _) in &recs {
        let b = bars
            .iter()
            .find(|b| b["row"] == row.as_str() && b["column"] == method.as_str())
            .unwrap_or_else(|| panic!("no bar for {row} {method}"));
        assert!((b["cm"].as_f64().unwrap() - cm).abs() < 1e-9, "{row} {method}: {b}");
        let h = b["height"].as_f64().unwrap();
        assert!((h - cm * px_per_cm).abs() < 0.5, "{row} {method}: {h} px for {cm} cm at {px_per_cm} px/cm");
        assert!((b["bottom"].as_f64().unwrap() - bottom).abs() < 0.5, "common baseline");
        assert!(b["width"].as_f64().unwrap() > 2.0, "visible");
    }
}

fn range_mm(list: &serde_json::Value, scale: f64, decimals: usize) -> String {
    let v: Vec<f64> = list.as_array().unwrap().iter().filter_map(|x| x.as_f64()).map(|x| x * scale).collect();
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (a, b) = (format!("{lo:.decimals$}"), format!("{hi:.decimals$}"));
    if a == b { a } else { format!("{a}-{b}") }
}

/// The figures table: fig. 4 and fig. 7b in mm and the acceptance rate, per group column.
fn check_variation_figures(table: &serde_json::Value, v: &serde_json::Value) {
    let rows = rows(table);
    let groups: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(rows[0][1..].iter().collect::<Vec<_>>(), groups);
    let find = |prefix: &str| rows.iter().find(|r| r[0].starts_with(prefix)).unwrap_or_else(|| panic!("{prefix}: {rows:?}"));
    for (i, g) in groups.iter().enumerate() {
        let e = &v[g.as_str()]["eval"];
        let fig4 = format!(
            "{:.2} vs {:.2} mm",
            1e3 * e["reconstruction_gpdm_m"].as_f64().unwrap(),
            1e3 * e["reconstruction_pca_m"].as_f64().unwrap()
        );
        assert_eq!(find("fig. 4")[1 + i], fig4, "{g}");
        for b in e["latent_blend"].as_array().unwrap() {
            let w = b["w"].as_f64().unwrap();
            let text = format!("{:.2} vs {:.2} mm", 1e3 * b["guided_m"].as_f64().unwrap(), 1e3 * b["unguided_m"].as_f64().unwrap());
            let r = rows.iter().find(|r| r[0].ends_with(&format!("w = {w}"))).unwrap();
            assert_eq!(r[1 + i], text, "{g} w = {w}");
        }
        let a = &v[g.as_str()]["samples"]["accept_rate"];
        assert!(find("HMC acceptance")[1 + i].starts_with(&format!("{:.2} (", a["mean"].as_f64().unwrap())));
    }
}

/// The per-sequence table: a row per sampled sequence with its pose-distance range in mm and
/// its mean distance between variations.
fn check_variation_sequences(table: &serde_json::Value, v: &serde_json::Value) {
    let rows = rows(table);
    let head = &rows[0];
    let pose = head.iter().position(|h| h.starts_with("pose distance")).unwrap();
    let between = head.iter().position(|h| h.starts_with("distance between")).unwrap();
    let mut n = 0;
    for (g, grp) in v.as_object().unwrap() {
        for q in grp["samples"]["sequences"].as_array().unwrap() {
            n += 1;
            let label = format!("{} ({})", q["label"].as_str().unwrap(), q["frames"]);
            let r = rows.iter().find(|r| &r[0] == g && r[1] == label).unwrap_or_else(|| panic!("{g} {label}"));
            assert_eq!(r[pose], range_mm(&q["pose_distance_to_source_m"], 1e3, 0), "{g} {label}");
            assert_eq!(r[between], format!("{:.2}", q["pairwise_distance_m"]["mean"].as_f64().unwrap()));
        }
    }
    assert_eq!(rows.len(), 1 + n);
}
