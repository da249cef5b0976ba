//! The artifact container: the one file format stages pass to each other.
//!
//! Byte layout (all integers little-endian):
//!
//! | bytes        | content                                                    |
//! |--------------|------------------------------------------------------------|
//! | 8            | magic `SURFCAP\0`                                          |
//! | 4 (u32)      | container format version ([`CONTAINER_VERSION`])           |
//! | 4 (u32) + k  | length of the artifact kind, then the kind (UTF-8)        |
//! | 4 (u32)      | artifact-kind version                                      |
//! | 8 (u64) + h  | length of the JSON header, then the header ([`Header`])    |
//! | 8 (u64) + p  | length of the payload, then the payload (bincode 2, `standard()` config, serde) |
//! | 32           | SHA-256 of every preceding byte                            |
//!
//! The header records provenance (producer, command line, parameters, seed,
//! SHA-256 of the inputs) and nothing time-dependent, so the same inputs and
//! seed give a byte-identical file. Writes are atomic
//! ([`crate::atomic::write_atomic`]).
//!
//! Reading trusts nothing: every length is checked against the bytes that
//! remain before anything is allocated, the checksum is verified before the
//! header or payload is parsed, and the payload decoder has a byte limit of
//! [`DECODE_EXPANSION`] (32) times the payload's length, so a crafted length
//! inside the payload cannot allocate more than the file justifies (sequences
//! are capped by serde itself at 1 MiB of up-front reservation). Decoded
//! payloads are then checked by [`Artifact::validate`]. Each failure is one
//! [`Error::File`] line naming the file, e.g.
//! `model.art: expected artifact kind 'pca-model', found 'gpr-model'`.

use std::io::Read;
use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::error::{Error, Result};

/// The eight magic bytes every artifact starts with.
pub const MAGIC: [u8; 8] = *b"SURFCAP\0";
/// Version of the container layout described in the module documentation.
pub const CONTAINER_VERSION: u32 = 1;
/// Longest artifact kind name accepted (a sanity bound, not a format limit).
pub const MAX_KIND_LEN: usize = 256;
const CHECKSUM_LEN: usize = 32;

/// Which stage wrote an artifact.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Producer {
    /// Stage (binary) name, e.g. `"align"`.
    pub stage: String,
    /// Version of the crate that holds the stage, e.g. `"0.1.0"`.
    pub version: String,
}

/// One input file of a stage and the SHA-256 of its bytes (lowercase hex).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputRecord {
    pub path: String,
    pub sha256: String,
}

/// Provenance header of an artifact, stored as JSON.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub producer: Producer,
    /// The stage's command line, for stages that record no params; the program name is
    /// reduced to its file name so the record does not depend on where the binary was built.
    pub command_line: Vec<String>,
    /// The stage's parameters (its parsed options), any JSON value.
    pub params: serde_json::Value,
    /// Random seed, for stages that use randomness.
    pub seed: Option<u64>,
    /// Input files and their hashes.
    pub inputs: Vec<InputRecord>,
}

impl Header {
    /// A header for `stage` of crate version `version` (pass
    /// `env!("CARGO_PKG_VERSION")`), with no command line, params, seed or inputs.
    pub fn new(stage: &str, version: &str) -> Self {
        Header {
            producer: Producer {
                stage: stage.to_string(),
                version: version.to_string(),
            },
            command_line: Vec::new(),
            params: serde_json::Value::Null,
            seed: None,
            inputs: Vec::new(),
        }
    }

    /// Records the given command line (argument 0 reduced to its file name).
    pub fn with_command_line<I, S>(mut self, args: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        self.command_line = args.into_iter().map(Into::into).collect();
        if let Some(first) = self.command_line.first_mut() {
            if let Some(name) = Path::new(first.as_str()).file_name() {
                *first = name.to_string_lossy().into_owned();
            }
        }
        self
    }

    /// Records this process's command line ([`std::env::args_os`], lossily UTF-8).
    pub fn with_process_command_line(self) -> Self {
        let args: Vec<String> = std::env::args_os()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        self.with_command_line(args)
    }

