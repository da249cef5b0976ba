//! PLY input and output.
//!
//! Reading accepts ascii, binary little- and big-endian files with float or
//! double `x y z` and any polygon faces (`vertex_indices` or `vertex_index`,
//! a list of any integer type), fan-triangulated: polygon `(p0, p1, ..., pk)`
//! becomes `(p0, pj, pj+1)` for `j = 1..k-1`. Other elements and properties
//! are ignored.
//!
//! The header is parsed by ply-rs-bw. Before any payload is read, each
//! element count is checked against the bytes that follow the header (an
//! element needs at least 1 byte in ascii and the sum of its scalar sizes in
//! binary), so a crafted header cannot make the reader allocate more than the
//! file justifies. Binary files with the common layout (`vertex` with scalar
//! properties, then `face` with the index list and possibly scalars) are
//! decoded by a direct fast path; everything else goes through ply-rs-bw's
//! generic payload reader. A sequence's later frames ([`read_ply_like`]) whose
//! bytes outside the vertex records equal its first frame's take the first
//! frame's faces without decoding them again.
//!
//! Writing produces binary little-endian (double `x y z`, `list uchar int
//! vertex_indices`) by default, ascii on request, always atomically.

use std::io::Write;
use std::path::Path;

use nalgebra::Vector3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};

use crate::atomic::write_atomic;
use crate::error::{Error, Result};
use crate::mesh::TriMesh;

/// How a PLY file's payload is encoded when writing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PlyEncoding {
    #[default]
    BinaryLittleEndian,
    BinaryBigEndian,
    Ascii,
}

/// Scalar type of the written coordinates (`Float` rounds to f32).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PlyPrecision {
    Float,
    #[default]
    Double,
}

/// Options for [`write_ply_with`]. The default is binary little-endian, double.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct PlyOptions {
    pub encoding: PlyEncoding,
    pub precision: PlyPrecision,
}

/// Reads and validates a PLY mesh (see the module doc); errors are one line
/// naming the file.
pub fn read_ply(path: impl AsRef<Path>) -> Result<TriMesh> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    let (mesh, skipped) = parse(&bytes, true).map_err(|msg| Error::file(path, msg))?;
    super::warn_skipped_faces(path, skipped);
    Ok(mesh)
}

/// Parses a PLY file held in memory (fast path for common binary layouts).
/// The mesh is validated ([`TriMesh::validate`]).
pub fn parse_ply(bytes: &[u8]) -> std::result::Result<TriMesh, String> {
    parse(bytes, true).map(|(mesh, _)| mesh)
}

/// Parses a PLY file held in memory always through ply-rs-bw's generic
/// payload reader (the reference the fast path is tested against).
pub fn parse_ply_generic(bytes: &[u8]) -> std::result::Result<TriMesh, String> {
    parse(bytes, false).map(|(mesh, _)| mesh)
}

