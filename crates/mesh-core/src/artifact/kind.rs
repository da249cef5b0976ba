//! Artifact kinds: the [`Artifact`] trait tying a payload type to its kind name and version
//! (save, load, decode, validate), and the index checks its validations share.

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::Serialize;

use super::read::{decode_artifact, decode_artifact_hashed, read_artifact};
use super::write::write_artifact;
use super::Header;
use crate::error::{Error, Result};

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
    /// [`sha256_file`](super::sha256_file), from the read and the hash that verify the checksum: one pass).
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