    /// Records the stage parameters (anything serde can turn into JSON) and drops the
    /// command line: the parsed parameters describe the run completely, while the command
    /// line also holds flags that change no output (`-v`, `--threads`), so a header with
    /// params is the same bytes however the stage was invoked.
    pub fn with_params<P: Serialize>(mut self, params: &P) -> Result<Self> {
        self.params = serde_json::to_value(params)
            .map_err(|e| Error::invalid(format!("cannot record parameters as JSON: {e}")))?;
        self.command_line.clear();
        Ok(self)
    }

    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = Some(seed);
        self
    }

    /// Records `path` (as given) as an input whose SHA-256 is `sha256`, from a read that hashed
    /// it on the way (e.g. [`Artifact::load_hashed`]).
    pub fn with_input_hashed(mut self, path: impl AsRef<Path>, sha256: String) -> Self {
        self.inputs.push(InputRecord { path: path.as_ref().display().to_string(), sha256 });
        self
    }

    /// Hashes `path` and records it as an input (path as given).
    pub fn with_input(mut self, path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let sha256 = sha256_file(path)?;
        self.inputs.push(InputRecord {
            path: path.display().to_string(),
            sha256,
        });
        Ok(self)
    }
}

/// A payload type with a fixed artifact kind and version, so stages can write
/// `PcaModel::load(path)?` and `model.save(path, &header)?`.
pub trait Artifact: Serialize + DeserializeOwned {
    /// Kind name written in the file, e.g. `"pca-model"`.
    const KIND: &'static str;
    /// Version of this kind's payload layout; bump it when the struct changes.
    const VERSION: u32;

    /// Checks every index and size of a decoded payload against the rest of
    /// it, so consumers can index without bounds failures. A valid checksum only
    /// says the file was not corrupted in transit; a rewritten file with a
    /// recomputed checksum reaches this check. The error is the problem,
    /// without the file name.
    fn validate(&self) -> std::result::Result<(), String> {
        Ok(())
    }

    /// Writes `self` to `path` atomically.
    fn save(&self, path: impl AsRef<Path>, header: &Header) -> Result<()> {
        write_artifact(path, Self::KIND, Self::VERSION, header, self)
    }
    /// Reads the payload, checking kind, version and checksum.
    fn load(path: impl AsRef<Path>) -> Result<Self> {
        Ok(Self::load_with_header(path)?.1)
    }
    /// Reads header and payload, checking kind, version, checksum and
    /// [`Artifact::validate`].
    fn load_with_header(path: impl AsRef<Path>) -> Result<(Header, Self)> {
        let path = path.as_ref();
        let (header, payload): (Header, Self) = read_artifact(path, Self::KIND, Self::VERSION)?;
        payload
            .validate()
            .map_err(|msg| Error::file(path, format!("invalid '{}' payload: {msg}", Self::KIND)))?;
        Ok((header, payload))
    }

    /// [`Artifact::load`], and the SHA-256 of the file for an input record (the value of
    /// [`sha256_file`], from the read and the hash that verify the checksum: one pass).
    fn load_hashed(path: impl AsRef<Path>) -> Result<(Self, String)> {
        let path = path.as_ref();
        let bytes = crate::input::read_regular_file(path)?;
        let (_, payload, sha256): (Header, Self, String) =
            decode_artifact_hashed(&bytes, Self::KIND, Self::VERSION).map_err(|msg| Error::file(path, msg))?;
        payload
            .validate()
            .map_err(|msg| Error::file(path, format!("invalid '{}' payload: {msg}", Self::KIND)))?;
        Ok((payload, sha256))
    }

    /// Decodes and validates an artifact held in memory (the error without the file name).
    fn decode(bytes: &[u8]) -> std::result::Result<(Header, Self), String> {
        let (header, payload): (Header, Self) = decode_artifact(bytes, Self::KIND, Self::VERSION)?;
        payload
            .validate()
            .map_err(|msg| format!("invalid '{}' payload: {msg}", Self::KIND))?;
        Ok((header, payload))
    }
}

/// For [`Artifact::validate`]: the first index in `indices` that is not below
/// `bound`, as an error naming `what()`.
pub fn check_indices(
    indices: impl IntoIterator<Item = u32>,
    bound: usize,
    what: impl Fn() -> String,
) -> std::result::Result<(), String> {
    match indices.into_iter().find(|&i| i as usize >= bound) {
        Some(i) => Err(format!("{} has index {i}, but only {bound} are valid", what())),
        None => Ok(()),
    }
}

/// For [`Artifact::validate`] of part sets: `parts` (each part's template
/// vertex list) hold only indices below `n_vertices` and together cover
/// every template vertex. Checks the count first, so a crafted `n_vertices`
/// allocates nothing the file does not justify.
pub fn check_cover(n_vertices: usize, parts: &[&[u32]]) -> std::result::Result<(), String> {
    let total: usize = parts.iter().map(|p| p.len()).sum();
    if parts.is_empty() || n_vertices == 0 || n_vertices > total {
        return Err(format!(
            "{} parts holding {total} vertices cannot cover a template of {n_vertices} vertices",
            parts.len()
        ));
    }
    let mut covered = vec![false; n_vertices];
    for (k, p) in parts.iter().enumerate() {
        check_indices(p.iter().copied(), n_vertices, || format!("part {k}'s vertex list"))?;
        for &v in p.iter() {
            covered[v as usize] = true;
        }
    }
    match covered.iter().position(|c| !c) {
        Some(v) => Err(format!("template vertex {v} is in no part")),
        None => Ok(()),
    }
}

