//! glTF 2.0 binary (`.glb`) export of a mesh sequence as morph-target animation.
//!
//! One mesh, one node. The base `POSITION` is the first exported frame; every
//! further exported frame `k` is a morph target holding the deltas
//! `frame_k - base`. One animation channel drives the mesh node's `weights`:
//! at time `t_k = k * stride / fps` the weight vector is one-hot on target
//! `k` (all zeros at `t_0`, which shows the base); a closing key at
//! `t_last + stride / fps` repeats the last frame so that a looping player
//! gives it its full duration. With `STEP` sampling each
//! key shows an exact frame; with `LINEAR` sampling the weights blend
//! linearly, which moves each vertex on the straight line between frames.
//! No normals are written: the glTF spec has clients compute flat normals,
//! which stay correct as the shape deforms.
//!
//! Default: float32 positions and deltas (12 bytes per vertex per frame),
//! which the Khronos validator accepts with no extension. `--stride` keeps
//! every n-th frame; [`GlbOptions::quantize`] stores positions and deltas as
//! int16 normalized (`KHR_mesh_quantization`, required extension), with
//! the node's translation and scale undoing the quantisation (6 bytes per
//! vertex padded to 8, the 4-byte vertex stride glTF requires).

use std::path::Path;

use mesh_core::atomic::write_bytes_atomic;
use mesh_core::sequence::MeshSequence;
use mesh_core::{Error, Result};
use nalgebra::Vector3;
use serde_json::{json, Value};

/// Sampling of the one-hot weight keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Interpolation {
    #[default]
    Step,
    Linear,
}

/// Options of [`encode_glb`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlbOptions {
    /// Keep frames 0, stride, 2*stride, ... (>= 1).
    pub stride: usize,
    /// Frames per second of the input sequence.
    pub fps: f64,
    pub interpolation: Interpolation,
    /// Store positions and deltas as int16 normalized (KHR_mesh_quantization).
    pub quantize: bool,
}

impl Default for GlbOptions {
    fn default() -> Self {
        GlbOptions {
            stride: 1,
            fps: 30.0,
            interpolation: Interpolation::Step,
            quantize: false,
        }
    }
}

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const SHORT: u32 = 5122;
const UNSIGNED_INT: u32 = 5125;

/// Accumulates the binary chunk, buffer views and accessors.
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    fn view(&mut self, bytes: &[u8], target: Option<u32>, stride: Option<usize>) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    fn accessor(&mut self, a: Value) -> usize {
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// A float32 accessor (with min/max, exact f32 values) over new bytes.
    fn floats(&mut self, data: &[f32], ty: &str, width: usize, target: Option<u32>) -> usize {
        let (min, max) = min_max(data, width);
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, target, None);
        self.accessor(json!({"bufferView": view, "componentType": FLOAT,
            "count": data.len() / width, "type": ty, "min": min, "max": max}))
    }

    /// An int16-normalized VEC3 accessor, each vertex padded to 8 bytes.
    fn shorts3(&mut self, data: &[i16]) -> usize {
        let mut bytes = Vec::with_capacity(data.len() / 3 * 8);
        for v in data.chunks(3) {
            for c in v {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
            bytes.extend_from_slice(&[0, 0]);
        }
        // For integer component types, glTF bounds are the stored integers.
        let mut min = [i16::MAX; 3];
        let mut max = [i16::MIN; 3];
        for v in data.chunks(3) {
            for c in 0..3 {
                min[c] = min[c].min(v[c]);
                max[c] = max[c].max(v[c]);
            }
        }
        let view = self.view(&bytes, Some(ARRAY_BUFFER), Some(8));
        self.accessor(
            json!({"bufferView": view, "componentType": SHORT, "normalized": true,
            "count": data.len() / 3, "type": "VEC3", "min": min, "max": max}),
        )
    }
}

/// Component-wise min and max as exact f64 copies of the f32 values (the
/// validator compares them with the data bit for bit).
fn min_max(data: &[f32], width: usize) -> (Vec<f64>, Vec<f64>) {
    let mut min = vec![f64::INFINITY; width];
    let mut max = vec![f64::NEG_INFINITY; width];
    for chunk in data.chunks(width) {
        for (i, &x) in chunk.iter().enumerate() {
            min[i] = min[i].min(f64::from(x));
            max[i] = max[i].max(f64::from(x));
        }
    }
    (min, max)
}

/// int16 normalized encoding of `x` in [-1, 1] (decoded as `q / 32767`).
fn quantize(x: f64) -> i16 {
    (x * 32767.0).round().clamp(-32767.0, 32767.0) as i16
}

/// Frame indices kept with `stride`.
pub fn kept_frames(n_frames: usize, stride: usize) -> Vec<usize> {
    (0..n_frames).step_by(stride.max(1)).collect()
}

