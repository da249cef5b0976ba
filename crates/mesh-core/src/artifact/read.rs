//! Reading artifacts held in memory: the container split into its sections (magic, versions,
//! every length, checksum), the kind and version checked, the header parsed and the payload
//! decoded; `inspect`'s view of a file.

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::Serialize;
use sha2::{Digest, Sha256};

use super::decode::decode_payload;
use super::hash::hex;
use super::{Header, CHECKSUM_LEN, CONTAINER_VERSION, MAGIC, MAX_KIND_LEN};
use crate::error::{Error, Result};

/// What `inspect` reports about an artifact (checksum verified).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ArtifactInfo {
    pub container_version: u32,
    pub kind: String,
    pub kind_version: u32,
    pub header: Header,
    pub payload_bytes: u64,
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
pub(super) fn version_error(kind: &str, found: u32, build: u32, header_json: &[u8]) -> String {
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


/// The sections of a checksum-verified artifact, borrowed from the file bytes.
struct RawArtifact<'a> {
    container_version: u32,
    kind: &'a str,
    kind_version: u32,
    header_json: &'a [u8],
    payload: &'a [u8],
    /// SHA-256 of the whole file, lowercase hex ([`sha256_file`](super::sha256_file)'s value).
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

pub(super) fn parse_header(json: &[u8]) -> std::result::Result<Header, String> {
    serde_json::from_slice(json).map_err(|e| format!("header is not valid JSON: {e}"))
}