/// What `inspect` reports about an artifact (checksum verified).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ArtifactInfo {
    pub container_version: u32,
    pub kind: String,
    pub kind_version: u32,
    pub header: Header,
    pub payload_bytes: u64,
}

/// Encodes an artifact to bytes (see the module documentation for the layout).
pub fn encode_artifact<T: Serialize + ?Sized>(
    kind: &str,
    kind_version: u32,
    header: &Header,
    payload: &T,
) -> Result<Vec<u8>> {
    let header_json = header_bytes(kind, header)?;
    // The payload is sized first, then encoded in place: a model can be hundreds of MB, and
    // neither a second copy of it nor a reallocation of the buffer is made.
    let encoding_error = |e: bincode::error::EncodeError| Error::invalid(format!("cannot encode '{kind}' payload: {e}"));
    let mut size = bincode::enc::write::SizeWriter::default();
    bincode::serde::encode_into_writer(payload, &mut size, bincode::config::standard()).map_err(encoding_error)?;
    let mut out = Vec::with_capacity(
        8 + 4 + 4 + kind.len() + 4 + 8 + header_json.len() + 8 + size.bytes_written + CHECKSUM_LEN,
    );
    out.extend_from_slice(&prefix(kind, kind_version, &header_json, size.bytes_written as u64));
    let written = bincode::serde::encode_into_std_write(payload, &mut out, bincode::config::standard()).map_err(encoding_error)?;
    debug_assert_eq!(written, size.bytes_written);
    let digest = Sha256::digest(&out);
    out.extend_from_slice(&digest);
    Ok(out)
}

/// The header as JSON, after checking the kind's length.
fn header_bytes(kind: &str, header: &Header) -> Result<Vec<u8>> {
    if kind.is_empty() || kind.len() > MAX_KIND_LEN {
        return Err(Error::invalid(format!(
            "artifact kind must be 1 to {MAX_KIND_LEN} bytes, got {:?}",
            kind
        )));
    }
    serde_json::to_vec(header).map_err(|e| Error::invalid(format!("cannot encode artifact header: {e}")))
}

/// Every byte of the container before the payload.
fn prefix(kind: &str, kind_version: u32, header_json: &[u8], payload_len: u64) -> Vec<u8> {
    let mut out = Vec::with_capacity(8 + 4 + 4 + kind.len() + 4 + 8 + header_json.len() + 8);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&CONTAINER_VERSION.to_le_bytes());
    out.extend_from_slice(&(kind.len() as u32).to_le_bytes());
    out.extend_from_slice(kind.as_bytes());
    out.extend_from_slice(&kind_version.to_le_bytes());
    out.extend_from_slice(&(header_json.len() as u64).to_le_bytes());
    out.extend_from_slice(header_json);
    out.extend_from_slice(&payload_len.to_le_bytes());
    out
}

/// The bytes `value` takes in a payload (bincode 2, `standard()` config), e.g. to add up the
/// length [`write_artifact_streamed`] needs before the payload is written.
pub fn encoded_len<T: Serialize + ?Sized>(value: &T) -> Result<u64> {
    let mut size = bincode::enc::write::SizeWriter::default();
    bincode::serde::encode_into_writer(value, &mut size, bincode::config::standard())
        .map_err(|e| Error::invalid(format!("cannot encode payload: {e}")))?;
    Ok(size.bytes_written as u64)
}

/// The bytes a sequence's length takes in a payload, before its elements: a `Vec<T>` of `n`
/// elements is this length and then each element's encoding.
pub fn encoded_seq_len(n: usize) -> u64 {
    // A sequence's length is encoded as the u64 it is.
    encoded_len(&(n as u64)).unwrap_or(9)
}

/// A payload being written piece by piece by [`write_artifact_streamed`]: the pieces are
/// encoded as serde and bincode encode a struct's fields, in order and without separators.
pub struct PayloadWriter<'a> {
    out: &'a mut dyn std::io::Write,
    path: &'a Path,
    written: u64,
}

