//! Alembic (`.abc`) mesh caches: one animated PolyMesh read into a [`MeshSequence`] and its
//! frame rate. The container is Ogawa ([`super::ogawa`]); this module walks Alembic's schema on
//! top of it, only as far as a PolyMesh's points and faces:
//!
//! - The root group: child 0 the archive version (`i32`), 1 the library version (`i32`), 2 the
//!   top object, 3 the archive's metadata, 4 the time samplings, 5 the indexed metadata.
//! - An object group: child 0 its properties (a compound), children `1..=n` its `n` child
//!   objects, the last child the headers of those children (name, metadata; 32 bytes of hashes
//!   at the end). A PolyMesh's metadata holds `schema=AbcGeom_PolyMesh_v1`.
//! - A compound property group: one child per property, the last child the packed property
//!   headers (kind, plain-old-data type and extent, sample counts, time sampling, name, metadata).
//! - An array property: two children per stored sample, the data (a 16-byte key, then the
//!   values) and its dimensions. Samples equal to the one before are not stored: the header's
//!   first and last changed indices map a sample to the one stored.
//! - A time sampling: time per cycle and the sample times of a cycle; one time per cycle is
//!   uniform sampling, `1 / time per cycle` frames per second.
//!
//! Read: the PolyMesh's `.geom` compound: `P` (float32 or float64 3-vectors, one sample per
//! frame, a constant vertex count), `.faceCounts` and `.faceIndices` (int32), constant over the
//! samples. Faces are stored clockwise (Alembic's convention, which Blender's and Maya's
//! exporters follow by reversing their polygons): each polygon is reversed back to
//! counter-clockwise and fan-triangulated. Positions are the mesh's own coordinates (Alembic is
//! +Y up like surfcap's capture sets: Blender's exporter turns its +Z up into +Y up); parent
//! transforms are not applied. Not read: normals, UVs, velocities, face sets, subdivision
//! surfaces, changing topology, other schemas.
//!
//! Hardening: every count and offset is checked against the file's length before anything is
//! allocated, the object tree is walked without recursion and each object group at most once,
//! and the frames written out (samples repeated from a stored one included) may not need more
//! than [`EXPANSION_LIMIT`] times the file's size.

#![forbid(unsafe_code)]

use std::collections::HashSet;
use std::path::Path;

use nalgebra::Vector3;

use super::ogawa::{Group, Ogawa};
use crate::error::{Error, Result};
use crate::input::escape_control;
use crate::sequence::MeshSequence;

/// The frames read (as f64 vertices) may need at most this many times the file's bytes:
/// samples that repeat the one before are stored once, so a few bytes could otherwise ask for
/// any number of frames.
pub const EXPANSION_LIMIT: u64 = 32;

/// The Alembic library version the newest Ogawa files carry at least (Alembic 0.9.9).
const MIN_LIBRARY_VERSION: i32 = 9999;
/// Time per cycle of acyclic time samplings (`f64::MAX / 32` in Alembic).
const ACYCLIC_TIME_PER_CYCLE: f64 = f64::MAX / 32.0;
const POLYMESH_SCHEMA: &str = "AbcGeom_PolyMesh_v1";

/// A PolyMesh read from an Alembic file.
#[derive(Clone, Debug)]
pub struct AlembicMesh {
    /// The object's full path in the file (`/Cube/CubeShape`).
    pub path: String,
    /// The frames, counter-clockwise triangles.
    pub sequence: MeshSequence,
    /// Frames per second of `P`'s time sampling.
    pub fps: f64,
    /// Time of the first sample, seconds.
    pub start_time: f64,
    /// Polygons left out as degenerate (fewer than 3 distinct corners).
    pub skipped_faces: usize,
}

/// Plain-old-data types of Alembic's property headers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pod {
    Bool,
    Uint8,
    Int32,
    Float32,
    Float64,
    Other(u8),
}

impl Pod {
    fn of(code: u8) -> Pod {
        match code {
            0 => Pod::Bool,
            1 => Pod::Uint8,
            6 => Pod::Int32,
            10 => Pod::Float32,
            11 => Pod::Float64,
            c => Pod::Other(c),
        }
    }
    fn name(self) -> String {
        const NAMES: [&str; 14] = [
            "bool", "uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64",
            "float16", "float32", "float64", "string", "wstring",
        ];
        let code = match self {
            Pod::Bool => 0,
            Pod::Uint8 => 1,
            Pod::Int32 => 6,
            Pod::Float32 => 10,
            Pod::Float64 => 11,
            Pod::Other(c) => c,
        };
        NAMES.get(code as usize).map_or(format!("type {code}"), |s| s.to_string())
    }
    fn size(self) -> Option<usize> {
        match self {
            Pod::Bool | Pod::Uint8 => Some(1),
            Pod::Int32 | Pod::Float32 => Some(4),
            Pod::Float64 => Some(8),
            Pod::Other(_) => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Compound,
    Scalar,
    Array,
}

/// One entry of a compound's packed property headers.
#[derive(Clone, Debug)]
struct PropertyHeader {
    name: String,
    kind: Kind,
    pod: Pod,
    extent: u8,
    /// Number of samples (stored or repeated).
    samples: u32,
    first_changed: u32,
    last_changed: u32,
    time_sampling: u32,
}

impl PropertyHeader {
    /// The stored sample that sample `i` reads (Alembic stores a run of equal samples once).
    fn stored_index(&self, i: u32) -> Option<u64> {
        let (first, last) = (self.first_changed, self.last_changed);
        if i < first || (first == 0 && last == 0) {
            Some(0)
        } else if i >= last {
            Some(u64::from(last.checked_sub(first)?) + 1)
        } else {
            Some(u64::from(i - first) + 1)
        }
    }
}

/// A time sampling: time per cycle and the times of one cycle.
#[derive(Clone, Debug)]
struct TimeSampling {
    time_per_cycle: f64,
    times: Vec<f64>,
}

/// Little-endian readers over a header buffer that fail instead of panicking.
struct Cursor<'a> {
    b: &'a [u8],
    at: usize,
    what: &'static str,
}

impl<'a> Cursor<'a> {
    fn new(b: &'a [u8], what: &'static str) -> Self {
        Cursor { b, at: 0, what }
    }
    fn done(&self) -> bool {
        self.at >= self.b.len()
    }
    fn take(&mut self, n: usize) -> std::result::Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.b.len()).ok_or_else(|| {
            format!("{} cut short: {n} bytes needed at byte {} of {}", self.what, self.at, self.b.len())
        })?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u8(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u16(&mut self) -> std::result::Result<u16, String> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }
    fn u32(&mut self) -> std::result::Result<u32, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn f64(&mut self) -> std::result::Result<f64, String> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(f64::from_le_bytes(a))
    }
    /// A `u32` stored in 1, 2 or 4 bytes (`hint` 0, 1, 2).
    fn hinted(&mut self, hint: u32) -> std::result::Result<u32, String> {
        match hint {
            0 => self.u8().map(u32::from),
            1 => self.u16().map(u32::from),
            2 => self.u32(),
            _ => Err(format!("{}: bad size hint {hint}", self.what)),
        }
    }
    fn text(&mut self, n: usize) -> std::result::Result<String, String> {
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }
}

