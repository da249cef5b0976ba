//! Mesh sequences: ordered frames sharing one topology, stored on disk as a
//! directory of `000000.ply`, `000001.ply`, ... (or `.obj`) files.

use std::path::{Path, PathBuf};
use std::str::FromStr;

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::io::MeshFormat;
use crate::mesh::TriMesh;
use crate::topology::Topology;

/// Frames of one subject's motion: one face list, per-frame vertex positions.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshSequence {
    pub faces: Vec<[u32; 3]>,
    pub frames: Vec<Vec<Vector3<f64>>>,
}

/// A half-open frame range `a:b` (`a` defaults to 0, `b` to the end), as
/// given to `--frames`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FrameRange {
    pub start: usize,
    pub end: Option<usize>,
}

impl FromStr for FrameRange {
    type Err = String;
    /// Parses `a:b`, `a:`, `:b`, `:` or a single frame `a` (= `a:a+1`).
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let num = |t: &str| -> std::result::Result<Option<usize>, String> {
            let t = t.trim();
            if t.is_empty() {
                return Ok(None);
            }
            t.parse()
                .map(Some)
                .map_err(|_| format!("bad frame number '{t}' in range '{s}'"))
        };
        let r = match s.split_once(':') {
            Some((a, b)) => FrameRange {
                start: num(a)?.unwrap_or(0),
                end: num(b)?,
            },
            None => {
                let a = num(s)?.ok_or_else(|| format!("empty frame range '{s}'"))?;
                FrameRange {
                    start: a,
                    end: Some(a + 1),
                }
            }
        };
        if r.end.is_some_and(|e| e <= r.start) {
            return Err(format!(
                "empty frame range '{s}' (end must be greater than start)"
            ));
        }
        Ok(r)
    }
}

/// Frame number of a file named `<digits>.ply` / `<digits>.obj`.
pub(crate) fn frame_number(path: &Path) -> Option<usize> {
    MeshFormat::from_path(path)?;
    let stem = path.file_stem()?.to_str()?;
    if stem.is_empty() || !stem.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    stem.parse().ok()
}

pub(crate) fn is_rate_file(p: &Path) -> bool {
    p.file_name().is_some_and(|n| n == RATE_FILE)
}

/// The frame-rate sidecar of a sequence folder: `{"fps": 25.0}`, written beside the frames by
/// the stages that know the rate (`gpr-predict` from the model's source rate, `hmc-sample` from
/// the capture's) and read by `mesh-export` and the report's player. Frame loaders ignore it.
pub const RATE_FILE: &str = "rate.json";

/// The frame rate recorded in `dir`'s [`RATE_FILE`], `None` when the folder has none.
pub fn read_rate(dir: impl AsRef<Path>) -> Result<Option<f64>> {
    let path = dir.as_ref().join(RATE_FILE);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(&path, e)),
    };
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| Error::file(&path, format!("not JSON: {e}")))?;
    match value.get("fps").and_then(|f| f.as_f64()) {
        Some(fps) => crate::frame_rate::check_fps(fps).map(Some).map_err(|e| Error::file(&path, format!("'fps': {e}"))),
        None => Err(Error::file(&path, "needs \"fps\": a number of frames per second")),
    }
}

/// The frame files of `dir` in frame order, found by
/// [`crate::frame_pattern::detect`]: surfcap's own `000000.ply`, ... (`.obj`
/// too), or one prefixed sequence (`frame_0001.ply`, `walk.0001.obj`,
/// Blender's `punch0.obj`, ...), numbered without gaps or duplicates from
/// its first number. A reading other than surfcap's own is stated once per
/// folder on stderr (not with `-q`).
pub fn frame_files(dir: impl AsRef<Path>) -> Result<Vec<PathBuf>> {
    let dir = dir.as_ref();
    let listing = crate::frame_pattern::detect(dir)?;
    if !listing.is_native() {
        state_reading(dir, &listing);
    }
    Ok(listing.files)
}

/// The frame files of `dir` named by `pattern` (e.g. `walk.%04d.obj`), in
/// frame order; the reading is stated as by [`frame_files`].
pub fn frame_files_matching(
    dir: impl AsRef<Path>,
    pattern: &crate::frame_pattern::FramePattern,
) -> Result<Vec<PathBuf>> {
    let dir = dir.as_ref();
    let listing = crate::frame_pattern::list(dir, pattern)?;
    if !listing.is_native() {
        state_reading(dir, &listing);
    }
    Ok(listing.files)
}

/// `stage: dir: frames walk.%04d.obj, ...` on stderr, once per folder and
/// process, unless `-q`.
fn state_reading(dir: &Path, listing: &crate::frame_pattern::FrameListing) {
    static STATED: std::sync::Mutex<std::collections::BTreeSet<PathBuf>> =
        std::sync::Mutex::new(std::collections::BTreeSet::new());
    if crate::cli::is_quiet() {
        return;
    }
    let first = STATED.lock().map(|mut s| s.insert(dir.to_path_buf())).unwrap_or(false);
    if first {
        eprintln!(
            "{}: {}: {}",
            crate::cli::stage_name(),
            crate::input::escape_control(&dir.display().to_string()),
            listing.describe()
        );
    }
}

impl MeshSequence {
    pub fn new(faces: Vec<[u32; 3]>, frames: Vec<Vec<Vector3<f64>>>) -> Self {
        MeshSequence { faces, frames }
    }