/// Writes `mesh` as binary little-endian PLY (double coordinates), atomically.
pub fn write_ply(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<()> {
    write_ply_with(path, mesh, PlyOptions::default())
}

/// Writes `mesh` as ascii PLY (coordinates printed to round-trip exactly), atomically.
pub fn write_ply_ascii(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<()> {
    let opts = PlyOptions {
        encoding: PlyEncoding::Ascii,
        precision: PlyPrecision::Double,
    };
    write_ply_with(path, mesh, opts)
}

/// Writes `mesh` as PLY with the given encoding and precision, atomically.
pub fn write_ply_with(path: impl AsRef<Path>, mesh: &TriMesh, opts: PlyOptions) -> Result<()> {
    write_atomic(path.as_ref(), |w| encode_ply(w, mesh, opts))
}

/// Serialises `mesh` as PLY into `w`.
pub fn encode_ply(w: &mut dyn Write, mesh: &TriMesh, opts: PlyOptions) -> std::io::Result<()> {
    let (format, le) = match opts.encoding {
        PlyEncoding::BinaryLittleEndian => ("binary_little_endian", true),
        PlyEncoding::BinaryBigEndian => ("binary_big_endian", false),
        PlyEncoding::Ascii => ("ascii", true),
    };
    let scalar = match opts.precision {
        PlyPrecision::Float => "float",
        PlyPrecision::Double => "double",
    };
    write!(
        w,
        "ply\nformat {format} 1.0\ncomment surfcap\nelement vertex {}\n",
        mesh.vertices.len()
    )?;
    for c in ["x", "y", "z"] {
        writeln!(w, "property {scalar} {c}")?;
    }
    write!(
        w,
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.faces.len()
    )?;
    if opts.encoding == PlyEncoding::Ascii {
        for v in &mesh.vertices {
            match opts.precision {
                PlyPrecision::Double => writeln!(w, "{} {} {}", v.x, v.y, v.z)?,
                PlyPrecision::Float => writeln!(w, "{} {} {}", v.x as f32, v.y as f32, v.z as f32)?,
            }
        }
        for f in &mesh.faces {
            writeln!(w, "3 {} {} {}", f[0], f[1], f[2])?;
        }
        return Ok(());
    }
    let mut buf = Vec::with_capacity(mesh.vertices.len() * 24 + mesh.faces.len() * 13);
    for v in &mesh.vertices {
        for c in [v.x, v.y, v.z] {
            match (opts.precision, le) {
                (PlyPrecision::Double, true) => buf.extend_from_slice(&c.to_le_bytes()),
                (PlyPrecision::Double, false) => buf.extend_from_slice(&c.to_be_bytes()),
                (PlyPrecision::Float, true) => buf.extend_from_slice(&(c as f32).to_le_bytes()),
                (PlyPrecision::Float, false) => buf.extend_from_slice(&(c as f32).to_be_bytes()),
            }
        }
    }
    for f in &mesh.faces {
        buf.push(3);
        for &i in f {
            let i = i as i32;
            buf.extend_from_slice(&if le { i.to_le_bytes() } else { i.to_be_bytes() });
        }
    }
    w.write_all(&buf)
}

// ---------------------------------------------------------------- reading

const INDEX_NAMES: [&str; 2] = ["vertex_indices", "vertex_index"];

/// The validated mesh and the number of degenerate faces skipped.
fn parse(bytes: &[u8], allow_fast: bool) -> std::result::Result<(TriMesh, usize), String> {
    parse_keeping_records(bytes, allow_fast).map(|(mesh, skipped, _)| (mesh, skipped))
}

/// [`parse`], with where the vertex records lie when the fast reader took the file (their
/// first byte in `bytes` and their layout).
fn parse_keeping_records(bytes: &[u8], allow_fast: bool) -> std::result::Result<(TriMesh, usize, Option<(usize, VertexRecords)>), String> {
    let mut reader = Reader::new(bytes);
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| format!("malformed PLY header: {}", one_line(&e.to_string())))?;
    let payload_len = reader.get_ref().len();
    check_counts(&header, payload_len)?;
    let layout = Layout::of(&header)?;
    let mut records = None;
    let (mesh, skipped) = if allow_fast && header.encoding != Encoding::Ascii && layout.fast {
        let payload: &[u8] = reader.get_ref();
        records = Some((bytes.len() - payload_len, VertexRecords::of(&header, &layout)));
        read_binary_fast(payload, &header, &layout)?
    } else {
        read_generic(&mut reader, &header, &layout)?
    };
    if mesh.vertices.is_empty() {
        return Err("no vertices (element vertex is empty)".into());
    }
    mesh.validate().map_err(|e| e.to_string())?;
    Ok((mesh, skipped, records))
}

/// A sequence's first frame as [`read_ply_like`] compares its later frames with: its mesh, the
/// degenerate faces skipped, and for a binary file of the fast reader's layout its bytes and
/// where its vertex records lie in them.
pub struct PlyFirstFrame {
    pub mesh: TriMesh,
    skipped: usize,
    bytes: Option<(Vec<u8>, usize, VertexRecords)>,
}

/// Reads a sequence's first frame as [`read_ply`] does, keeping what [`read_ply_like`] needs.
pub fn read_ply_first(path: impl AsRef<Path>) -> Result<PlyFirstFrame> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    let (mesh, skipped, records) = parse_keeping_records(&bytes, true).map_err(|msg| Error::file(path, msg))?;
    super::warn_skipped_faces(path, skipped);
    Ok(PlyFirstFrame { mesh, skipped, bytes: records.map(|(start, r)| (bytes, start, r)) })
}