/// The schemas of objects this reader tells apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Schema {
    PolyMesh,
    Xform,
    Other,
}

impl Schema {
    /// The schema named in object metadata.
    fn of(meta: &str) -> Schema {
        match meta_value(meta, "schema") {
            Some(POLYMESH_SCHEMA) => Schema::PolyMesh,
            Some(XFORM_SCHEMA) => Schema::Xform,
            _ => Schema::Other,
        }
    }
}

/// The value of `key` in Alembic metadata (`key=value;key=value`).
fn meta_value<'m>(meta: &'m str, key: &str) -> Option<&'m str> {
    meta.split(';').find_map(|kv| kv.split_once('=').filter(|(k, _)| *k == key).map(|(_, v)| v))
}

/// The archive: its time samplings, indexed metadata and top object.
struct Archive<'a> {
    time_samplings: Vec<TimeSampling>,
    metadata: Vec<String>,
    top: Group<'a>,
    /// Header bytes parsed so far, and the most allowed (the file's length: each header block
    /// once; a crafted file sharing one block between many groups stops here).
    parsed: u64,
    budget: u64,
}

fn i32_data(d: &[u8], what: &str) -> std::result::Result<i32, String> {
    let b: [u8; 4] = d
        .try_into()
        .map_err(|_| format!("{what} is {} bytes, expected 4", d.len()))?;
    Ok(i32::from_le_bytes(b))
}

impl<'a> Archive<'a> {
    fn open(file: &Ogawa<'a>) -> std::result::Result<Self, String> {
        let root = file.root()?;
        let layout_ok = root.len() >= 6
            && root.is_data(0)
            && root.is_data(1)
            && root.is_group(2)
            && root.is_data(3)
            && root.is_data(4)
            && root.is_data(5);
        if !layout_ok {
            return Err(format!(
                "not an Alembic archive: the root group ({} children) lacks the version, \
                 top object, time samplings and metadata Alembic puts there",
                root.len()
            ));
        }
        let version = i32_data(root.data(0)?, "the archive version")?;
        if !(0..=1).contains(&version) {
            return Err(format!("unsupported Alembic archive version {version} (expected 0 or 1)"));
        }
        let library = i32_data(root.data(1)?, "the library version")?;
        if library < MIN_LIBRARY_VERSION {
            return Err(format!("unsupported Alembic library version {library} (expected {MIN_LIBRARY_VERSION} or later)"));
        }
        let time_samplings = parse_time_samplings(root.data(4)?)?;
        let metadata = parse_indexed_metadata(root.data(5)?)?;
        Ok(Archive {
            time_samplings,
            metadata,
            top: root.group(2)?,
            parsed: 0,
            budget: file.len(),
        })
    }

    fn charge(&mut self, bytes: usize) -> std::result::Result<(), String> {
        self.parsed += bytes as u64;
        if self.parsed > self.budget {
            return Err("the object tree refers to the same headers again and again (more header bytes than the file holds)".into());
        }
        Ok(())
    }

    /// The indexed metadata entry `index`.
    fn indexed(&self, index: u32, what: &str) -> std::result::Result<&str, String> {
        self.metadata
            .get(index as usize)
            .map(String::as_str)
            .ok_or_else(|| format!("{what}: metadata index {index} but the archive indexes {}", self.metadata.len()))
    }

    /// The headers of `group`'s child objects: name and schema.
    fn object_headers(&mut self, group: &Group<'a>) -> std::result::Result<Vec<(String, Schema)>, String> {
        let n = group.len();
        if n == 0 || !group.is_data(n - 1) {
            return Ok(Vec::new());
        }
        let data = group.data(n - 1)?;
        self.charge(data.len())?;
        if data.len() <= 32 {
            return Ok(Vec::new());
        }
        let mut c = Cursor::new(&data[..data.len() - 32], "object headers");
        let mut out = Vec::new();
        while !c.done() {
            let size = c.u32()? as usize;
            if size == 0 {
                return Err("object headers: an object without a name".into());
            }
            let name = c.text(size)?;
            let index = c.u8()?;
            let schema = if index == 0xff {
                let size = c.u32()? as usize;
                Schema::of(&String::from_utf8_lossy(c.take(size)?))
            } else {
                Schema::of(self.indexed(u32::from(index), "object headers")?)
            };
            out.push((name, schema));
        }
        Ok(out)
    }

    /// The property headers of a compound property group.
    fn property_headers(&mut self, group: &Group<'a>) -> std::result::Result<Vec<PropertyHeader>, String> {
        let n = group.len();
        if n == 0 || !group.is_data(n - 1) {
            return Ok(Vec::new());
        }
        let data = group.data(n - 1)?;
        self.charge(data.len())?;
        let mut c = Cursor::new(data, "property headers");
        let mut out = Vec::new();
        while !c.done() {
            let info = c.u32()?;
            let kind = match info & 3 {
                0 => Kind::Compound,
                1 => Kind::Scalar,
                _ => Kind::Array,
            };
            let hint = (info >> 2) & 3;
            let mut h = PropertyHeader {
                name: String::new(),
                kind,
                pod: Pod::Other(0xff),
                extent: 0,
                samples: 0,
                first_changed: 0,
                last_changed: 0,
                time_sampling: 0,
            };
            if kind != Kind::Compound {
                let pod = ((info >> 4) & 0xf) as u8;
                if pod > 13 {
                    return Err(format!("property headers: unknown data type {pod}"));
                }
                h.pod = Pod::of(pod);
                h.extent = ((info >> 12) & 0xff) as u8;
                h.samples = c.hinted(hint)?;
                if info & 0x200 != 0 {
                    h.first_changed = c.hinted(hint)?;
                    h.last_changed = c.hinted(hint)?;
                } else if info & 0x800 != 0 {
                    (h.first_changed, h.last_changed) = (0, 0);
                } else {
                    h.first_changed = 1;
                    h.last_changed = h.samples.saturating_sub(1);
                }
                if info & 0x100 != 0 {
                    h.time_sampling = c.hinted(hint)?;
                }
            }
            let size = c.hinted(hint)? as usize;
            if size == 0 {
                return Err("property headers: a property without a name".into());
            }
            h.name = c.text(size)?;
            let meta_index = (info >> 20) & 0xff;
            if meta_index == 0xff {
                let size = c.hinted(hint)? as usize;
                c.take(size)?;
            } else {
                self.indexed(meta_index, "property headers")?;
            }
            out.push(h);
        }
        Ok(out)
    }
}