impl PayloadWriter<'_> {
    /// Appends `value`'s encoding (a whole field, or one element of a sequence field).
    pub fn encode<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<()> {
        let n = bincode::serde::encode_into_std_write(value, &mut self.out, bincode::config::standard()).map_err(
            |e| match e {
                bincode::error::EncodeError::Io { inner, .. } => Error::io(self.path, inner),
                e => Error::file(self.path, format!("cannot encode payload: {e}")),
            },
        )?;
        self.written += n as u64;
        Ok(())
    }

    /// Appends the length of a sequence field whose `n` elements follow.
    pub fn seq_len(&mut self, n: usize) -> Result<()> {
        self.encode(&(n as u64))
    }
}

/// A writer that hashes every byte it passes on.
struct HashingWriter<'a> {
    inner: &'a mut dyn std::io::Write,
    hasher: Sha256,
}

impl std::io::Write for HashingWriter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Writes an artifact whose payload `fill` writes piece by piece ([`PayloadWriter`]), so that
/// a payload larger than memory never is in memory: the container's bytes go to a temporary
/// file as they are made and are hashed on the way, and the file is renamed onto `path` once
/// the checksum is appended ([`crate::atomic::write_atomic_with`]). `payload_len` is the
/// payload's length in bytes (the container stores it before the payload; [`encoded_len`] and
/// [`encoded_seq_len`] add it up). The file is that of [`write_artifact`] with the value the
/// pieces encode, byte for byte. If `fill` fails, or writes other than `payload_len` bytes,
/// nothing is left at `path` and its error is returned as it is.
pub fn write_artifact_streamed<F>(
    path: impl AsRef<Path>,
    kind: &str,
    kind_version: u32,
    header: &Header,
    payload_len: u64,
    fill: F,
) -> Result<()>
where
    F: FnOnce(&mut PayloadWriter<'_>) -> Result<()>,
{
    let path = path.as_ref();
    let header_json = header_bytes(kind, header).map_err(|e| Error::file(path, e.to_string()))?;
    crate::atomic::write_atomic_with(path, |w| {
        let mut hashing = HashingWriter { inner: w, hasher: Sha256::new() };
        std::io::Write::write_all(&mut hashing, &prefix(kind, kind_version, &header_json, payload_len))
            .map_err(|e| Error::io(path, e))?;
        let written = {
            let mut payload = PayloadWriter { out: &mut hashing, path, written: 0 };
            fill(&mut payload)?;
            payload.written
        };
        if written != payload_len {
            return Err(Error::file(
                path,
                format!("the '{kind}' payload written is {written} bytes, not the {payload_len} announced"),
            ));
        }
        let digest = hashing.hasher.finalize();
        hashing.inner.write_all(&digest).map_err(|e| Error::io(path, e))
    })
}

/// Writes an artifact atomically (temporary file, then rename).
pub fn write_artifact<T: Serialize + ?Sized>(
    path: impl AsRef<Path>,
    kind: &str,
    kind_version: u32,
    header: &Header,
    payload: &T,
) -> Result<()> {
    let path = path.as_ref();
    let bytes = encode_artifact(kind, kind_version, header, payload)
        .map_err(|e| Error::file(path, e.to_string()))?;
    crate::atomic::write_bytes_atomic(path, &bytes)
}

/// Reads an artifact of kind `kind` and version `kind_version`: header and payload.
pub fn read_artifact<T: DeserializeOwned>(
    path: impl AsRef<Path>,
    kind: &str,
    kind_version: u32,
) -> Result<(Header, T)> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    decode_artifact(&bytes, kind, kind_version).map_err(|msg| Error::file(path, msg))
}

/// The error of an artifact of kind version `found` read by a build of version `build`: for an
/// older one, the stage its header names as the producer, whose run in this build re-creates it.
fn version_error(kind: &str, found: u32, build: u32, header_json: &[u8]) -> String {
    let problem = format!("'{kind}' version {found} is not supported (this build reads version {build})");
    match parse_header(header_json) {
        Ok(h) if found < build && !h.producer.stage.is_empty() => {
            format!("{problem}: an older build's, re-create it with this build's {}", h.producer.stage)
        }
        _ => problem,
    }
}

/// Reads kind, kind version and header of any artifact (checksum verified).
pub fn read_header(path: impl AsRef<Path>) -> Result<(String, u32, Header)> {
    let info = inspect_artifact(path)?;
    Ok((info.kind, info.kind_version, info.header))
}

/// Reads everything but the payload of any artifact (checksum verified).
pub fn inspect_artifact(path: impl AsRef<Path>) -> Result<ArtifactInfo> {
    let path = path.as_ref();
    let bytes = crate::input::read_regular_file(path)?;
    let file = |msg: String| Error::file(path, msg);
    let raw = split(&bytes).map_err(file)?;
    let header = parse_header(raw.header_json).map_err(file)?;
    Ok(ArtifactInfo {
        container_version: raw.container_version,
        kind: raw.kind.to_string(),
        kind_version: raw.kind_version,
        header,
        payload_bytes: raw.payload.len() as u64,
    })
}