/// Reads a later frame of the sequence that starts with `first`, as [`read_ply`] does. A file
/// whose bytes before and after its vertex records equal the first frame's (the same header,
/// so the same layout and counts, and the same face records) has the first frame's faces:
/// only its vertex records are decoded.
pub fn read_ply_like(path: impl AsRef<Path>, first: &PlyFirstFrame) -> Result<TriMesh> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    if let Some((first_bytes, start, records)) = &first.bytes {
        let end = start + records.len();
        if bytes.len() == first_bytes.len() && bytes[..*start] == first_bytes[..*start] && bytes[end..] == first_bytes[end..] {
            let vertices = records.decode(&bytes[*start..]).map_err(|msg| Error::file(path, msg))?;
            let mesh = TriMesh { vertices, faces: first.mesh.faces.clone() };
            mesh.validate().map_err(|e| Error::file(path, e.to_string()))?;
            super::warn_skipped_faces(path, first.skipped);
            return Ok(mesh);
        }
    }
    let (mesh, skipped) = parse(&bytes, true).map_err(|msg| Error::file(path, msg))?;
    super::warn_skipped_faces(path, skipped);
    Ok(mesh)
}

/// Where the vertex coordinates and face indices live in the header.
struct Layout {
    /// Element index of `vertex` and `face` in header order.
    vertex: usize,
    face: Option<usize>,
    /// Name of the face index list property.
    index_name: Option<String>,
    /// True when the fast binary reader handles this layout.
    fast: bool,
}

impl Layout {
    fn of(header: &Header) -> std::result::Result<Self, String> {
        let elements: Vec<&ElementDef> = header.elements.values().collect();
        let vertex = elements
            .iter()
            .position(|e| e.name == "vertex")
            .ok_or("PLY file has no 'vertex' element")?;
        for c in ["x", "y", "z"] {
            match elements[vertex].properties.get(c).map(|p| &p.data_type) {
                Some(PropertyType::Scalar(ScalarType::Float | ScalarType::Double)) => {}
                Some(t) => {
                    return Err(format!(
                        "vertex property '{c}' has type {t:?}; expected float or double"
                    ))
                }
                None => return Err(format!("vertex element has no '{c}' property")),
            }
        }
        let face = elements.iter().position(|e| e.name == "face");
        let mut index_name = None;
        if let Some(f) = face {
            let def = elements[f];
            let name = INDEX_NAMES
                .iter()
                .find(|n| def.properties.contains_key(**n))
                .ok_or("face element has no 'vertex_indices' or 'vertex_index' property")?;
            match &def.properties[*name].data_type {
                PropertyType::List(_, ScalarType::Float | ScalarType::Double)
                | PropertyType::Scalar(_) => {
                    return Err(format!("face property '{name}' must be a list of integers"));
                }
                PropertyType::List(..) => {}
            }
            index_name = Some(name.to_string());
        }
        let scalar_only = |e: &ElementDef| {
            e.properties
                .values()
                .all(|p| matches!(p.data_type, PropertyType::Scalar(_)))
        };
        let fast = vertex == 0
            && scalar_only(elements[0])
            && match face {
                None => elements.len() == 1,
                Some(f) => {
                    f == 1
                        && elements.len() == 2
                        && elements[1].properties.values().all(|p| {
                            matches!(p.data_type, PropertyType::Scalar(_))
                                || Some(&p.name) == index_name.as_ref()
                        })
                }
            };
        Ok(Layout {
            vertex,
            face,
            index_name,
            fast,
        })
    }
}

