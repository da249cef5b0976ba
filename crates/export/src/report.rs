//! The static report page of a pipeline run: `OUT/index.html` plus
//! `OUT/report-assets/`, opened from disk with no server and no network.
//!
//! Content, from whatever exists under `OUT`: the 3D viewer of the given
//! sequences (source / transfer / truth side by side, play/pause and a frame
//! slider, see [`crate::viewer`]); every `results.json` as the pose error per
//! motion and method, a table and an inline SVG plot ([`crate::transfer_summary`]), and every
//! `variation.json` as the tables of docs/RESULTS.md ([`crate::variation_summary`]), other
//! JSON layouts as nested tables; contact sheets (PNG files whose name contains
//! `contact`), GIFs, and plots (other PNG and SVG files; numbered frame
//! images such as `frames/000012.png` are skipped); the provenance of every
//! surfcap artifact found (kind, producer, seed, parameters, via
//! [`mesh_core::artifact::inspect_json`]); and versions (this crate,
//! three.js, `git describe` when available).

use std::io::Read;
use std::path::{Path, PathBuf};

use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result};

use crate::html::{escape, json_to_html, url_path};
use crate::viewer::{import_map, three_version, view_data_js, ViewSequence, VIEWER_JS};

/// Name of the assets folder inside `OUT`.
pub const ASSETS_DIR: &str = "report-assets";
/// Files visited at most while scanning `OUT`.
const MAX_FILES: usize = 100_000;
/// Images and artifacts listed at most (the rest are counted).
const MAX_ITEMS: usize = 200;

/// What to put in the report.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// Pipeline output folder: scanned, and where `index.html` goes.
    pub out: PathBuf,
    /// Sequences for the 3D view, `(label, folder of numbered frames)`, in
    /// display order (e.g. source, transfer, truth).
    pub views: Vec<(String, PathBuf)>,
    pub title: String,
    /// Frames per second of the sequences.
    pub fps: f64,
    /// Frames kept at most per sequence in the viewer.
    pub max_frames: usize,
    /// Bytes of packed positions kept at most in the viewer (fewer frames
    /// are kept when `max_frames` would exceed it; at least 2).
    pub max_data_bytes: usize,
    /// Folder of the npm package `three`.
    pub three_dir: PathBuf,
}

/// Files found under `OUT`, as paths relative to it (sorted).
#[derive(Debug, Default)]
pub struct Findings {
    pub tables: Vec<PathBuf>,
    pub contact_sheets: Vec<PathBuf>,
    pub gifs: Vec<PathBuf>,
    pub plots: Vec<PathBuf>,
    pub artifacts: Vec<PathBuf>,
    /// Items beyond the listing limit.
    pub left_out: usize,
    /// The scan stopped at [`MAX_FILES`] files.
    pub truncated: bool,
}

fn is_numbered(path: &Path) -> bool {
    path.file_stem()
        .and_then(|s| s.to_str())
        .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
}

fn has_artifact_magic(path: &Path) -> bool {
    let mut magic = [0u8; 8];
    mesh_core::input::open_regular_file(path)
        .is_ok_and(|mut f| f.read_exact(&mut magic).is_ok())
        && magic == mesh_core::artifact::MAGIC
}

/// Scans `out` (breadth-first, sorted, at most [`MAX_FILES`] files, skipping
/// hidden entries and the report's own assets).
pub fn scan(out: &Path) -> Result<Findings> {
    let mut f = Findings::default();
    let mut queue = vec![PathBuf::new()];
    let mut visited = 0usize;
    'walk: while let Some(rel) = queue.pop() {
        let dir = out.join(&rel);
        let mut entries: Vec<_> = std::fs::read_dir(&dir)
            .map_err(|e| Error::io(&dir, e))?
            .filter_map(|e| e.ok())
            .collect();
        entries.sort_by_key(|e| e.file_name());
        for e in entries.into_iter().rev() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') || (rel.as_os_str().is_empty() && name == ASSETS_DIR) {
                continue;
            }
            let r = rel.join(&name);
            let Ok(ft) = e.file_type() else { continue };
            if ft.is_dir() {
                queue.push(r);
                continue;
            }
            visited += 1;
            if visited > MAX_FILES {
                f.truncated = true;
                break 'walk;
            }
            let ext = r
                .extension()
                .and_then(|x| x.to_str())
                .unwrap_or("")
                .to_ascii_lowercase();
            let list = match ext.as_str() {
                "json" if name == "results.json" || name == "variation.json" => &mut f.tables,
                "gif" => &mut f.gifs,
                "png" | "svg" if is_numbered(&r) => continue,
                "png" if name.contains("contact") => &mut f.contact_sheets,
                "png" | "svg" => &mut f.plots,
                "ply" | "obj" | "json" | "csv" | "html" | "js" | "txt" | "md" | "pc2" | "glb" => {
                    continue
                }
                _ if has_artifact_magic(&e.path()) => &mut f.artifacts,
                _ => continue,
            };
            if list.len() < MAX_ITEMS {
                list.push(r);
            } else {
                f.left_out += 1;
            }
        }
    }
    for list in [
        &mut f.tables,
        &mut f.contact_sheets,
        &mut f.gifs,
        &mut f.plots,
        &mut f.artifacts,
    ] {
        list.sort();
    }
    Ok(f)
}