fn parse_time_samplings(data: &[u8]) -> std::result::Result<Vec<TimeSampling>, String> {
    let mut c = Cursor::new(data, "time samplings");
    let mut out = Vec::new();
    while !c.done() {
        let _max_sample = c.u32()?;
        let time_per_cycle = c.f64()?;
        let n = c.u32()? as usize;
        if n == 0 {
            return Err("time samplings: a sampling with no sample times".into());
        }
        // Checked against the buffer before allocating.
        let raw = c.take(n.checked_mul(8).ok_or("time samplings: count overflows")?)?;
        let times = raw
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
            .collect();
        out.push(TimeSampling { time_per_cycle, times });
    }
    Ok(out)
}

fn parse_indexed_metadata(data: &[u8]) -> std::result::Result<Vec<String>, String> {
    // Entry 0 is the empty metadata; the archive indexes at most 255 more, each under 256 bytes.
    let mut out = vec![String::new()];
    let mut c = Cursor::new(data, "indexed metadata");
    while !c.done() {
        let n = c.u8()? as usize;
        out.push(c.text(n)?);
        if out.len() > 256 {
            return Err("indexed metadata: more than 255 entries".into());
        }
    }
    Ok(out)
}

/// Object trees deeper than this are refused (real scenes are a few levels deep).
const MAX_DEPTH: usize = 1000;
const XFORM_SCHEMA: &str = "AbcGeom_Xform_v3";

/// An object of the tree walked so far.
struct Node<'a> {
    name: String,
    group: Group<'a>,
    parent: Option<usize>,
    depth: usize,
    is_xform: bool,
    /// The object `--object` names, or one below it (every object when none is named).
    chosen: bool,
}

/// The object tree walked down to the PolyMesh sought.
struct Tree<'a> {
    nodes: Vec<Node<'a>>,
}

impl Tree<'_> {
    /// The full path of node `i` (`/Cube/CubeShape`).
    fn path(&self, i: usize) -> String {
        let mut names = Vec::new();
        let mut at = Some(i);
        while let Some(n) = at {
            names.push(self.nodes[n].name.as_str());
            at = self.nodes[n].parent;
        }
        names.iter().rev().fold(String::new(), |p, n| p + "/" + n)
    }

    /// Whether node `i` is the object `wanted`: its name, or its full path when `wanted`
    /// starts with `/` (compared upwards, without building the path).
    fn is(&self, i: usize, wanted: &str) -> bool {
        let Some(path) = wanted.strip_prefix('/') else {
            return self.nodes[i].name == wanted;
        };
        let mut at = Some(i);
        for part in path.rsplit('/') {
            match at {
                Some(n) if self.nodes[n].name == part => at = self.nodes[n].parent,
                _ => return false,
            }
        }
        at.is_none()
    }

    /// The Xform ancestors of node `i`, outermost first.
    fn xforms(&self, i: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut at = self.nodes[i].parent;
        while let Some(n) = at {
            if self.nodes[n].is_xform {
                out.push(n);
            }
            at = self.nodes[n].parent;
        }
        out.reverse();
        out
    }
}