fn scalar_size(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// Rejects headers whose element counts cannot fit in the payload, before
/// anything is allocated for them.
fn check_counts(header: &Header, payload_len: usize) -> std::result::Result<(), String> {
    let mut need: usize = 0;
    for e in header.elements.values() {
        if e.count > 0 && e.properties.is_empty() {
            return Err(format!(
                "element '{}' has {} entries but no properties",
                e.name, e.count
            ));
        }
        let per = match header.encoding {
            Encoding::Ascii => 1,
            _ => e
                .properties
                .values()
                .map(|p| match &p.data_type {
                    PropertyType::Scalar(t) => scalar_size(t),
                    PropertyType::List(n, _) => scalar_size(n),
                })
                .sum(),
        };
        need = e
            .count
            .checked_mul(per)
            .and_then(|b| need.checked_add(b))
            .filter(|&b| b <= payload_len)
            .ok_or_else(|| {
                format!(
                    "header declares {} '{}' elements, more than the {} bytes after the header can hold (truncated or corrupt file)",
                    e.count, e.name, payload_len
                )
            })?;
    }
    Ok(())
}

/// Turns a multi-line ply-rs-bw error into one short line: its first line
/// (which carries the file line number) plus the offending text, if quoted.
fn one_line(s: &str) -> String {
    let mut out = s.lines().next().unwrap_or_default().trim().to_string();
    let quoted = s
        .split_once("String: '")
        .and_then(|(_, rest)| rest.split_once('\''));
    if let Some((text, _)) = quoted {
        out.push_str(&format!(" '{}'", text.trim()));
    }
    let mut out: String = out.split_whitespace().collect::<Vec<_>>().join(" ");
    if out.len() > 200 {
        let mut cut = 200;
        while !out.is_char_boundary(cut) {
            cut -= 1;
        }
        out.truncate(cut);
        out.push_str("...");
    }
    out
}

/// Appends polygon `poly` fan-triangulated to `faces`, checking the indices;
/// counts in `skipped` the degenerate faces left out ([`super::push_fan`]).
fn push_polygon(
    faces: &mut Vec<[u32; 3]>,
    skipped: &mut usize,
    poly: &[i64],
    face: usize,
    n_vertices: usize,
) -> std::result::Result<(), String> {
    if let Some(&i) = poly
        .iter()
        .find(|&&i| i < 0 || i as u64 >= n_vertices as u64)
    {
        return Err(format!(
            "face {face} uses vertex {i}, but the file has {n_vertices} vertices"
        ));
    }
    let poly: Vec<u32> = poly.iter().map(|&i| i as u32).collect();
    *skipped += super::push_fan(faces, &poly);
    Ok(())
}

// ---- fast binary path

/// Cursor over a binary payload with one byte order.
struct Bin<'a> {
    data: &'a [u8],
    pos: usize,
    le: bool,
}