fn git_describe() -> Option<String> {
    let out = std::process::Command::new("git")
        .args(["describe", "--always", "--dirty", "--tags"])
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn images(title: &str, list: &[PathBuf]) -> String {
    if list.is_empty() {
        return String::new();
    }
    let mut s = format!("<section><h2>{}</h2>", escape(title));
    for p in list {
        let rel = p.to_string_lossy();
        s += &format!(
            "<figure><a href=\"{u}\"><img src=\"{u}\" alt=\"{e}\" loading=\"lazy\"></a><figcaption>{e}</figcaption></figure>",
            u = url_path(&rel),
            e = escape(&rel)
        );
    }
    s + "</section>"
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;margin:1.5em;color:#222;background:#fff}
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0;font-size:.9em}th,td{border:1px solid #ccc;padding:.2em .5em;text-align:left;vertical-align:top}
th{background:#f0f0f0}td{font-variant-numeric:tabular-nums}figure{display:inline-block;margin:.5em;vertical-align:top}
figure img{max-width:640px;max-height:480px;border:1px solid #ddd}
table.pose-error td,table.variation-figures td,table.variation-sequences td{text-align:right;white-space:nowrap}
table.variation-sequences td:nth-child(-n+2){text-align:left}
tr.pooled{font-weight:bold}figure.plot{display:block;overflow-x:auto}section{overflow-x:auto}figcaption{font-size:.8em;color:#555}
#viewer{width:100%;max-width:1100px;height:480px;border:1px solid #ccc;background:#f4f4f0}
.controls{margin:.5em 0;display:flex;gap:1em;align-items:center}.controls input{width:400px}
.legend span{display:inline-block;margin-right:1.5em}.legend i{display:inline-block;width:1em;height:1em;margin-right:.3em;vertical-align:middle}";

/// Writes `OUT/index.html` and `OUT/report-assets/view-data.js`; returns the
/// page's path.
pub fn write_report(opts: &ReportOptions) -> Result<PathBuf> {
    let out = &opts.out;
    if !out.is_dir() {
        return Err(Error::file(
            out,
            "is not a folder (the pipeline output to report on)",
        ));
    }
    mesh_core::frame_rate::check_fps(opts.fps).map_err(|e| Error::invalid(format!("--fps: {e}")))?;
    let mut views = Vec::new();
    for (label, dir) in &opts.views {
        let seq = MeshSequence::load_dir(dir)?;
        views.push(ViewSequence {
            label: label.clone(),
            seq,
        });
    }
    let found = scan(out)?;
    let title = escape(&opts.title);
    let mut body = format!("<h1>{title}</h1>");

    let mut head_extra = String::new();
    if !views.is_empty() {
        let per_frame: usize = views.iter().map(|v| 6 * v.seq.n_vertices()).sum();
        let max_frames = opts
            .max_frames
            .min(opts.max_data_bytes / per_frame.max(1))
            .max(2);
        let data = view_data_js(&views, opts.fps, max_frames);
        mesh_core::atomic::write_bytes_atomic(
            &out.join(ASSETS_DIR).join("view-data.js"),
            data.as_bytes(),
        )?;
        head_extra = import_map(&opts.three_dir)?;
        let legend: Vec<String> = data_legend(&views);
        body += &format!(
            "<section><h2>3D view</h2><div class=\"legend\">{}</div><div id=\"viewer\"></div>\
             <div class=\"controls\"><button id=\"play\">Play</button>\
             <input id=\"slider\" type=\"range\" min=\"0\" max=\"0\" value=\"0\">\
             <span>frame <span id=\"frame\">0</span></span></div>\
             <p>Drag to orbit, wheel to zoom. {}</p></section>\
             <script src=\"{ASSETS_DIR}/view-data.js\"></script>\
             <script type=\"module\">{}</script>",
            legend.join(""),
            playback_note(&views, max_frames, opts.fps),
            VIEWER_JS.replace("</script", "<\\/script")
        );
    }
    for t in &found.tables {
        let path = out.join(t);
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| Error::file(&path, format!("not valid JSON: {e}")))?;
        let content = match t.file_name().and_then(|n| n.to_str()) {
            Some("results.json") => crate::transfer_summary::section_html(&v),
            Some("variation.json") => crate::variation_summary::section_html(&v),
            _ => None,
        };
        body += &format!(
            "<section><h2>{}</h2>{}</section>",
            escape(&t.to_string_lossy()),
            content.unwrap_or_else(|| json_to_html(&v))
        );
    }
    body += &images("Contact sheets", &found.contact_sheets);
    body += &images("Animations", &found.gifs);
    body += &images("Plots", &found.plots);
    body += &provenance(out, &found.artifacts, &opts.three_dir);
    if found.left_out > 0 {
        body += &format!("<p>{} more files were not listed.</p>", found.left_out);
    }
    if found.truncated {
        body += &format!("<p>The scan of this folder stopped after {MAX_FILES} files.</p>");
    }
    let page = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{title}</title><style>{STYLE}</style>{head_extra}</head><body>{body}</body></html>\n"
    );
    let index = out.join("index.html");
    mesh_core::atomic::write_bytes_atomic(&index, page.as_bytes())?;
    Ok(index)
}

fn data_legend(views: &[ViewSequence]) -> Vec<String> {
    let colours = crate::viewer::COLOURS;
    views
        .iter()
        .enumerate()
        .map(|(i, v)| {
            format!(
                "<span><i style=\"background:{}\"></i>{} ({} frames, {} vertices)</span>",
                colours[i % colours.len()],
                escape(&v.label),
                v.seq.n_frames(),
                v.seq.n_vertices()
            )
        })
        .collect()
}

fn provenance(out: &Path, artifacts: &[PathBuf], three_dir: &Path) -> String {
    let mut s = String::from("<section><h2>Parameters and versions</h2>");
    let mut versions = serde_json::Map::new();
    versions.insert("surfcap export".into(), env!("CARGO_PKG_VERSION").into());
    if let Some(v) = three_version(three_dir) {
        versions.insert("three.js".into(), v.into());
    }
    if let Some(g) = git_describe() {
        versions.insert("git describe".into(), g.into());
    }
    s += &json_to_html(&serde_json::Value::Object(versions));
    let mut rows = Vec::new();
    for a in artifacts {
        match mesh_core::artifact::inspect_json(out.join(a)) {
            Ok(mut v) => {
                v["file"] = a.to_string_lossy().into_owned().into();
                rows.push(v);
            }
            Err(e) => {
                rows.push(serde_json::json!({"file": a.to_string_lossy(), "error": e.to_string()}))
            }
        }
    }
    if !rows.is_empty() {
        s += "<h3>Artifacts</h3>";
        s += &json_to_html(&serde_json::Value::Array(rows));
    }
    s + "</section>"
}

/// What the 3D view plays, stated from the numbers the viewer uses: the common stride, the
/// frames shown and the rate (each shown frame lasts `stride / fps` seconds, so the motion
/// plays at its real speed).
pub fn playback_note(views: &[ViewSequence], max_frames: usize, fps: f64) -> String {
    let longest = views.iter().map(|v| v.seq.n_frames()).max().unwrap_or(0);
    let stride = crate::viewer::view_stride(longest, max_frames);
    let shown = longest.div_ceil(stride.max(1));
    let which = if stride == 1 { "Every frame".to_string() } else { format!("One frame in {stride}") };
    format!("{which} of {longest} is shown ({shown} frames), each for {stride}/{fps} s: the capture's speed.")
}