    pub fn n_frames(&self) -> usize {
        self.frames.len()
    }
    /// Vertices per frame (0 for an empty sequence).
    pub fn n_vertices(&self) -> usize {
        self.frames.first().map_or(0, Vec::len)
    }
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// Frame `i` as a standalone mesh (copies). Panics if `i >= n_frames()`.
    pub fn frame_mesh(&self, i: usize) -> TriMesh {
        TriMesh::new(self.frames[i].clone(), self.faces.clone())
    }

    /// Adjacency of the shared topology.
    pub fn topology(&self) -> Topology {
        Topology::new(self.n_vertices(), &self.faces)
    }

    /// Loads every frame of `dir` (see [`frame_files`]).
    pub fn load_dir(dir: impl AsRef<Path>) -> Result<Self> {
        Self::load_dir_range(dir, FrameRange::default())
    }

    /// Loads frames `range` of `dir`, in parallel but deterministically: the
    /// result and the reported error (the first bad frame in frame order) do
    /// not depend on the thread count. Every frame must have the vertex count
    /// and faces of the first loaded frame; the error names the offending file.
    pub fn load_dir_range(dir: impl AsRef<Path>, range: FrameRange) -> Result<Self> {
        let dir = dir.as_ref();
        let files = frame_files(dir)?;
        let end = range.end.unwrap_or(files.len());
        if range.start >= files.len() || end > files.len() {
            return Err(Error::file(
                dir,
                format!(
                    "frame range {}:{end} is outside the {} frames",
                    range.start,
                    files.len()
                ),
            ));
        }
        Self::load_files(&files[range.start..end])
    }

    /// Loads the given frame files in order (in parallel), checking each
    /// against the first.
    pub fn load_files(files: &[PathBuf]) -> Result<Self> {
        let Some(first_path) = files.first() else {
            return Ok(Self::default());
        };
        let bar = crate::cli::stage_progress(files.len() as u64, "frames read");
        let first = crate::io::read_first_frame(first_path)?;
        bar.inc(1);
        let meshes: Vec<Result<TriMesh>> = files[1..].par_iter().map(|f| crate::io::read_mesh_like(f, &first)).inspect(|_| bar.inc(1)).collect();
        bar.finish_and_clear();
        let TriMesh { vertices, faces } = first.into_mesh();
        let mut frames: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(files.len());
        frames.push(vertices);
        for (mesh, path) in meshes.into_iter().zip(&files[1..]) {
            let mesh = mesh?;
            check_like_first(first_path, frames[0].len(), &faces, path, &mesh)?;
            frames.push(mesh.vertices);
        }
        Ok(MeshSequence { faces, frames })
    }

    /// Writes the frames as `dir/000000.ply`, `000001.ply`, ... (binary PLY)
    /// with [`write_frames_atomic`]: the folder is replaced as a whole, so it
    /// holds exactly this sequence or (after a failure or a kill) what it held
    /// before, and [`MeshSequence::load_dir`] reads back exactly this sequence.
    pub fn write_dir(&self, dir: impl AsRef<Path>) -> Result<()> {
        self.write_dir_at(dir, None)
    }

    /// [`MeshSequence::write_dir`] with the frame rate `fps` recorded in the folder's
    /// [`RATE_FILE`] (in the same atomic replacement); `None` leaves no rate file.
    pub fn write_dir_at(&self, dir: impl AsRef<Path>, fps: Option<f64>) -> Result<()> {
        let writer = crate::io::ply_frames::PlyFrames::new(self.n_vertices(), &self.faces);
        let bar = crate::cli::stage_progress(self.n_frames() as u64, "frames written");
        let done = writer.write_dir_counting(dir.as_ref(), &self.frames, fps, &|| bar.inc(1));
        bar.finish_and_clear();
        done
    }
}

/// Fails, naming `path`, unless the frame `mesh` read from it has the vertex count `n_vertices`
/// and the faces `faces` of the sequence's first frame, read from `first_path`.
pub fn check_like_first(
    first_path: &Path,
    n_vertices: usize,
    faces: &[[u32; 3]],
    path: &Path,
    mesh: &TriMesh,
) -> Result<()> {
    let first = first_path.file_name().unwrap_or_default().to_string_lossy();
    if mesh.vertices.len() != n_vertices {
        return Err(Error::file(
            path,
            format!("has {} vertices but the first frame ({first}) has {n_vertices}", mesh.vertices.len()),
        ));
    }
    if mesh.faces.len() != faces.len() {
        return Err(Error::file(
            path,
            format!("has {} faces but the first frame ({first}) has {}", mesh.faces.len(), faces.len()),
        ));
    }
    if let Some(f) = mesh.faces.iter().zip(faces).position(|(a, b)| a != b) {
        return Err(Error::file(
            path,
            format!("face {f} differs from the first frame ({first}): topology must be shared"),
        ));
    }
    Ok(())
}

/// Writes a folder of `n` numbered frames `000000.<ext>`, ... atomically
/// ([`crate::atomic::write_dir_atomic`]): `write(i, path)` writes frame `i`
/// (in parallel). Non-frame files of an existing folder are kept; its frame
/// files (an earlier, longer sequence, or the other format) are not.
pub fn write_frames_atomic<F>(dir: &Path, n: usize, ext: &str, write: F) -> Result<()>
where
    F: Fn(usize, &Path) -> Result<()> + Sync,
{
    let keep = |p: &Path| frame_number(p).is_none() && !is_rate_file(p);
    let bar = crate::cli::stage_progress(n as u64, "frames written");
    let done = crate::atomic::write_dir_atomic(dir, &keep, |tmp| {
        (0..n).into_par_iter().try_for_each(|i| {
            bar.inc(1);
            write(i, &tmp.join(format!("{i:06}.{ext}")))
        })
    });
    bar.finish_and_clear();
    done
}
