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
//! [`Error::File`](crate::error::Error::File) line naming the file, e.g.
//! `model.art: expected artifact kind 'pca-model', found 'gpr-model'`.
//!
//! Files: [`header`] (the provenance header), [`kind`] (the [`Artifact`] trait of a payload type
//! and its validation helpers), [`write`] (encoding, atomic and streamed writes), [`read`]
//! (reading and inspecting a file held in memory), [`stream`] (reading in one pass without
//! holding the file), [`decode`] (the payload decoder's byte limit), [`hash`] (SHA-256 of files).

mod decode;
mod hash;
mod header;
mod kind;
mod read;
mod stream;
mod write;

pub use decode::DECODE_EXPANSION;
pub use hash::sha256_file;
pub use header::{Header, InputRecord, Producer};
pub use kind::{check_cover, check_indices, Artifact};
pub use read::{
    decode_artifact, decode_artifact_hashed, inspect_artifact, inspect_json, read_artifact, read_header,
    ArtifactInfo,
};
pub use stream::read_artifact_seeded;
pub use write::{encode_artifact, encoded_len, encoded_seq_len, write_artifact, write_artifact_streamed, PayloadWriter};

/// The eight magic bytes every artifact starts with.
pub const MAGIC: [u8; 8] = *b"SURFCAP\0";
/// Version of the container layout described in the module documentation.
pub const CONTAINER_VERSION: u32 = 1;
/// Longest artifact kind name accepted (a sanity bound, not a format limit).
pub const MAX_KIND_LEN: usize = 256;
const CHECKSUM_LEN: usize = 32;