impl Bin<'_> {
    fn take(&mut self, n: usize) -> std::result::Result<&[u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.data.len());
        let end = end.ok_or("file is truncated (payload ends early)")?;
        let s = &self.data[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn float(&mut self, t: &ScalarType) -> std::result::Result<f64, String> {
        let le = self.le;
        Ok(match t {
            ScalarType::Float => {
                let b: [u8; 4] = self.take(4)?.try_into().unwrap();
                (if le {
                    f32::from_le_bytes(b)
                } else {
                    f32::from_be_bytes(b)
                }) as f64
            }
            _ => {
                let b: [u8; 8] = self.take(8)?.try_into().unwrap();
                if le {
                    f64::from_le_bytes(b)
                } else {
                    f64::from_be_bytes(b)
                }
            }
        })
    }
    fn int(&mut self, t: &ScalarType) -> std::result::Result<i64, String> {
        let le = self.le;
        let s = self.take(scalar_size(t))?;
        macro_rules! rd {
            ($ty:ty, $n:expr) => {{
                let b: [u8; $n] = s.try_into().unwrap();
                (if le {
                    <$ty>::from_le_bytes(b)
                } else {
                    <$ty>::from_be_bytes(b)
                }) as i64
            }};
        }
        Ok(match t {
            ScalarType::Char => rd!(i8, 1),
            ScalarType::UChar => rd!(u8, 1),
            ScalarType::Short => rd!(i16, 2),
            ScalarType::UShort => rd!(u16, 2),
            ScalarType::Int => rd!(i32, 4),
            ScalarType::UInt => rd!(u32, 4),
            _ => return Err("list count or index of floating-point type".into()),
        })
    }
}

/// Where `x y z` lie in the fixed-size vertex records of a binary file the fast reader takes.
#[derive(Clone)]
struct VertexRecords {
    /// Byte offset and type of x, y, z within a record.
    coord: [(usize, ScalarType); 3],
    stride: usize,
    count: usize,
    le: bool,
}

impl VertexRecords {
    fn of(header: &Header, layout: &Layout) -> VertexRecords {
        let elements: Vec<&ElementDef> = header.elements.values().collect();
        let vdef = elements[layout.vertex];
        let mut stride = 0;
        let mut coord = [(0usize, ScalarType::Float), (0, ScalarType::Float), (0, ScalarType::Float)];
        for p in vdef.properties.values() {
            let PropertyType::Scalar(t) = &p.data_type else {
                unreachable!("checked by Layout")
            };
            if let Some(k) = ["x", "y", "z"].iter().position(|c| *c == p.name) {
                coord[k] = (stride, t.clone());
            }
            stride += scalar_size(t);
        }
        VertexRecords { coord, stride, count: vdef.count, le: header.encoding == Encoding::BinaryLittleEndian }
    }

    fn len(&self) -> usize {
        self.count * self.stride
    }

    /// The vertices of the records at the start of `payload`.
    fn decode(&self, payload: &[u8]) -> std::result::Result<Vec<Vector3<f64>>, String> {
        let vbytes = payload.get(..self.len()).ok_or("file is truncated (vertex data ends early)")?;
        let mut vertices = Vec::with_capacity(self.count);
        for rec in vbytes.chunks_exact(self.stride) {
            let mut xyz = [0.0; 3];
            for (k, (off, t)) in self.coord.iter().enumerate() {
                xyz[k] = Bin { data: rec, pos: *off, le: self.le }.float(t)?;
            }
            vertices.push(Vector3::new(xyz[0], xyz[1], xyz[2]));
        }
        Ok(vertices)
    }
}

fn read_binary_fast(
    payload: &[u8],
    header: &Header,
    layout: &Layout,
) -> std::result::Result<(TriMesh, usize), String> {
    let mut skipped = 0;
    let le = header.encoding == Encoding::BinaryLittleEndian;
    let elements: Vec<&ElementDef> = header.elements.values().collect();
    let records = VertexRecords::of(header, layout);
    let (n, stride) = (records.count, records.stride);
    let vertices = records.decode(payload)?;
    let mut faces = Vec::new();
    if let Some(f) = layout.face {
        let fdef = elements[f];
        let name = layout.index_name.as_deref().unwrap_or_default();
        faces.reserve(fdef.count);
        let mut bin = Bin {
            data: payload,
            pos: n * stride,
            le,
        };
        let mut poly: Vec<i64> = Vec::with_capacity(8);
        for face in 0..fdef.count {
            for p in fdef.properties.values() {
                match &p.data_type {
                    PropertyType::Scalar(t) => {
                        bin.take(scalar_size(t))?;
                    }
                    PropertyType::List(ct, it) => {
                        let count = bin.int(ct)?;
                        if count < 0 || p.name != name {
                            return Err(format!("face {face}: bad list length {count}"));
                        }
                        poly.clear();
                        for _ in 0..count {
                            poly.push(bin.int(it)?);
                        }
                    }
                }
            }
            push_polygon(&mut faces, &mut skipped, &poly, face, n)?;
        }
    }
    Ok((TriMesh { vertices, faces }, skipped))
}