/// The first PolyMesh (depth-first) that `wanted` names (by name or full path) or that lies
/// below the object it names (Maya's transform `body` above `bodyShape`), else the first,
/// with the tree walked to reach it; also the paths of (up to 10) other PolyMeshes seen, for the
/// error when none matches.
fn find_polymesh<'a>(
    archive: &mut Archive<'a>,
    wanted: Option<&str>,
) -> std::result::Result<(Tree<'a>, Option<usize>, Vec<String>), String> {
    let mut seen_groups = HashSet::new();
    let mut tree = Tree { nodes: Vec::new() };
    let mut others = Vec::new();
    // Depth-first with an explicit stack: a crafted tree cannot exhaust the call stack.
    let mut stack: Vec<(Option<usize>, Group<'a>)> = vec![(None, archive.top)];
    while let Some((node, group)) = stack.pop() {
        let where_ = |tree: &Tree| escape_control(&node.map_or("/".to_string(), |n| tree.path(n))).into_owned();
        if group.offset() != 0 && !seen_groups.insert(group.offset()) {
            return Err(format!("object {}: its group is reached twice (a cycle in the object tree)", where_(&tree)));
        }
        let depth = node.map_or(0, |n| tree.nodes[n].depth + 1);
        if depth > MAX_DEPTH {
            return Err(format!("the object tree is deeper than {MAX_DEPTH} levels"));
        }
        let headers = archive.object_headers(&group).map_err(|e| format!("object {}: {e}", where_(&tree)))?;
        let mut children = Vec::with_capacity(headers.len());
        for (i, (name, schema)) in headers.into_iter().enumerate() {
            let child = group
                .group(i as u64 + 1)
                .map_err(|e| format!("object {}/{}: {e}", where_(&tree), escape_control(&name)))?;
            let parent_chosen = node.is_some_and(|n| tree.nodes[n].chosen);
            tree.nodes.push(Node {
                name,
                group: child,
                parent: node,
                depth,
                is_xform: schema == Schema::Xform,
                chosen: false,
            });
            let id = tree.nodes.len() - 1;
            let chosen = wanted.is_none_or(|w| parent_chosen || tree.is(id, w));
            tree.nodes[id].chosen = chosen;
            if schema == Schema::PolyMesh {
                if chosen {
                    return Ok((tree, Some(id), others));
                }
                if others.len() < 10 {
                    others.push(tree.path(id));
                }
            }
            children.push((Some(id), child));
        }
        stack.extend(children.into_iter().rev());
    }
    Ok((tree, None, others))
}

/// Where a sample lies in time: sample `i` of a sampling.
fn sample_time(ts: &TimeSampling, i: u32) -> f64 {
    let n = ts.times.len().max(1);
    if ts.time_per_cycle >= ACYCLIC_TIME_PER_CYCLE {
        return ts.times.get(i as usize).or(ts.times.last()).copied().unwrap_or(0.0);
    }
    let (cycle, k) = (i as usize / n, i as usize % n);
    ts.times.get(k).copied().unwrap_or(0.0) + cycle as f64 * ts.time_per_cycle
}

/// The sample (of `samples`) of a sampling nearest to time `t`.
fn sample_near(ts: &TimeSampling, samples: u32, t: f64) -> u32 {
    // Times increase with the index: the first sample at or after t, or the one before it.
    let (mut lo, mut hi) = (0u32, samples.saturating_sub(1));
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if sample_time(ts, mid) < t {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    if lo > 0 && (t - sample_time(ts, lo - 1)).abs() <= (sample_time(ts, lo) - t).abs() {
        lo - 1
    } else {
        lo
    }
}

/// An Xform's operations and its channel values per stored sample.
struct Xform {
    path: String,
    ops: Vec<u8>,
    header: Option<PropertyHeader>,
    values: Vec<Vec<f64>>,
    inherits: bool,
}

impl Xform {
    /// The matrix at time `t`.
    fn matrix_at(&self, samplings: &[TimeSampling], t: f64) -> std::result::Result<nalgebra::Matrix4<f64>, String> {
        let vals = match &self.header {
            Some(h) if h.samples > 1 => {
                let ts = samplings.get(h.time_sampling as usize).ok_or_else(|| {
                    format!("Xform {}: time sampling {} is not in the archive", escape_control(&self.path), h.time_sampling)
                })?;
                let k = sample_near(ts, h.samples, t);
                let stored = h.stored_index(k).unwrap_or(0) as usize;
                self.values.get(stored).or(self.values.last())
            }
            _ => self.values.first(),
        };
        let defaults;
        let vals = match vals {
            Some(v) => v,
            None => {
                defaults = super::alembic_xform::default_values(&self.ops);
                &defaults
            }
        };
        super::alembic_xform::matrix(&self.ops, vals).map_err(|e| format!("Xform {}: {e}", escape_control(&self.path)))
    }
}

/// The values of a scalar property's stored sample `stored` (after the 16-byte key), `size`
/// bytes per value.
fn scalar_sample<'a>(h: &PropertyHeader, g: &Group<'a>, stored: u64, size: usize) -> std::result::Result<&'a [u8], String> {
    let data = g.data(stored).map_err(|e| format!("{} sample {stored}: {e}", h.name))?;
    let want = size * h.extent as usize;
    if data.len() != 16 + want {
        return Err(format!("{} sample {stored}: {} bytes, expected a 16-byte key and {want} bytes", h.name, data.len()));
    }
    Ok(&data[16..])
}

fn f64s(values: &[u8]) -> Vec<f64> {
    values
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
        .collect()
}

/// Reads the Xform object `group` (`.xform`: `.ops`, `.vals`, `.inherits`).
fn read_xform<'a>(archive: &mut Archive<'a>, path: String, group: &Group<'a>) -> std::result::Result<Xform, String> {
    let mut x = Xform { path, ops: Vec::new(), header: None, values: Vec::new(), inherits: true };
    let at = |e: String| format!("Xform {}: {e}", escape_control(&x.path));
    if group.is_empty() || !group.is_group(0) {
        return Ok(x);
    }
    let props = group.group(0).map_err(at)?;
    let Some((xh, xg)) = property(archive, &props, ".xform").map_err(at)? else {
        return Ok(x);
    };
    if xh.kind != Kind::Compound {
        return Err(at(".xform is not a compound property".into()));
    }
    let headers = archive.property_headers(&xg).map_err(at)?;
    for (i, h) in headers.iter().enumerate() {
        let g = || xg.group(i as u64);
        match h.name.as_str() {
            ".ops" if h.samples > 0 => {
                if h.kind != Kind::Scalar || h.pod != Pod::Uint8 {
                    return Err(at(format!(".ops is {} {:?}, expected uint8 scalar", h.pod.name(), h.kind)));
                }
                x.ops = scalar_sample(h, &g().map_err(at)?, 0, 1).map_err(at)?.to_vec();
            }
            ".inherits" if h.samples > 0 => {
                if h.kind != Kind::Scalar || !matches!(h.pod, Pod::Bool | Pod::Uint8) || h.extent != 1 {
                    return Err(at(format!(".inherits is {} x{}, expected bool", h.pod.name(), h.extent)));
                }
                x.inherits = scalar_sample(h, &g().map_err(at)?, 0, 1).map_err(at)?[0] != 0;
            }
            ".vals" if h.samples > 0 => {
                if h.pod != Pod::Float64 || h.kind == Kind::Compound {
                    return Err(at(format!(".vals is {} {:?}, expected float64", h.pod.name(), h.kind)));
                }
                let vg = g().map_err(at)?;
                let last = h.stored_index(h.samples - 1).ok_or_else(|| at(".vals: inconsistent sample indices".into()))?;
                for k in 0..=last {
                    let bytes = if h.kind == Kind::Scalar {
                        scalar_sample(h, &vg, k, 8)
                    } else {
                        array_sample(h, &vg, k)
                    }
                    .map_err(at)?;
                    x.values.push(f64s(bytes));
                }
                x.header = Some(h.clone());
            }
            _ => {}
        }
    }
    let need = super::alembic_xform::channel_count(&x.ops).map_err(at)?;
    if let Some(bad) = x.values.iter().position(|v| v.len() != need) {
        return Err(at(format!(
            ".vals sample {bad} has {} values, the operations take {need}",
            x.values[bad].len()
        )));
    }
    Ok(x)
}

/// The sub-property `name` of a compound group, with its group.
fn property<'a>(
    archive: &mut Archive<'a>,
    compound: &Group<'a>,
    name: &str,
) -> std::result::Result<Option<(PropertyHeader, Group<'a>)>, String> {
    let headers = archive.property_headers(compound)?;
    let Some(i) = headers.iter().position(|h| h.name == name) else {
        return Ok(None);
    };
    let group = compound.group(i as u64)?;
    Ok(Some((headers[i].clone(), group)))
}