/// What `inspect` prints for one file: `{"file", "kind", "kind_version",
/// "header", "payload_bytes"}`.
pub fn inspect_json(path: impl AsRef<Path>) -> Result<serde_json::Value> {
    let path = path.as_ref();
    let info = inspect_artifact(path)?;
    Ok(serde_json::json!({
        "file": path.display().to_string(),
        "kind": info.kind,
        "kind_version": info.kind_version,
        "header": info.header,
        "payload_bytes": info.payload_bytes,
    }))
}

/// Decodes an artifact held in memory; the error is the problem without the file name.
pub fn decode_artifact<T: DeserializeOwned>(
    bytes: &[u8],
    kind: &str,
    kind_version: u32,
) -> std::result::Result<(Header, T), String> {
    decode_artifact_hashed(bytes, kind, kind_version).map(|(h, t, _)| (h, t))
}

/// [`decode_artifact`], and the SHA-256 of `bytes` (lowercase hex) from the same pass of the
/// hash that verifies the checksum.
pub fn decode_artifact_hashed<T: DeserializeOwned>(
    bytes: &[u8],
    kind: &str,
    kind_version: u32,
) -> std::result::Result<(Header, T, String), String> {
    let raw = split(bytes)?;
    if raw.kind != kind {
        return Err(format!(
            "expected artifact kind '{kind}', found '{}'",
            raw.kind
        ));
    }
    if raw.kind_version != kind_version {
        return Err(version_error(kind, raw.kind_version, kind_version, raw.header_json));
    }
    let header = parse_header(raw.header_json)?;
    let payload = decode_payload::<T>(raw.payload)
        .map_err(|e| format!("'{kind}' payload does not decode: {e}"))?;
    Ok((header, payload, raw.file_sha256))
}

/// SHA-256 of a file's bytes as lowercase hex (streamed, for input records).
pub fn sha256_file(path: impl AsRef<Path>) -> Result<String> {
    let path = path.as_ref();
    let mut f = crate::input::open_regular_file(path)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf).map_err(|e| Error::io(path, e))?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hex(&hasher.finalize()))
}

fn hex(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    let mut s = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        s.push(DIGITS[(b >> 4) as usize] as char);
        s.push(DIGITS[(b & 15) as usize] as char);
    }
    s
}

/// The sections of a checksum-verified artifact, borrowed from the file bytes.
struct RawArtifact<'a> {
    container_version: u32,
    kind: &'a str,
    kind_version: u32,
    header_json: &'a [u8],
    payload: &'a [u8],
    /// SHA-256 of the whole file, lowercase hex ([`sha256_file`]'s value).
    file_sha256: String,
}

/// Bounds-checked reader over the file bytes.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
    fn take(&mut self, n: u64, what: &str) -> std::result::Result<&'a [u8], String> {
        let rem = self.remaining();
        if n > rem as u64 {
            return Err(format!(
                "truncated: {what} needs {n} bytes at offset {}, {rem} remain",
                self.pos
            ));
        }
        let n = n as usize;
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> std::result::Result<u32, String> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes(b.try_into().expect("4 bytes")))
    }
    fn u64(&mut self, what: &str) -> std::result::Result<u64, String> {
        let b = self.take(8, what)?;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }
}

/// Splits the container into its sections, checking magic, container
/// version, every length against the remaining bytes, and the checksum.
fn split(bytes: &[u8]) -> std::result::Result<RawArtifact<'_>, String> {
    if bytes.len() < MAGIC.len() {
        return Err(if MAGIC.starts_with(bytes) {
            format!(
                "truncated: file is {} bytes, shorter than the magic bytes",
                bytes.len()
            )
        } else {
            "not a surfcap artifact (wrong magic bytes)".to_string()
        });
    }
    if bytes[..MAGIC.len()] != MAGIC {
        return Err("not a surfcap artifact (wrong magic bytes)".to_string());
    }
    let mut c = Cursor {
        bytes,
        pos: MAGIC.len(),
    };
    let container_version = c.u32("container version")?;
    if container_version != CONTAINER_VERSION {
        return Err(format!(
            "container version {container_version} is not supported (this build reads version {CONTAINER_VERSION})"
        ));
    }
    let kind_len = c.u32("kind length")?;
    if kind_len as usize > MAX_KIND_LEN {
        return Err(format!(
            "corrupt: kind length {kind_len} exceeds the maximum of {MAX_KIND_LEN}"
        ));
    }
    let kind = c.take(kind_len as u64, "kind")?;
    let kind_version = c.u32("kind version")?;
    let header_len = c.u64("header length")?;
    let header_json = c.take(header_len, "header")?;
    let payload_len = c.u64("payload length")?;
    let payload = c.take(payload_len, "payload")?;
    let body_end = c.pos;
    let stored = c.take(CHECKSUM_LEN as u64, "checksum")?;
    if c.remaining() != 0 {
        return Err(format!(
            "corrupt: {} unexpected bytes after the checksum",
            c.remaining()
        ));
    }
    let mut hasher = Sha256::new();
    hasher.update(&bytes[..body_end]);
    if hasher.clone().finalize().as_slice() != stored {
        return Err("checksum mismatch (file corrupt)".to_string());
    }
    // The whole file's SHA-256 (what input records hold) continues the checksum's hash.
    hasher.update(stored);
    let file_sha256 = hex(&hasher.finalize());
    let kind = std::str::from_utf8(kind).map_err(|_| "corrupt: kind is not UTF-8".to_string())?;
    Ok(RawArtifact {
        container_version,
        kind,
        kind_version,
        header_json,
        payload,
        file_sha256,
    })
}