/// Encodes `seq` as a `.glb` byte buffer (see the module doc).
pub fn encode_glb(seq: &MeshSequence, name: &str, opts: &GlbOptions) -> Result<Vec<u8>> {
    if seq.n_frames() == 0 || seq.n_vertices() == 0 {
        return Err(Error::invalid("cannot export an empty sequence to glTF"));
    }
    if opts.stride == 0 {
        return Err(Error::invalid("glTF export needs stride >= 1"));
    }
    mesh_core::frame_rate::check_fps(opts.fps).map_err(|e| Error::invalid(format!("glTF export: {e}")))?;
    let kept = kept_frames(seq.n_frames(), opts.stride);
    let base = &seq.frames[kept[0]];
    let deltas: Vec<Vec<Vector3<f64>>> = kept[1..]
        .iter()
        .map(|&k| seq.frames[k].iter().zip(base).map(|(p, b)| p - b).collect())
        .collect();
    let mut b = Builder {
        bin: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
    };
    let indices: Vec<u8> = seq
        .faces
        .iter()
        .flatten()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    let index_view = b.view(&indices, Some(ELEMENT_ARRAY_BUFFER), None);
    let max_index = seq.faces.iter().flatten().copied().max().unwrap_or(0);
    let index_acc = b.accessor(
        json!({"bufferView": index_view, "componentType": UNSIGNED_INT,
        "count": seq.faces.len() * 3, "type": "SCALAR", "min": [0], "max": [max_index]}),
    );

    let mut node = json!({"mesh": 0, "name": name});
    let (position, targets): (usize, Vec<usize>) = if opts.quantize {
        // p = centre + scale * q, per axis; the scale covers base and deltas.
        let (lo, hi) = base.iter().fold(
            (
                Vector3::repeat(f64::INFINITY),
                Vector3::repeat(f64::NEG_INFINITY),
            ),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        );
        let centre = (lo + hi) / 2.0;
        let mut scale = (hi - lo) / 2.0;
        for d in deltas.iter().flatten() {
            scale = scale.sup(&d.abs());
        }
        let scale = scale.map(|s| if s > 0.0 { s } else { 1.0 });
        let q = |v: &Vector3<f64>, off: &Vector3<f64>| -> [i16; 3] {
            let u = (v - off).component_div(&scale);
            [quantize(u.x), quantize(u.y), quantize(u.z)]
        };
        let base_q: Vec<i16> = base.iter().flat_map(|p| q(p, &centre)).collect();
        let position = b.shorts3(&base_q);
        let zero = Vector3::zeros();
        let targets = deltas
            .iter()
            .map(|d| {
                let dq: Vec<i16> = d.iter().flat_map(|v| q(v, &zero)).collect();
                b.shorts3(&dq)
            })
            .collect();
        node["translation"] = json!([centre.x, centre.y, centre.z]);
        node["scale"] = json!([scale.x, scale.y, scale.z]);
        (position, targets)
    } else {
        let flat = |vs: &[Vector3<f64>]| -> Vec<f32> {
            vs.iter()
                .flat_map(|v| [v.x as f32, v.y as f32, v.z as f32])
                .collect()
        };
        let position = b.floats(&flat(base), "VEC3", 3, Some(ARRAY_BUFFER));
        let targets = deltas
            .iter()
            .map(|d| b.floats(&flat(d), "VEC3", 3, Some(ARRAY_BUFFER)))
            .collect();
        (position, targets)
    };

    let n_targets = targets.len();
    let mut primitive =
        json!({"attributes": {"POSITION": position}, "indices": index_acc, "mode": 4});
    let mut mesh = json!({"name": name, "primitives": []});
    let mut animations = json!([]);
    if n_targets > 0 {
        primitive["targets"] = targets.iter().map(|&t| json!({"POSITION": t})).collect();
        mesh["weights"] = json!(vec![0.0; n_targets]);
        let names: Vec<String> = kept[1..].iter().map(|k| format!("frame_{k:06}")).collect();
        mesh["extras"] = json!({"targetNames": names});
        // One key per kept frame plus a closing key one step after the last
        // that repeats it, so that a looping player shows the last frame for
        // as long as the others.
        let step = opts.stride as f64 / opts.fps;
        let mut times: Vec<f32> = kept.iter().map(|&k| (k as f64 / opts.fps) as f32).collect();
        times.push((*kept.last().expect("frames") as f64 / opts.fps + step) as f32);
        let mut weights = vec![0f32; times.len() * n_targets];
        for k in 1..times.len() {
            weights[k * n_targets + (k - 1).min(n_targets - 1)] = 1.0;
        }
        let input = b.floats(&times, "SCALAR", 1, None);
        let output = b.floats(&weights, "SCALAR", 1, None);
        let interpolation = match opts.interpolation {
            Interpolation::Step => "STEP",
            Interpolation::Linear => "LINEAR",
        };
        animations = json!([{
            "name": name,
            "samplers": [{"input": input, "output": output, "interpolation": interpolation}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
        }]);
    }
    mesh["primitives"] = json!([primitive]);

    while b.bin.len() % 4 != 0 {
        b.bin.push(0);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": concat!("surfcap export ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [node],
        "meshes": [mesh],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": b.bin.len()}],
    });
    if n_targets > 0 {
        doc["animations"] = animations;
    }
    if opts.quantize {
        doc["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        doc["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    }
    Ok(pack_glb(&doc, &b.bin))
}

/// The GLB container: 12-byte header, JSON chunk (space-padded), BIN chunk
/// (zero-padded), each chunk 4-byte aligned.
fn pack_glb(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).expect("glTF JSON serialises");
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

/// Writes `seq` as a `.glb` file, atomically.
pub fn write_glb(path: &Path, seq: &MeshSequence, opts: &GlbOptions) -> Result<()> {
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "sequence".into());
    let bytes = encode_glb(seq, &name, opts)?;
    if bytes.len() > u32::MAX as usize {
        return Err(Error::file(
            path,
            format!(
                "{} bytes exceed the 4 GiB glb limit: use a larger --stride or --quantize",
                bytes.len()
            ),
        ));
    }
    write_bytes_atomic(path, &bytes)
}
