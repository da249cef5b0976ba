//! The payload decoder: bincode under a byte limit proportional to the payload's length, from a
//! slice or from a stream.

use serde::de::DeserializeOwned;

use super::stream::PayloadReader;

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
pub(super) fn decode_payload<T: DeserializeOwned>(payload: &[u8]) -> std::result::Result<T, String> {
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


/// Decodes one value from `reader` with `seed` under the decode limit of a `len`-byte payload.
pub(super) fn decode_seeded<S, V>(reader: &mut PayloadReader<'_>, len: u64, seed: S) -> std::result::Result<V, String>
where
    S: for<'de> serde::de::DeserializeSeed<'de, Value = V>,
{
    let len = usize::try_from(len).unwrap_or(usize::MAX);
    with_decode_limit!(len, |config| {
        let mut decoder = bincode::serde::OwnedSerdeDecoder::from_reader(reader, config);
        seed.deserialize(decoder.as_deserializer()).map_err(|e| e.to_string())
    })
}