// ---- generic path (ply-rs-bw payload reader)

/// Element that ignores every property.
struct Skip;
impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

/// Vertex record: only `x y z` are kept.
#[derive(Default)]
struct PlyVertex([f64; 3]);
impl PlyVertex {
    fn set(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        match name {
            "x" => self.0[0] = v,
            "y" => self.0[1] = v,
            "z" => self.0[2] = v,
            _ => return PropertyAccessResult::Ignored,
        }
        PropertyAccessResult::Set
    }
}
impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex::default()
    }
    fn set_float(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        self.set(name, v as f64)
    }
    fn set_double(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        self.set(name, v)
    }
}

/// Face record: only the vertex index list is kept, widened to i64.
#[derive(Default)]
struct PlyFace(Vec<i64>);
impl PlyFace {
    fn set<T: Into<i64>>(&mut self, name: &str, v: Vec<T>) -> PropertyAccessResult {
        if INDEX_NAMES.contains(&name) {
            self.0 = v.into_iter().map(Into::into).collect();
            PropertyAccessResult::Set
        } else {
            PropertyAccessResult::Ignored
        }
    }
}
impl PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace::default()
    }
    fn set_list_char(&mut self, name: &str, v: Vec<i8>) -> PropertyAccessResult {
        self.set(name, v)
    }
    fn set_list_uchar(&mut self, name: &str, v: Vec<u8>) -> PropertyAccessResult {
        self.set(name, v)
    }
    fn set_list_short(&mut self, name: &str, v: Vec<i16>) -> PropertyAccessResult {
        self.set(name, v)
    }
    fn set_list_ushort(&mut self, name: &str, v: Vec<u16>) -> PropertyAccessResult {
        self.set(name, v)
    }
    fn set_list_int(&mut self, name: &str, v: Vec<i32>) -> PropertyAccessResult {
        self.set(name, v)
    }
    fn set_list_uint(&mut self, name: &str, v: Vec<u32>) -> PropertyAccessResult {
        self.set(name, v)
    }
}

fn read_generic(
    reader: &mut Reader<&[u8]>,
    header: &Header,
    layout: &Layout,
) -> std::result::Result<(TriMesh, usize), String> {
    let mut skipped = 0;
    let err = |e: ply_rs_bw::parser::ParseError| one_line(&e.to_string());
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for (i, def) in header.elements.values().enumerate() {
        if i == layout.vertex {
            let vs = Parser::<PlyVertex>::new()
                .read_payload_for_element(reader, def, header)
                .map_err(err)?;
            vertices = vs.into_iter().map(|v| Vector3::from(v.0)).collect();
        } else if Some(i) == layout.face {
            let fs = Parser::<PlyFace>::new()
                .read_payload_for_element(reader, def, header)
                .map_err(err)?;
            faces.reserve(fs.len());
            for (k, f) in fs.iter().enumerate() {
                push_polygon(
                    &mut faces,
                    &mut skipped,
                    &f.0,
                    k,
                    layout_vertex_count(header, layout),
                )?;
            }
        } else {
            Parser::<Skip>::new()
                .read_payload_for_element(reader, def, header)
                .map_err(err)?;
        }
    }
    Ok((TriMesh { vertices, faces }, skipped))
}

fn layout_vertex_count(header: &Header, layout: &Layout) -> usize {
    header.elements[layout.vertex].count
}
