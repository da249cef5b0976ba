//! Ogawa: the binary container of Alembic (`.abc`) files. The Alembic layer on top of it
//! (objects, properties, time samplings) is [`super::alembic`].
//!
//! Layout (little-endian): a 16-byte header, `"Ogawa"`, a frozen byte (`0xff` once the
//! writer has closed the file, `0x00` while it is still being written), the container version
//! as two bytes, high first (1), and the `u64` offset of the root group. A group is a `u64`
//! child count followed by that many `u64` child offsets; a child whose high bit is set is a
//! data block (the offset is the rest of the bits), else a group. Offset 0 is the empty group,
//! `1 << 63` the empty data block. A data block is a `u64` byte count followed by the bytes.
//!
//! The reader works on the file's bytes in memory and allocates nothing: a [`Group`] is a view
//! of its child table and [`Group::data`] a slice of the file. Every offset and count is
//! checked against the file's length before it is used, so a truncated or crafted file gives
//! an error (the problem, without the file name), never a panic or an out-of-range read.

#![forbid(unsafe_code)]

/// The first 5 bytes of an Ogawa file.
pub const MAGIC: &[u8; 5] = b"Ogawa";
/// The container version this reader knows.
pub const VERSION: u16 = 1;
const HEADER_LEN: u64 = 16;
const DATA_BIT: u64 = 1 << 63;

/// An Ogawa file held in memory.
#[derive(Clone, Copy, Debug)]
pub struct Ogawa<'a> {
    bytes: &'a [u8],
    root: u64,
}

/// A group: a table of children, each a group or a data block.
#[derive(Clone, Copy, Debug)]
pub struct Group<'a> {
    bytes: &'a [u8],
    /// Byte offset of the group (0: the empty group).
    offset: u64,
    /// Number of children.
    len: u64,
}

fn u64_at(bytes: &[u8], at: u64) -> Option<u64> {
    let at = usize::try_from(at).ok()?;
    let b = bytes.get(at..at.checked_add(8)?)?;
    Some(u64::from_le_bytes(b.try_into().ok()?))
}

impl<'a> Ogawa<'a> {
    /// Checks the header; the error is the problem without the file name.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, String> {
        if bytes.len() < HEADER_LEN as usize {
            if bytes.starts_with(b"\x89HDF") {
                return Err("an HDF5 Alembic file (the old layout): only Ogawa files are read; re-export as Ogawa".into());
            }
            return Err(format!(
                "not an Alembic (Ogawa) file: {} bytes, shorter than the 16-byte header",
                bytes.len()
            ));
        }
        if &bytes[..5] != MAGIC {
            if bytes.starts_with(b"\x89HDF") {
                return Err("an HDF5 Alembic file (the old layout): only Ogawa files are read; re-export as Ogawa".into());
            }
            return Err("not an Alembic (Ogawa) file: it does not start with \"Ogawa\"".into());
        }
        if bytes[5] != 0xff {
            return Err(format!(
                "unfinished Ogawa file (frozen byte 0x{:02x}, not 0xff): its writer did not close it",
                bytes[5]
            ));
        }
        let version = u16::from_be_bytes([bytes[6], bytes[7]]);
        if version != VERSION {
            return Err(format!("unsupported Ogawa version {version} (expected {VERSION})"));
        }
        let root = u64_at(bytes, 8).unwrap_or(0);
        let file = Ogawa { bytes, root };
        file.root()?;
        Ok(file)
    }

    /// The root group.
    pub fn root(&self) -> Result<Group<'a>, String> {
        Group::at(self.bytes, self.root)
    }

    /// The file's length in bytes.
    pub fn len(&self) -> u64 {
        self.bytes.len() as u64
    }

    /// Always false: a parsed file holds at least its header.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}

impl<'a> Group<'a> {
    fn at(bytes: &'a [u8], offset: u64) -> Result<Self, String> {
        if offset & DATA_BIT != 0 {
            return Err(format!("expected a group, found a data block (offset 0x{offset:x})"));
        }
        if offset == 0 {
            return Ok(Group { bytes, offset, len: 0 });
        }
        let file_len = bytes.len() as u64;
        if offset < HEADER_LEN {
            return Err(format!("group at byte {offset} lies inside the 16-byte header"));
        }
        let len = u64_at(bytes, offset).ok_or_else(|| {
            format!("group at byte {offset} lies past the end of the file ({file_len} bytes)")
        })?;
        // Checked before anything is read: the child table must fit in the file.
        let room = (file_len - offset - 8) / 8;
        if len > room {
            return Err(format!(
                "group at byte {offset} announces {len} children but the file has room for {room}"
            ));
        }
        Ok(Group { bytes, offset, len })
    }

