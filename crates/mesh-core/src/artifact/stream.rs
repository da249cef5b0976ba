//! Reading an artifact in one pass without holding it in memory: the file hashed as it is read,
//! the sections checked against the file's length, the payload decoded by a serde seed, and the
//! checksum compared after the last byte.

use std::io::Read;
use std::path::Path;

use sha2::{Digest, Sha256};

use super::decode::decode_seeded;
use super::hash::hex;
use super::read::{parse_header, version_error};
use super::{Header, CHECKSUM_LEN, CONTAINER_VERSION, MAGIC, MAX_KIND_LEN};
use crate::error::{Error, Result};

/// [`read_artifact`](super::read_artifact) in one pass over the file without holding it in memory: `seed` decodes the
/// payload as it is read (e.g. a motion whose frames are encoded one block at a time), the
/// SHA-256 of the bytes is computed as they go by, and the checksum is compared after the last
/// byte. Returns the header, the seed's value and the file's SHA-256 ([`sha256_file`](super::sha256_file)'s value).
///
/// Fails with the error [`read_artifact`](super::read_artifact) gives for the same file: every length is checked
/// against the file's size before its bytes are read, and whatever is wrong with the kind,
/// version, header or payload is reported only once the checksum matched (a corrupt file is a
/// checksum mismatch, wherever the damage is). The payload decoder has the byte limit of
/// [`decode_payload`](super::decode::decode_payload). The seed's value is returned only from a file whose checksum matched, but
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
pub(super) struct PayloadReader<'a> {
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
    /// The header, or what [`decode_artifact_hashed`](super::decode_artifact_hashed) finds wrong (after the checksum) with the
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

/// [`Cursor`](super::read::Cursor) over a file of `len` bytes being read: the same bounds checks and messages.
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
    /// lengths against the file's, with [`split`](super::read::split)'s messages.
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