fn parse_header(json: &[u8]) -> std::result::Result<Header, String> {
    serde_json::from_slice(json).map_err(|e| format!("header is not valid JSON: {e}"))
}

/// Decodes a bincode payload under a byte limit of [`DECODE_EXPANSION`] times
/// the payload length, rounded up to a power of four (at least 4 KiB).
///
/// bincode 2 claims, against the limit, the in-memory size of every sequence
/// it is about to allocate (`len * size_of::<T>()`): a `Vec<u32>` stored as
/// one-byte varints claims 4 bytes per element, a `Vec<usize>` 8, a
/// `Vec<Vec<_>>` 24 per inner vector. A valid payload therefore needs a limit
/// well above its own length, while a crafted length still fails before
/// allocating more than `DECODE_EXPANSION` times what the file holds. The
/// limit is a const generic in bincode 2, hence the dispatch over powers of
/// four.
/// How many bytes of memory one payload byte may decode into (see [`decode_payload`]).
pub const DECODE_EXPANSION: usize = 32;

/// Evaluates `$body` with `$config` bound to bincode's `standard()` configuration under the
/// decode limit of a payload of `$len` bytes (see [`decode_payload`]), or returns
/// `Err("payload of N bytes is too large")` from the enclosing function.
macro_rules! with_decode_limit {
    ($len:expr, |$config:ident| $body:expr) => {
        with_decode_limit!(@powers $len, $config, $body, 12 14 16 18 20 22 24 26 28 30 32 34 36 38 40 42 44)
    };
    (@powers $len:expr, $config:ident, $body:expr, $($k:literal)*) => {{
        let len: usize = $len;
        let need = len.saturating_mul(DECODE_EXPANSION).max(1 << 12);
        $(
            if need <= (1usize << $k) {
                let $config = bincode::config::standard().with_limit::<{ 1usize << $k }>();
                return $body;
            }
        )*
        Err(format!("payload of {len} bytes is too large"))
    }};
}

fn decode_payload<T: DeserializeOwned>(payload: &[u8]) -> std::result::Result<T, String> {
    fn finish<T>(
        r: std::result::Result<(T, usize), bincode::error::DecodeError>,
        len: usize,
    ) -> std::result::Result<T, String> {
        let (value, used) = r.map_err(|e| e.to_string())?;
        if used != len {
            return Err(format!("{} unexpected bytes after the payload", len - used));
        }
        Ok(value)
    }
    with_decode_limit!(payload.len(), |config| {
        finish(bincode::serde::decode_from_slice::<T, _>(payload, config), payload.len())
    })
}

