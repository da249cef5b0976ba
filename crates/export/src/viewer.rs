//! The report's 3D viewer: mesh sequences packed for the page, and the
//! vendored three.js modules it runs on.
//!
//! Pages opened from disk cannot fetch files or import ES modules by
//! `file://` URL in Chromium, so everything is inlined: three.js (from the npm
//! package `three`, `build/three.module.js` + `build/three.core.js` +
//! `examples/jsm/controls/OrbitControls.js`) as `data:` URLs in an import
//! map, the viewer (`web/viewer.js`, compiled in) as an inline module, and
//! the sequences as `report-assets/view-data.js`, a classic script that sets
//! `window.SURFCAP_VIEW`.
//!
//! Each sequence is subsampled to at most `max_frames` frames (one common
//! stride) and quantised to int16 per axis around its bounding-box centre
//! over all kept frames: 6 bytes per vertex per frame before base64.

use std::path::Path;

use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result};
use nalgebra::Vector3;
use serde_json::json;

use crate::base64;

/// The viewer module (an ES module importing `three`).
pub const VIEWER_JS: &str = include_str!("../web/viewer.js");

/// Where `three` is looked for when `--three` is not given: the npm install
/// made by `scripts/setup-web` next to this crate.
pub const DEFAULT_THREE_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/web/node_modules/three");

/// Colours of the first sequences (source, transfer, truth, then others).
pub const COLOURS: [&str; 6] = [
    "#8a9bb0", "#e0893a", "#5aa469", "#b569b0", "#c9b44a", "#4aa3c9",
];

/// One labelled sequence to show.
pub struct ViewSequence {
    pub label: String,
    pub seq: MeshSequence,
}

/// Frame stride that keeps at most `max_frames` of `n_frames`.
pub fn view_stride(n_frames: usize, max_frames: usize) -> usize {
    n_frames.div_ceil(max_frames.max(1)).max(1)
}