/// The values of stored sample `stored` of an array property: the bytes after the 16-byte key,
/// checked against the element size and the recorded dimensions.
fn array_sample<'a>(h: &PropertyHeader, g: &Group<'a>, stored: u64) -> std::result::Result<&'a [u8], String> {
    let elem = h.pod.size().ok_or_else(|| format!("{} values are {}, not read", h.name, h.pod.name()))? * h.extent as usize;
    let data = g.data(2 * stored).map_err(|e| format!("{} sample {stored}: {e}", h.name))?;
    if data.is_empty() {
        return Ok(data);
    }
    if data.len() < 16 || elem == 0 {
        return Err(format!("{} sample {stored}: {} bytes, not a key and values", h.name, data.len()));
    }
    let values = &data[16..];
    if values.len() % elem != 0 {
        return Err(format!("{} sample {stored}: {} bytes of values, not whole {elem}-byte elements", h.name, values.len()));
    }
    let dims = g.data(2 * stored + 1).map_err(|e| format!("{} sample {stored} dimensions: {e}", h.name))?;
    if !dims.is_empty() {
        if dims.len() % 8 != 0 {
            return Err(format!("{} sample {stored}: dimensions of {} bytes", h.name, dims.len()));
        }
        let count = dims.chunks_exact(8).try_fold(1u64, |acc, d| {
            acc.checked_mul(u64::from_le_bytes(d.try_into().unwrap_or([0xff; 8])))
        });
        if count != Some((values.len() / elem) as u64) {
            return Err(format!(
                "{} sample {stored}: dimensions do not match its {} elements",
                h.name,
                values.len() / elem
            ));
        }
    }
    Ok(values)
}

fn int32s(values: &[u8]) -> impl Iterator<Item = i32> + '_ {
    values.chunks_exact(4).map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The frames per second of a time sampling: uniform (one time per cycle), or acyclic with
/// evenly spaced times.
fn sampling_fps(ts: &TimeSampling, what: &str) -> std::result::Result<f64, String> {
    let fps = if ts.time_per_cycle >= ACYCLIC_TIME_PER_CYCLE {
        let steps: Vec<f64> = ts.times.windows(2).map(|w| w[1] - w[0]).collect();
        let Some(&dt) = steps.first() else {
            return Err(format!("{what}'s acyclic time sampling has a single time: no frame rate"));
        };
        if steps.iter().any(|s| (s - dt).abs() > 1e-9 * dt.abs()) {
            return Err(format!("{what}'s time sampling is acyclic with uneven steps: no frame rate"));
        }
        1.0 / dt
    } else if ts.times.len() == 1 {
        1.0 / ts.time_per_cycle
    } else {
        return Err(format!(
            "{what}'s time sampling is cyclic ({} samples per cycle), not uniform: no frame rate",
            ts.times.len()
        ));
    };
    // 1 / (1/24) may come back as 24.000000000000004: snap to a thousandth when that close.
    let snapped = (fps * 1000.0).round() / 1000.0;
    let fps = if (fps - snapped).abs() <= 1e-9 * fps.abs() { snapped } else { fps };
    crate::frame_rate::check_fps(fps).map_err(|e| format!("{what}'s time sampling: {e}"))
}

/// Refuses `n_frames` frames of `n_vertices` vertices (f64) when they need more than
/// [`EXPANSION_LIMIT`] times a file of `file_len` bytes.
fn check_expansion(n_frames: usize, n_vertices: usize, file_len: usize) -> std::result::Result<(), String> {
    let needed = (n_frames as u128) * (n_vertices as u128) * 24;
    if needed > u128::from(EXPANSION_LIMIT) * file_len as u128 {
        return Err(format!(
            "P has {n_frames} samples of {n_vertices} points: {needed} bytes of frames, more than \
             {EXPANSION_LIMIT} times the file's {file_len} bytes (samples stored once and repeated)"
        ));
    }
    Ok(())
}