/// [`read_artifact`] in one pass over the file without holding it in memory: `seed` decodes the
/// payload as it is read (e.g. a motion whose frames are encoded one block at a time), the
/// SHA-256 of the bytes is computed as they go by, and the checksum is compared after the last
/// byte. Returns the header, the seed's value and the file's SHA-256 ([`sha256_file`]'s value).
///
/// Fails with the error [`read_artifact`] gives for the same file: every length is checked
/// against the file's size before its bytes are read, and whatever is wrong with the kind,
/// version, header or payload is reported only once the checksum matched (a corrupt file is a
/// checksum mismatch, wherever the damage is). The payload decoder has the byte limit of
/// [`decode_payload`]. The seed's value is returned only from a file whose checksum matched, but
/// the seed sees the payload before the checksum is known: it must treat it as untrusted (never
/// panic, allocate only for bytes it has read).
pub fn read_artifact_seeded<S, V>(
    path: impl AsRef<Path>,
    kind: &str,
    kind_version: u32,
    seed: S,
) -> Result<(Header, V, String)>
where
    S: for<'de> serde::de::DeserializeSeed<'de, Value = V>,
{
    let path = path.as_ref();
    let file = crate::input::open_regular_file(path)?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    let mut s = FileStream {
        reader: std::io::BufReader::with_capacity(1 << 16, HashingFile::new(file, len)),
        pos: 0,
        len,
    };
    let sections = s.sections().map_err(|e| e.into_error(path))?;
    // What is wrong with the sections or the payload, reported only if the checksum matches.
    let decoded = sections.check(kind, kind_version).and_then(|header| {
        let mut reader = PayloadReader { inner: &mut s.reader, left: sections.payload_len };
        let value = decode_seeded(&mut reader, sections.payload_len, seed)
            .map_err(|e| format!("'{kind}' payload does not decode: {e}"))?;
        match reader.left {
            0 => Ok((header, value)),
            n => Err(format!("'{kind}' payload does not decode: {n} unexpected bytes after the payload")),
        }
    });
    std::io::copy(&mut s.reader, &mut std::io::sink()).map_err(|e| Error::io(path, e))?;
    let hashing = s.reader.into_inner();
    if hashing.read != len {
        return Err(Error::file(path, format!("changed while it was read ({len} bytes, then {})", hashing.read)));
    }
    if hashing.hasher.clone().finalize().as_slice() != hashing.tail {
        return Err(Error::file(path, "checksum mismatch (file corrupt)"));
    }
    let (header, value) = decoded.map_err(|msg| Error::file(path, msg))?;
    let mut hasher = hashing.hasher;
    hasher.update(hashing.tail);
    Ok((header, value, hex(&hasher.finalize())))
}

/// Decodes one value from `reader` with `seed` under the decode limit of a `len`-byte payload.
fn decode_seeded<S, V>(reader: &mut PayloadReader<'_>, len: u64, seed: S) -> std::result::Result<V, String>
where
    S: for<'de> serde::de::DeserializeSeed<'de, Value = V>,
{
    let len = usize::try_from(len).unwrap_or(usize::MAX);
    with_decode_limit!(len, |config| {
        let mut decoder = bincode::serde::OwnedSerdeDecoder::from_reader(reader, config);
        seed.deserialize(decoder.as_deserializer()).map_err(|e| e.to_string())
    })
}

/// A file read front to back that hashes every byte before the checksum (its last
/// [`CHECKSUM_LEN`] bytes, which it keeps) and counts the bytes read.
struct HashingFile {
    file: std::fs::File,
    hasher: Sha256,
    /// Bytes before the checksum (the file's length at opening, less the checksum's).
    body_len: u64,
    read: u64,
    tail: [u8; CHECKSUM_LEN],
}

impl HashingFile {
    fn new(file: std::fs::File, len: u64) -> Self {
        HashingFile { file, hasher: Sha256::new(), body_len: len.saturating_sub(CHECKSUM_LEN as u64), read: 0, tail: [0; CHECKSUM_LEN] }
    }
}

impl Read for HashingFile {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.file.read(buf)?;
        let chunk = &buf[..n];
        let body = (self.body_len.saturating_sub(self.read).min(n as u64)) as usize;
        self.hasher.update(&chunk[..body]);
        for (i, &b) in chunk[body..].iter().enumerate() {
            // Offset in the checksum; bytes beyond it (a file grown while read) are not kept.
            let at = (self.read + (body + i) as u64).saturating_sub(self.body_len);
            if let Some(t) = usize::try_from(at).ok().and_then(|at| self.tail.get_mut(at)) {
                *t = b;
            }
        }
        self.read += n as u64;
        Ok(n)
    }
}

/// The payload's bytes as bincode reads them: at most `left` more from `inner`, the end of the
/// payload being an unexpected end as it is for a slice.
struct PayloadReader<'a> {
    inner: &'a mut std::io::BufReader<HashingFile>,
    left: u64,
}

impl bincode::de::read::Reader for PayloadReader<'_> {
    fn read(&mut self, bytes: &mut [u8]) -> std::result::Result<(), bincode::error::DecodeError> {
        if bytes.len() as u64 > self.left {
            return Err(bincode::error::DecodeError::UnexpectedEnd { additional: bytes.len() - self.left as usize });
        }
        self.inner
            .read_exact(bytes)
            .map_err(|inner| bincode::error::DecodeError::Io { inner, additional: bytes.len() })?;
        self.left -= bytes.len() as u64;
        Ok(())
    }

    fn peek_read(&mut self, n: usize) -> Option<&[u8]> {
        if n as u64 > self.left {
            return None;
        }
        self.inner.buffer().get(..n)
    }

    fn consume(&mut self, n: usize) {
        let n = n.min(self.inner.buffer().len()).min(self.left as usize);
        std::io::BufRead::consume(self.inner, n);
        self.left -= n as u64;
    }
}

