//! Writing artifacts: the container encoded in memory, written atomically, or streamed piece by
//! piece with the payload's length announced and the checksum computed on the way.

use std::path::Path;

use serde::Serialize;
use sha2::{Digest, Sha256};

use super::{Header, CHECKSUM_LEN, CONTAINER_VERSION, MAGIC, MAX_KIND_LEN};
use crate::error::{Error, Result};

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