/// Reads a PolyMesh from an Alembic file held in memory: the one named `object` (its name or
/// full path), else the first. The error is the problem without the file name.
pub fn parse_alembic(bytes: &[u8], object: Option<&str>) -> std::result::Result<AlembicMesh, String> {
    let file = Ogawa::parse(bytes)?;
    let mut archive = Archive::open(&file)?;
    let (tree, found, others) = find_polymesh(&mut archive, object)?;
    let Some(mesh_node) = found else {
        return Err(match object {
            Some(w) if !others.is_empty() => format!(
                "no PolyMesh at or below '{}' (the file has {})",
                escape_control(w),
                escape_control(&others.join(", "))
            ),
            Some(w) => format!("no PolyMesh at or below '{}' (the file has none)", escape_control(w)),
            None => "holds no PolyMesh (only PolyMesh objects are read)".into(),
        });
    };
    let path = tree.path(mesh_node);
    let group = tree.nodes[mesh_node].group;
    let at = |e: String| format!("PolyMesh {}: {e}", escape_control(&path));
    if !group.is_group(0) {
        return Err(at("has no properties".into()));
    }
    let props = group.group(0).map_err(at)?;
    let (geom_h, geom) = property(&mut archive, &props, ".geom")
        .map_err(at)?
        .ok_or_else(|| at("has no .geom properties".into()))?;
    if geom_h.kind != Kind::Compound {
        return Err(at(".geom is not a compound property".into()));
    }
    // The .geom headers parsed once, each property looked up in them.
    let geom_headers = archive.property_headers(&geom).map_err(at)?;
    let array = |name: &str| -> std::result::Result<(PropertyHeader, Group), String> {
        let i = geom_headers.iter().position(|h| h.name == name).ok_or_else(|| format!("has no {name}"))?;
        let (h, g) = (geom_headers[i].clone(), geom.group(i as u64)?);
        if h.kind != Kind::Array {
            return Err(format!("{name} is not an array property"));
        }
        Ok((h, g))
    };
    let (p_h, p_g) = array("P").map_err(at)?;
    let (counts_h, counts_g) = array(".faceCounts").map_err(at)?;
    let (indices_h, indices_g) = array(".faceIndices").map_err(at)?;

    // Topology: every stored sample equal to the first.
    let mut topology = Vec::with_capacity(2);
    for (h, g) in [(&counts_h, &counts_g), (&indices_h, &indices_g)] {
        if h.pod != Pod::Int32 || h.extent != 1 {
            return Err(at(format!("{} is {} x{}, expected int32", h.name, h.pod.name(), h.extent)));
        }
        if h.samples == 0 {
            return Err(at(format!("{} has no samples", h.name)));
        }
        let last = h.stored_index(h.samples - 1).ok_or_else(|| at(format!("{}: inconsistent sample indices", h.name)))?;
        let first = array_sample(h, g, 0).map_err(at)?;
        for k in 1..=last {
            if array_sample(h, g, k).map_err(at)? != first {
                return Err(at(format!(
                    "{} changes at stored sample {k}: only constant topology is read",
                    h.name
                )));
            }
        }
        topology.push(first);
    }
    let (counts, indices) = (topology[0], topology[1]);

    // Points.
    if !matches!(p_h.pod, Pod::Float32 | Pod::Float64) || p_h.extent != 3 {
        return Err(at(format!("P is {} x{}, expected float32 or float64 x3", p_h.pod.name(), p_h.extent)));
    }
    if p_h.samples == 0 {
        return Err(at("P has no samples".into()));
    }
    let first = array_sample(&p_h, &p_g, 0).map_err(at)?;
    let elem = p_h.pod.size().unwrap_or(4) * 3;
    let n_vertices = first.len() / elem;
    if n_vertices == 0 {
        return Err(at("P has no points".into()));
    }
    let decode = |values: &[u8], k: u32| -> std::result::Result<Vec<Vector3<f64>>, String> {
        let mut v = Vec::with_capacity(values.len() / elem);
        for (j, e) in values.chunks_exact(elem).enumerate() {
            let p = if p_h.pod == Pod::Float32 {
                let f = |i: usize| f64::from(f32::from_le_bytes([e[i], e[i + 1], e[i + 2], e[i + 3]]));
                Vector3::new(f(0), f(4), f(8))
            } else {
                let f = |i: usize| {
                    let mut a = [0u8; 8];
                    a.copy_from_slice(&e[i..i + 8]);
                    f64::from_le_bytes(a)
                };
                Vector3::new(f(0), f(8), f(16))
            };
            if !p.iter().all(|c| c.is_finite()) {
                return Err(format!("P sample {k}, point {j}: coordinate is not finite"));
            }
            v.push(p);
        }
        Ok(v)
    };
    let samplings = std::mem::take(&mut archive.time_samplings);
    let sampling = |index: u32, what: &str| -> std::result::Result<TimeSampling, String> {
        samplings.get(index as usize).cloned().ok_or_else(|| {
            at(format!("{what}'s time sampling {index} is not in the archive's {}", samplings.len()))
        })
    };
    let p_ts = sampling(p_h.time_sampling, "P")?;
    // The Xforms above the mesh, outermost first: frame k is placed by their matrices at its
    // time (each Xform's sample nearest that time).
    let mut xforms = Vec::new();
    for n in tree.xforms(mesh_node) {
        let node_path = tree.path(n);
        xforms.push(read_xform(&mut archive, node_path, &tree.nodes[n].group)?);
    }
    // The frames are P's samples; points that never change under an animated Xform (a rigid
    // object's motion: Blender writes P once) follow the Xform with the most samples instead.
    let animated = xforms.iter().filter_map(|x| x.header.as_ref()).filter(|h| h.samples > 1).max_by_key(|h| h.samples);
    let (ts, n_frames, follows_p) = match animated {
        Some(h) if p_h.samples == 1 => (sampling(h.time_sampling, "its Xform")?, h.samples, false),
        _ => (p_ts.clone(), p_h.samples, true),
    };
    let fps = sampling_fps(&ts, if follows_p { "P" } else { "its Xform" }).map_err(at)?;
    let start_time = ts.times.first().copied().unwrap_or(0.0);
    check_expansion(n_frames as usize, n_vertices, bytes.len()).map_err(at)?;
    let mut frames: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(n_frames as usize);
    let mut local: Vec<Vector3<f64>> = Vec::new();
    let mut last_stored = None;
    for k in 0..n_frames {
        let t = sample_time(&ts, k);
        let pk = if follows_p { k } else { sample_near(&p_ts, p_h.samples, t) };
        let stored = p_h.stored_index(pk).ok_or_else(|| at("P: inconsistent sample indices".into()))?;
        if last_stored != Some(stored) {
            let values = array_sample(&p_h, &p_g, stored).map_err(at)?;
            if values.len() / elem != n_vertices {
                return Err(at(format!(
                    "P sample {pk} has {} points, sample 0 has {n_vertices}: only constant topology is read",
                    values.len() / elem
                )));
            }
            local = decode(values, pk).map_err(at)?;
            last_stored = Some(stored);
        }
        let mut world = nalgebra::Matrix4::identity();
        for x in &xforms {
            let m = x.matrix_at(&samplings, t)?;
            world = if x.inherits { world * m } else { m };
        }
        if world == nalgebra::Matrix4::identity() {
            frames.push(local.clone());
        } else {
            let placed: Vec<Vector3<f64>> = local.iter().map(|p| (world * p.push(1.0)).xyz()).collect();
            if let Some(j) = placed.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
                return Err(at(format!("P sample {k}, point {j}: not finite once placed by its Xforms")));
            }
            frames.push(placed);
        }
    }

    // Faces: clockwise polygons reversed and fan-triangulated.
    let mut faces = Vec::with_capacity(indices.len() / 4);
    let mut all = int32s(indices);
    let mut poly = Vec::new();
    let mut skipped = 0;
    let mut used = 0usize;
    for (f, count) in int32s(counts).enumerate() {
        let count = usize::try_from(count).map_err(|_| at(format!("face {f} has {count} corners")))?;
        if count > indices.len() / 4 - used {
            return Err(at(format!(
                ".faceCounts asks for more corners than the {} of .faceIndices",
                indices.len() / 4
            )));
        }
        used += count;
        poly.clear();
        for _ in 0..count {
            let i = all.next().unwrap_or(-1);
            if i < 0 || i as usize >= n_vertices {
                return Err(at(format!("face {f}: vertex index {i} out of range (0..{n_vertices})")));
            }
            poly.push(i as u32);
        }
        poly.reverse();
        skipped += super::push_fan(&mut faces, &poly);
    }
    if used != indices.len() / 4 {
        return Err(at(format!(
            ".faceCounts covers {used} corners but .faceIndices has {}",
            indices.len() / 4
        )));
    }

    Ok(AlembicMesh {
        path,
        sequence: MeshSequence::new(faces, frames),
        fps,
        start_time,
        skipped_faces: skipped,
    })
}