/// The container's sections up to the payload, read from a stream.
struct StreamSections {
    kind: Vec<u8>,
    kind_version: u32,
    header_json: Vec<u8>,
    payload_len: u64,
}

impl StreamSections {
    /// The header, or what [`decode_artifact_hashed`] finds wrong (after the checksum) with the
    /// kind, its version and the header.
    fn check(&self, kind: &str, kind_version: u32) -> std::result::Result<Header, String> {
        let found = std::str::from_utf8(&self.kind).map_err(|_| "corrupt: kind is not UTF-8".to_string())?;
        if found != kind {
            return Err(format!("expected artifact kind '{kind}', found '{found}'"));
        }
        if self.kind_version != kind_version {
            return Err(version_error(kind, self.kind_version, kind_version, &self.header_json));
        }
        parse_header(&self.header_json)
    }
}

/// Why the sections could not be read: a message about the file, or a failed read.
enum StreamError {
    Msg(String),
    Io(std::io::Error),
}

impl StreamError {
    fn into_error(self, path: &Path) -> Error {
        match self {
            StreamError::Msg(m) => Error::file(path, m),
            StreamError::Io(e) => Error::io(path, e),
        }
    }
}

/// [`Cursor`] over a file of `len` bytes being read: the same bounds checks and messages.
struct FileStream {
    reader: std::io::BufReader<HashingFile>,
    pos: u64,
    len: u64,
}

impl FileStream {
    fn take(&mut self, n: u64, what: &str) -> std::result::Result<Vec<u8>, StreamError> {
        let rem = self.len - self.pos;
        if n > rem {
            return Err(StreamError::Msg(format!("truncated: {what} needs {n} bytes at offset {}, {rem} remain", self.pos)));
        }
        // `n` is at most the file's length: the allocation is what the file holds.
        let mut buf = vec![0u8; n as usize];
        self.reader.read_exact(&mut buf).map_err(StreamError::Io)?;
        self.pos += n;
        Ok(buf)
    }
    fn u32(&mut self, what: &str) -> std::result::Result<u32, StreamError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn u64(&mut self, what: &str) -> std::result::Result<u64, StreamError> {
        let b = self.take(8, what)?;
        Ok(u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
    }

    /// Reads the sections before the payload and checks the payload's and the checksum's
    /// lengths against the file's, with [`split`]'s messages.
    fn sections(&mut self) -> std::result::Result<StreamSections, StreamError> {
        let msg = |m: String| Err(StreamError::Msg(m));
        if self.len < MAGIC.len() as u64 {
            let bytes = self.take(self.len, "file")?;
            return msg(if MAGIC.starts_with(&bytes) {
                format!("truncated: file is {} bytes, shorter than the magic bytes", bytes.len())
            } else {
                "not a surfcap artifact (wrong magic bytes)".to_string()
            });
        }
        if self.take(MAGIC.len() as u64, "magic")? != MAGIC {
            return msg("not a surfcap artifact (wrong magic bytes)".to_string());
        }
        let container_version = self.u32("container version")?;
        if container_version != CONTAINER_VERSION {
            return msg(format!(
                "container version {container_version} is not supported (this build reads version {CONTAINER_VERSION})"
            ));
        }
        let kind_len = self.u32("kind length")?;
        if kind_len as usize > MAX_KIND_LEN {
            return msg(format!("corrupt: kind length {kind_len} exceeds the maximum of {MAX_KIND_LEN}"));
        }
        let kind = self.take(kind_len as u64, "kind")?;
        let kind_version = self.u32("kind version")?;
        let header_len = self.u64("header length")?;
        let header_json = self.take(header_len, "header")?;
        let payload_len = self.u64("payload length")?;
        let rem = self.len - self.pos;
        if payload_len > rem {
            return msg(format!("truncated: payload needs {payload_len} bytes at offset {}, {rem} remain", self.pos));
        }
        let after = rem - payload_len;
        if after < CHECKSUM_LEN as u64 {
            return msg(format!(
                "truncated: checksum needs {CHECKSUM_LEN} bytes at offset {}, {after} remain",
                self.pos + payload_len
            ));
        }
        if after > CHECKSUM_LEN as u64 {
            return msg(format!("corrupt: {} unexpected bytes after the checksum", after - CHECKSUM_LEN as u64));
        }
        Ok(StreamSections { kind, kind_version, header_json, payload_len })
    }
}
