//! Alembic's packed header values: plain-old-data types, property kinds, one property's header
//! (with the map from a sample to the one stored), and a little-endian cursor over header bytes
//! that fails instead of panicking.

/// Plain-old-data types of Alembic's property headers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Pod {
    Bool,
    Uint8,
    Int32,
    Float32,
    Float64,
    Other(u8),
}

impl Pod {
    pub(super) fn of(code: u8) -> Pod {
        match code {
            0 => Pod::Bool,
            1 => Pod::Uint8,
            6 => Pod::Int32,
            10 => Pod::Float32,
            11 => Pod::Float64,
            c => Pod::Other(c),
        }
    }
    pub(super) fn name(self) -> String {
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
    pub(super) fn size(self) -> Option<usize> {
        match self {
            Pod::Bool | Pod::Uint8 => Some(1),
            Pod::Int32 | Pod::Float32 => Some(4),
            Pod::Float64 => Some(8),
            Pod::Other(_) => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Compound,
    Scalar,
    Array,
}

/// One entry of a compound's packed property headers.
#[derive(Clone, Debug)]
pub(super) struct PropertyHeader {
    pub(super) name: String,
    pub(super) kind: Kind,
    pub(super) pod: Pod,
    pub(super) extent: u8,
    /// Number of samples (stored or repeated).
    pub(super) samples: u32,
    pub(super) first_changed: u32,
    pub(super) last_changed: u32,
    pub(super) time_sampling: u32,
}

impl PropertyHeader {
    /// The stored sample that sample `i` reads (Alembic stores a run of equal samples once).
    pub(super) fn stored_index(&self, i: u32) -> Option<u64> {
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

/// Little-endian readers over a header buffer that fail instead of panicking.
pub(super) struct Cursor<'a> {
    pub(super) b: &'a [u8],
    pub(super) at: usize,
    pub(super) what: &'static str,
}

impl<'a> Cursor<'a> {
    pub(super) fn new(b: &'a [u8], what: &'static str) -> Self {
        Cursor { b, at: 0, what }
    }
    pub(super) fn done(&self) -> bool {
        self.at >= self.b.len()
    }
    pub(super) fn take(&mut self, n: usize) -> std::result::Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.b.len()).ok_or_else(|| {
            format!("{} cut short: {n} bytes needed at byte {} of {}", self.what, self.at, self.b.len())
        })?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    pub(super) fn u8(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    pub(super) fn u16(&mut self) -> std::result::Result<u16, String> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }
    pub(super) fn u32(&mut self) -> std::result::Result<u32, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    pub(super) fn f64(&mut self) -> std::result::Result<f64, String> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(f64::from_le_bytes(a))
    }
    /// A `u32` stored in 1, 2 or 4 bytes (`hint` 0, 1, 2).
    pub(super) fn hinted(&mut self, hint: u32) -> std::result::Result<u32, String> {
        match hint {
            0 => self.u8().map(u32::from),
            1 => self.u16().map(u32::from),
            2 => self.u32(),
            _ => Err(format!("{}: bad size hint {hint}", self.what)),
        }
    }
    pub(super) fn text(&mut self, n: usize) -> std::result::Result<String, String> {
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