/// Reads a PolyMesh from the Alembic file `path` (see [`parse_alembic`]); errors are one line
/// naming the file.
pub fn read_alembic(path: impl AsRef<Path>, object: Option<&str>) -> Result<AlembicMesh> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    let mesh = parse_alembic(&bytes, object).map_err(|m| Error::file(path, m))?;
    super::warn_skipped_faces(path, mesh.skipped_faces);
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Vec<u8> {
        std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/alembic/cube.abc")).unwrap()
    }

    /// `fixtures/alembic/cube.abc`, written by Blender 5.0.1 (`fixtures/alembic/cube.py`): a cube
    /// with a shape key, turned, scaled and moving (an animated Xform above the mesh), read back
    /// as the world-space values Blender printed (7 decimals), turned +Z up -> +Y up.
    #[test]
    fn blenders_cube_reads_as_blender_had_it() {
        let m = parse_alembic(&cube(), None).unwrap();
        assert_eq!(m.path, "/Cube/CubeShape");
        assert_eq!(m.fps, 25.0);
        assert!((m.start_time - 0.04).abs() < 1e-12, "{}", m.start_time);
        assert_eq!(m.skipped_faces, 0);
        let blender: [[[f64; 3]; 8]; 3] = [
            [[0.2554128, -2.2618861, 1.2268115], [0.4457921, -2.4879124, 2.182148],
             [-0.9754766, -0.8005229, 1.817852], [-0.7850972, -1.0265492, 2.7731886],
             [1.7850972, -0.9734508, 1.2268115], [1.9754765, -1.1994772, 2.182148],
             [0.5542079, 0.4879125, 1.817852], [0.7445872, 0.2618862, 2.7731886]],
            [[0.5935379, -1.9577692, 1.2010374], [0.8697543, -2.2080913, 2.3952079],
             [-0.8685894, -0.0666433, 1.9398379], [-0.5923732, -0.3169653, 3.1340086],
             [2.658612, -0.2183814, 1.2010374], [2.9348283, -0.4687035, 2.3952079],
             [1.1964844, 1.6727444, 1.9398379], [1.4727008, 1.4224224, 3.1340086]],
            [[0.9316632, -1.6536522, 1.1752632], [1.2937164, -1.92827, 2.608268],
             [-0.7617023, 0.6672363, 2.0618238], [-0.3996491, 0.3926186, 3.4948287],
             [3.5321267, 0.5366879, 1.1752632], [3.8941798, 0.2620701, 2.608268],
             [1.8387611, 2.8575764, 2.0618238], [2.2008145, 2.5829587, 3.4948287]],
        ];
        assert_eq!(m.sequence.n_frames(), 3);
        for (frame, want) in m.sequence.frames.iter().zip(&blender) {
            assert_eq!(frame.len(), 8);
            for (got, b) in frame.iter().zip(want) {
                let want = Vector3::new(b[0], b[2], -b[1]);
                assert!((got - want).amax() < 1e-6, "{got:?} vs {want:?}");
            }
        }
        // Blender's quads, counter-clockwise as Blender has them, fan-triangulated.
        let quads = [[0, 1, 3, 2], [2, 3, 7, 6], [6, 7, 5, 4], [4, 5, 1, 0], [2, 6, 4, 0], [7, 3, 1, 5]];
        let want: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        assert_eq!(m.sequence.faces, want);
        // Outward normals: the faces wind counter-clockwise seen from outside.
        let f0 = &m.sequence.frames[0];
        let middle = f0.iter().sum::<Vector3<f64>>() / 8.0;
        for t in &m.sequence.faces {
            let [a, b, c] = t.map(|i| f0[i as usize]);
            let centre = (a + b + c) / 3.0 - middle;
            assert!((b - a).cross(&(c - a)).dot(&centre) > 0.0, "{t:?} winds inwards");
        }
        // Picked by name or by path; a missing name lists the meshes there are.
        assert_eq!(parse_alembic(&cube(), Some("CubeShape")).unwrap().path, "/Cube/CubeShape");
        assert_eq!(parse_alembic(&cube(), Some("/Cube/CubeShape")).unwrap().path, "/Cube/CubeShape");
        // The Xform above it names it too.
        assert_eq!(parse_alembic(&cube(), Some("Cube")).unwrap().path, "/Cube/CubeShape");
        assert_eq!(parse_alembic(&cube(), Some("/Cube")).unwrap().path, "/Cube/CubeShape");
        let err = parse_alembic(&cube(), Some("Suzanne")).unwrap_err();
        assert_eq!(err, "no PolyMesh at or below 'Suzanne' (the file has /Cube/CubeShape)");
        for wrong in ["/CubeShape", "/X/CubeShape", "Cube/CubeShape", "//Cube/CubeShape", "/"] {
            assert!(parse_alembic(&cube(), Some(wrong)).unwrap_err().starts_with("no PolyMesh at or below"), "{wrong}");
        }
    }

    /// `fixtures/alembic/rigid.abc` (`rigid.py`): a mesh that does not deform under an animated
    /// parent, written by Blender as one sample of points below animated Xforms (/Rig, /Rig/Tet),
    /// reads as Blender's world-space frames, at the Xforms' 4 samples and 30 fps; the still
    /// `Ball` beside it by `--object`.
    #[test]
    fn a_rigid_motion_is_the_xforms_frames() {
        let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/alembic/rigid.abc")).unwrap();
        let m = parse_alembic(&bytes, None).unwrap();
        assert_eq!((m.path.as_str(), m.fps, m.sequence.n_frames()), ("/Rig/Tet/TetShape", 30.0, 4));
        let blender = [
            [[1.4794255, 2.0, 3.8775826], [2.357008, 2.0, 3.3981571], [1.4794255, 3.0, 3.8775826], [1.9588511, 2.0, 4.7551651]],
            [[1.9476438, 2.0, 3.7253461], [2.6729898, 2.0, 3.0369618], [1.9476438, 3.0, 3.7253461], [2.6360281, 2.0, 4.4506922]],
            [[2.6867652, 2.0, 3.3240955], [3.0108607, 2.0, 2.3780711], [2.6867652, 3.0, 3.3240955], [3.6327896, 2.0, 3.648191]],
            [[2.9974949, 2.0, 3.0707371], [3.0682321, 2.0, 2.0732422], [2.9974949, 3.0, 3.0707371], [3.9949899, 2.0, 3.1414742]],
        ];
        for (frame, want) in m.sequence.frames.iter().zip(&blender) {
            for (got, b) in frame.iter().zip(want) {
                let want = Vector3::new(b[0], b[2], -b[1]);
                assert!((got - want).amax() < 1e-6, "{got:?} vs {want:?}");
            }
        }
        assert_eq!(m.sequence.faces, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
        let ball = parse_alembic(&bytes, Some("Ball")).unwrap();
        assert_eq!((ball.path.as_str(), ball.sequence.n_frames(), ball.sequence.n_vertices()), ("/Ball/Icosphere", 1, 12));
        assert!(ball.sequence.frames[0].iter().all(|p| (p.x - 3.0).abs() <= 1.0 + 1e-6));
        for n in 0..bytes.len() {
            assert!(parse_alembic(&bytes[..n], None).is_err(), "prefix of {n} bytes read");
        }
    }

    /// Every proper prefix of the fixture is an error, never a panic.
    #[test]
    fn every_truncation_is_an_error() {
        let bytes = cube();
        for n in 0..bytes.len() {
            assert!(parse_alembic(&bytes[..n], None).is_err(), "prefix of {n} bytes read");
        }
    }

    /// Every single-bit flip of the fixture reads or fails, never panics, and a read keeps the
    /// sequence's shape consistent.
    #[test]
    fn bit_flips_never_panic() {
        let bytes = cube();
        for i in 0..bytes.len() {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[i] ^= 1 << bit;
                if let Ok(m) = parse_alembic(&b, None) {
                    let n = m.sequence.n_vertices();
                    assert!(m.sequence.frames.iter().all(|f| f.len() == n));
                    assert!(m.sequence.faces.iter().flatten().all(|&v| (v as usize) < n));
                    assert!(crate::frame_rate::check_fps(m.fps).is_ok());
                }
            }
        }
    }

    /// Errors read as one line naming the file.
    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.abc");
        std::fs::write(&path, &cube()[..1000]).unwrap();
        let err = read_alembic(&path, None).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}: ", path.display())) && err.lines().count() == 1, "{err}");
        std::fs::write(&path, b"POINTCACHE2\0 and more bytes").unwrap();
        let err = read_alembic(&path, None).unwrap_err().to_string();
        assert!(err.ends_with("not an Alembic (Ogawa) file: it does not start with \"Ogawa\""), "{err}");
    }

    /// A few bytes claiming 4 billion repeats of one stored sample are refused before allocating.
    #[test]
    fn repeats_beyond_the_files_size_are_refused() {
        assert!(check_expansion(3, 8, 3258).is_ok());
        assert!(check_expansion(1000, 100_000, 300_000_000).is_ok());
        let err = check_expansion(u32::MAX as usize, 8, 3258).unwrap_err();
        assert!(err.contains("more than 32 times the file's 3258 bytes"), "{err}");
    }

    #[test]
    fn repeated_samples_map_to_the_stored_ones() {
        let h = |samples, first_changed, last_changed| PropertyHeader {
            name: "P".into(),
            kind: Kind::Array,
            pod: Pod::Float32,
            extent: 3,
            samples,
            first_changed,
            last_changed,
            time_sampling: 0,
        };
        // All distinct: sample i is stored sample i.
        assert_eq!((0..5).map(|i| h(5, 1, 4).stored_index(i)).collect::<Vec<_>>(), [0, 1, 2, 3, 4].map(Some));
        // Constant: one stored sample.
        assert_eq!(h(5, 0, 0).stored_index(4), Some(0));
        // Equal to sample 0 until 2, changing until 3, then held.
        assert_eq!((0..6).map(|i| h(6, 2, 3).stored_index(i)).collect::<Vec<_>>(), [0, 0, 1, 2, 2, 2].map(Some));
        assert_eq!(h(6, 3, 2).stored_index(5), None);
    }

    #[test]
    fn frame_rates_of_time_samplings() {
        let ts = |time_per_cycle, times: &[f64]| TimeSampling { time_per_cycle, times: times.to_vec() };
        assert_eq!(sampling_fps(&ts(1.0 / 24.0, &[0.0]), "P"), Ok(24.0));
        assert_eq!(sampling_fps(&ts(1.0 / 25.0, &[1.0 / 25.0]), "P"), Ok(25.0));
        assert!((sampling_fps(&ts(1001.0 / 30000.0, &[0.0]), "P").unwrap() - 30000.0 / 1001.0).abs() < 1e-9);
        assert_eq!(sampling_fps(&ts(ACYCLIC_TIME_PER_CYCLE, &[0.0, 0.02, 0.04]), "P"), Ok(50.0));
        assert!(sampling_fps(&ts(ACYCLIC_TIME_PER_CYCLE, &[0.0, 0.02, 0.05]), "P").unwrap_err().contains("uneven"));
        assert!(sampling_fps(&ts(1.0, &[0.0, 0.5]), "P").unwrap_err().contains("cyclic"));
        assert!(sampling_fps(&ts(1e-300, &[0.0]), "P").unwrap_err().contains("outside 1 to 10000 fps"));
        assert!(sampling_fps(&ts(0.0, &[0.0]), "P").is_err());
        assert!(sampling_fps(&ts(-0.04, &[0.0]), "P").is_err());
        // Sample times, and the sample of an animated Xform nearest a frame's time.
        let uniform = ts(0.04, &[0.04]);
        assert!((sample_time(&uniform, 2) - 0.12).abs() < 1e-15);
        assert_eq!([0.08, 0.081, 10.0, -5.0].map(|t| sample_near(&uniform, 3, t)), [1, 1, 2, 0]);
        let acyclic = ts(ACYCLIC_TIME_PER_CYCLE, &[0.0, 0.5, 2.0]);
        assert_eq!([0.2, 0.3, 1.9, 9.0].map(|t| sample_near(&acyclic, 3, t)), [0, 1, 2, 2]);
        assert_eq!(sample_near(&uniform, 0, 1.0), 0);
    }
}
