//! Reading untrusted input files.
//!
//! Every reader (meshes, capture-set JSON, artifacts, point caches) takes its
//! bytes from [`read_regular_file`], which refuses anything but a regular file
//! (after following symbolic links) before opening it: a FIFO would block the
//! stage forever, a device could stream without end, and a directory gives an
//! unhelpful OS error. Message text built from file contents goes through
//! [`escape_control`] so that a crafted file cannot send terminal escape
//! sequences to the user's screen.

use std::path::Path;

use crate::error::{Error, Result};

/// Why `path` is not a regular file, or `None` if it is one (or does not
/// exist: opening it then gives the OS error).
fn not_regular(path: &Path) -> Option<&'static str> {
    let meta = std::fs::metadata(path).ok()?;
    let ft = meta.file_type();
    if ft.is_file() {
        return None;
    }
    if ft.is_dir() {
        return Some("is a directory, not a file");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return Some("is a FIFO (named pipe), not a regular file");
        }
        if ft.is_socket() {
            return Some("is a socket, not a regular file");
        }
        if ft.is_char_device() || ft.is_block_device() {
            return Some("is a device, not a regular file");
        }
    }
    Some("is not a regular file")
}

/// Fails with one line naming `path` unless it is a regular file.
pub fn check_regular_file(path: &Path) -> Result<()> {
    match not_regular(path) {
        Some(why) => Err(Error::file(path, why)),
        None => Ok(()),
    }
}

/// The bytes of the regular file `path` (see the module documentation).
pub fn read_regular_file(path: impl AsRef<Path>) -> Result<Vec<u8>> {
    let path = path.as_ref();
    check_regular_file(path)?;
    std::fs::read(path).map_err(|e| Error::io(path, e))
}

/// Opens the regular file `path` for streaming (see the module documentation).
pub fn open_regular_file(path: impl AsRef<Path>) -> Result<std::fs::File> {
    let path = path.as_ref();
    check_regular_file(path)?;
    std::fs::File::open(path).map_err(|e| Error::io(path, e))
}

/// `text` with every control character (C0, DEL, C1, e.g. ESC `\x1b` or BEL
/// `\x07`) written as a `\x..` / `\u{..}` escape, so a message quoting file
/// contents prints as plain text on a terminal.
pub fn escape_control(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.chars().any(char::is_control) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        match c {
            c if (c as u32) < 0x80 && c.is_control() => {
                out.push_str(&format!("\\x{:02x}", c as u32))
            }
            c if c.is_control() => out.push_str(&format!("\\u{{{:x}}}", c as u32)),
            c => out.push(c),
        }
    }
    std::borrow::Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_terminal_sequences_and_keeps_text() {
        assert_eq!(escape_control("plain é text"), "plain é text");
        assert_eq!(escape_control("a\x1b[2Jb"), "a\\x1b[2Jb");
        assert_eq!(escape_control("\x1b]0;title\x07"), "\\x1b]0;title\\x07");
        assert_eq!(escape_control("\u{9b}x"), "\\u{9b}x");
        assert!(!escape_control("\x00\x7f\u{85}").chars().any(char::is_control));
    }

    #[cfg(unix)]
    #[test]
    fn refuses_a_fifo_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("000000.ply");
        let status = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(status.success());
        let err = read_regular_file(&fifo).unwrap_err().to_string();
        assert!(err.contains("000000.ply") && err.contains("FIFO"), "{err}");
        let err = read_regular_file(dir.path()).unwrap_err().to_string();
        assert!(err.contains("directory"), "{err}");
        assert!(read_regular_file(dir.path().join("missing")).is_err());
    }
}