    /// The group's byte offset in the file (0 for the empty group).
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// Number of children.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// True for a group without children.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn child(&self, i: u64) -> Result<u64, String> {
        if i >= self.len {
            return Err(format!(
                "group at byte {} has {} children, child {i} is missing",
                self.offset, self.len
            ));
        }
        // In range: `at` checked that the whole table lies in the file.
        u64_at(self.bytes, self.offset + 8 + 8 * i)
            .ok_or_else(|| format!("group at byte {}: child table cut short", self.offset))
    }

    /// True when child `i` exists and is a data block.
    pub fn is_data(&self, i: u64) -> bool {
        self.child(i).is_ok_and(|c| c & DATA_BIT != 0)
    }

    /// True when child `i` exists and is a group.
    pub fn is_group(&self, i: u64) -> bool {
        self.child(i).is_ok_and(|c| c & DATA_BIT == 0)
    }

    /// Child `i`, which must be a group.
    pub fn group(&self, i: u64) -> Result<Group<'a>, String> {
        let c = self.child(i)?;
        if c != 0 && c == self.offset {
            return Err(format!("group at byte {} lists itself as child {i}", self.offset));
        }
        Group::at(self.bytes, c).map_err(|e| format!("child {i} of group at byte {}: {e}", self.offset))
    }

    /// The bytes of child `i`, which must be a data block.
    pub fn data(&self, i: u64) -> Result<&'a [u8], String> {
        let c = self.child(i)?;
        if c & DATA_BIT == 0 {
            return Err(format!(
                "child {i} of group at byte {} is a group, expected a data block",
                self.offset
            ));
        }
        let offset = c & !DATA_BIT;
        if offset == 0 {
            return Ok(&[]);
        }
        let file_len = self.bytes.len() as u64;
        let size = u64_at(self.bytes, offset)
            .filter(|_| offset >= HEADER_LEN)
            .ok_or_else(|| format!("data block at byte {offset} lies outside the file ({file_len} bytes)"))?;
        let start = offset + 8;
        if size > file_len - start {
            return Err(format!(
                "data block at byte {offset} announces {size} bytes but the file ends {} bytes after it",
                file_len - start
            ));
        }
        Ok(&self.bytes[start as usize..(start + size) as usize])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file with the root group holding one data block ("abc") and one empty group.
    fn tiny() -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&[0xff, 0, 1]);
        b.extend_from_slice(&16u64.to_le_bytes()); // root at 16
        b.extend_from_slice(&2u64.to_le_bytes());
        b.extend_from_slice(&(40u64 | DATA_BIT).to_le_bytes());
        b.extend_from_slice(&0u64.to_le_bytes());
        b.extend_from_slice(&3u64.to_le_bytes()); // data at 40
        b.extend_from_slice(b"abc");
        b
    }

    #[test]
    fn reads_groups_and_data() {
        let bytes = tiny();
        let f = Ogawa::parse(&bytes).unwrap();
        let root = f.root().unwrap();
        assert_eq!(root.len(), 2);
        assert!(root.is_data(0) && root.is_group(1) && !root.is_data(2));
        assert_eq!(root.data(0).unwrap(), b"abc");
        assert!(root.group(1).unwrap().is_empty());
        assert!(root.group(0).unwrap_err().contains("found a data block"));
        assert!(root.data(1).unwrap_err().contains("is a group"));
        assert!(root.data(2).unwrap_err().contains("missing"));
    }

    #[test]
    fn crafted_offsets_and_counts_are_errors() {
        let mut bytes = tiny();
        bytes[5] = 0;
        assert!(Ogawa::parse(&bytes).unwrap_err().contains("unfinished"));
        let mut bytes = tiny();
        bytes[16..24].copy_from_slice(&u64::MAX.to_le_bytes() .map(|b| b & 0x7f));
        assert!(Ogawa::parse(&bytes).unwrap_err().contains("announces"), "{:?}", Ogawa::parse(&bytes));
        let mut bytes = tiny();
        bytes[40..48].copy_from_slice(&(u64::MAX >> 1).to_le_bytes());
        let f = Ogawa::parse(&bytes).unwrap();
        assert!(f.root().unwrap().data(0).unwrap_err().contains("announces"));
        let mut bytes = tiny();
        bytes[8..16].copy_from_slice(&(1u64 << 62).to_le_bytes());
        assert!(Ogawa::parse(&bytes).unwrap_err().contains("past the end"));
        let mut bytes = tiny();
        bytes[8..16].copy_from_slice(&16u64.to_le_bytes());
        bytes[32..40].copy_from_slice(&16u64.to_le_bytes()); // the root lists itself
        assert!(Ogawa::parse(&bytes).unwrap().root().unwrap().group(1).unwrap_err().contains("itself"));
        assert!(Ogawa::parse(b"\x89HDF\r\n\x1a\n").unwrap_err().contains("HDF5"));
        for n in 0..tiny().len() {
            let b = &tiny()[..n];
            if let Ok(f) = Ogawa::parse(b) {
                let root = f.root().unwrap();
                assert!(root.data(0).is_err(), "prefix {n}");
            }
        }
    }
}