/// The `view-data.js` script: `window.SURFCAP_VIEW = {...};`. All sequences
/// are sampled at the same frame numbers `0, stride, 2 stride, ...` (a shorter
/// sequence holds its last frame).
pub fn view_data_js(seqs: &[ViewSequence], fps: f64, max_frames: usize) -> String {
    let longest = seqs.iter().map(|v| v.seq.n_frames()).max().unwrap_or(0);
    let stride = view_stride(longest, max_frames);
    let kept: Vec<usize> = (0..longest).step_by(stride).collect();
    let mut out = Vec::new();
    for (i, v) in seqs.iter().enumerate() {
        let n = v.seq.n_frames();
        let frames: Vec<&Vec<Vector3<f64>>> =
            kept.iter().map(|&k| &v.seq.frames[k.min(n - 1)]).collect();
        let (mut lo, mut hi) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        for p in frames.iter().copied().flatten() {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let centre = (lo + hi) / 2.0;
        let scale = ((hi - lo) / 2.0).map(|s| if s > 0.0 { s } else { 1.0 });
        let mut q = Vec::with_capacity(frames.len() * v.seq.n_vertices() * 6);
        for p in frames.iter().copied().flatten() {
            let u = (p - centre).component_div(&scale);
            for c in [u.x, u.y, u.z] {
                let qi = (c * 32767.0).round().clamp(-32767.0, 32767.0) as i16;
                q.extend_from_slice(&qi.to_le_bytes());
            }
        }
        let faces: Vec<u8> = v
            .seq
            .faces
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        out.push(json!({
            "label": v.label,
            "colour": COLOURS[i % COLOURS.len()],
            "nVertices": v.seq.n_vertices(),
            "centre": [centre.x, centre.y, centre.z],
            "scale": [scale.x, scale.y, scale.z],
            "faces": base64::encode(&faces),
            "positions": base64::encode(&q),
        }));
    }
    let doc = json!({"fps": fps, "stride": stride, "nFrames": kept.len(), "seqs": out});
    format!("window.SURFCAP_VIEW = {doc};\n")
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

fn data_url(js: &str) -> String {
    format!(
        "data:text/javascript;base64,{}",
        base64::encode(js.as_bytes())
    )
}

/// The `<script type="importmap">` element mapping `three`, its core and
/// OrbitControls to `data:` URLs read from the npm package at `three_dir`.
pub fn import_map(three_dir: &Path) -> Result<String> {
    let module_path = three_dir.join("build/three.module.js");
    if !module_path.is_file() {
        return Err(Error::file(
            &module_path,
            "three.js is not installed (run scripts/setup-web, or give --three <dir of the npm package three>)",
        ));
    }
    let module = read_text(&module_path)?;
    if !module.contains("from './three.core.js'") {
        return Err(Error::file(
            &module_path,
            "unexpected layout: it does not import './three.core.js' (three.js version changed?)",
        ));
    }
    let module = module.replace("from './three.core.js'", "from 'three/core'");
    let core = read_text(&three_dir.join("build/three.core.js"))?;
    let orbit = read_text(&three_dir.join("examples/jsm/controls/OrbitControls.js"))?;
    let map = json!({"imports": {
        "three": data_url(&module),
        "three/core": data_url(&core),
        "three/addons/controls/OrbitControls.js": data_url(&orbit),
    }});
    Ok(format!("<script type=\"importmap\">{map}</script>"))
}

/// Version of the three.js package at `three_dir` (from its package.json).
pub fn three_version(three_dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(three_dir.join("package.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("version")?.as_str().map(str::to_string)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Standard base64 decoding, written independently of the encoder.
    fn unbase64(s: &str) -> Vec<u8> {
        let val = |c: u8| match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("bad base64 byte {c}"),
        };
        let mut out = Vec::new();
        for chunk in s.as_bytes().chunks(4) {
            let pad = chunk.iter().filter(|&&c| c == b'=').count();
            let n = chunk
                .iter()
                .take(4 - pad)
                .enumerate()
                .fold(0u32, |n, (i, &c)| n | (u32::from(val(c)) << (18 - 6 * i)));
            out.extend_from_slice(&n.to_be_bytes()[1..4 - pad]);
        }
        out
    }

    /// The page reconstructs `centre + scale * q / 32767`: within half a
    /// quantisation step of the true positions, at the sampled frames.
    #[test]
    fn packed_sequences_decode_to_the_frames() {
        let (mesh, _) = mesh_core::shapes::capsule_body(4, 8, 0.1, 1.0);
        let frames: Vec<Vec<Vector3<f64>>> = (0..10)
            .map(|t| {
                mesh.vertices
                    .iter()
                    .map(|p| p + Vector3::new(0.05 * t as f64, 0.0, -0.02 * t as f64))
                    .collect()
            })
            .collect();
        let short = MeshSequence::new(mesh.faces.clone(), frames[..4].to_vec());
        let seqs = [
            ViewSequence {
                label: "a".into(),
                seq: MeshSequence::new(mesh.faces.clone(), frames.clone()),
            },
            ViewSequence {
                label: "b".into(),
                seq: short,
            },
        ];
        let js = view_data_js(&seqs, 25.0, 4);
        let doc: serde_json::Value = serde_json::from_str(
            js.strip_prefix("window.SURFCAP_VIEW = ")
                .unwrap()
                .trim_end()
                .strip_suffix(';')
                .unwrap(),
        )
        .unwrap();
        assert_eq!(
            (doc["stride"].as_u64(), doc["nFrames"].as_u64()),
            (Some(3), Some(4))
        );
        for (si, v) in seqs.iter().enumerate() {
            let s = &doc["seqs"][si];
            let faces = unbase64(s["faces"].as_str().unwrap());
            let faces: Vec<u32> = faces
                .chunks(4)
                .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
                .collect();
            assert_eq!(
                faces,
                v.seq.faces.iter().flatten().copied().collect::<Vec<_>>()
            );
            let q = unbase64(s["positions"].as_str().unwrap());
            let q: Vec<f64> = q
                .chunks(2)
                .map(|b| f64::from(i16::from_le_bytes([b[0], b[1]])))
                .collect();
            let c: Vec<f64> = s["centre"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let sc: Vec<f64> = s["scale"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let nv = v.seq.n_vertices();
            for (j, k) in [0usize, 3, 6, 9].into_iter().enumerate() {
                let truth = &v.seq.frames[k.min(v.seq.n_frames() - 1)];
                for (i, p) in truth.iter().enumerate() {
                    for a in 0..3 {
                        let got = c[a] + sc[a] * q[(j * nv + i) * 3 + a] / 32767.0;
                        assert!(
                            (got - p[a]).abs() <= 0.51 * sc[a] / 32767.0,
                            "seq {si} frame {k} vertex {i}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn stride_keeps_at_most_max_frames() {
        for n in 1..300 {
            for m in [1, 7, 60] {
                let s = view_stride(n, m);
                assert!((0..n).step_by(s).count() <= m, "n={n} m={m}");
                assert!(
                    s == 1 || (0..n).step_by(s - 1).count() > m,
                    "stride not minimal"
                );
            }
        }
    }
}
