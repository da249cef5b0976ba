//! How the frame files of a folder are named, detected or given as a printf
//! pattern (`walk.%04d.obj`).
//!
//! A frame file's name is `<prefix><number><extension>` with a `.ply` or
//! `.obj` extension (any case) and `<number>` the trailing run of digits of
//! the stem: `000012.ply` (no prefix, surfcap's own layout), `frame_0012.ply`,
//! `walk.0012.obj`, or Blender's unpadded sequence export `punch12.obj`.
//!
//! Detection ([`detect`]) groups a folder's mesh files by prefix:
//! - files with no prefix (only digits) are the frames if there are any; the
//!   other mesh files are ignored, as in surfcap's own folders;
//! - otherwise the one prefix found names the frames; two prefixes are an
//!   ambiguity error that lists them (pick one with a pattern);
//! - the numbers must run without gaps or duplicates from the first, which
//!   may be any number (0- and 1-based exports alike).
//!
//! A reading other than surfcap's own (no prefix, from 0) is stated once per
//! folder on stderr by [`crate::sequence::frame_files`] (not with `-q`).

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::io::MeshFormat;

/// A frame-file name pattern: `prefix`, the frame number (zero-padded to
/// `width` digits, or unpadded when `width` is `None`), then `suffix`
/// (the extension with its dot).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FramePattern {
    pub prefix: String,
    pub width: Option<usize>,
    pub suffix: String,
}

impl FromStr for FramePattern {
    type Err = String;
    /// Parses printf's `%d` or `%0Nd` (one of them, once), e.g. `walk.%04d.obj`, `punch%d.obj`.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = |why: &str| format!("frame pattern '{s}': {why} (e.g. 'walk.%04d.obj' or 'punch%d.obj')");
        if s.contains(['/', '\\']) {
            return Err(bad("give the file name only, the folder separately"));
        }
        let Some(at) = s.find('%') else {
            return Err(bad("no %d in it"));
        };
        let (prefix, rest) = (&s[..at], &s[at + 1..]);
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let Some(suffix) = rest[digits.len()..].strip_prefix('d') else {
            return Err(bad("the number must be written %d or %0Nd"));
        };
        if suffix.contains('%') {
            return Err(bad("more than one %"));
        }
        let width = match digits.as_str() {
            "" => None,
            d if d.starts_with('0') && d.len() > 1 => Some(d[1..].parse().map_err(|_| bad("bad width"))?),
            _ => return Err(bad("the width must be zero-padded (%04d) or absent (%d)")),
        };
        let pattern = FramePattern { prefix: prefix.to_string(), width, suffix: suffix.to_string() };
        if MeshFormat::from_path(Path::new(&pattern.example(0))).is_none() {
            return Err(bad("the name must end in .ply or .obj"));
        }
        Ok(pattern)
    }
}

impl fmt::Display for FramePattern {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.width {
            Some(w) => write!(f, "{}%0{w}d{}", self.prefix, self.suffix),
            None => write!(f, "{}%d{}", self.prefix, self.suffix),
        }
    }
}

impl FramePattern {
    /// The file name of frame number `n`.
    pub fn example(&self, n: usize) -> String {
        match self.width {
            Some(w) => format!("{}{n:0w$}{}", self.prefix, self.suffix),
            None => format!("{}{n}{}", self.prefix, self.suffix),
        }
    }

    /// The frame number of a file name that matches the pattern exactly.
    pub fn number_of(&self, name: &str) -> Option<usize> {
        let digits = name.strip_prefix(self.prefix.as_str())?.strip_suffix(self.suffix.as_str())?;
        let ok = !digits.is_empty()
            && digits.bytes().all(|b| b.is_ascii_digit())
            && self.width.is_none_or(|w| digits.len() == w);
        if ok { digits.parse().ok() } else { None }
    }
}

/// The frames of one folder: where they are and how their names were read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameListing {
    /// How the names read (for surfcap's own folders: `%06d.ply`).
    pub pattern: FramePattern,
    /// The first frame's number (frame 0 of the sequence).
    pub first: usize,
    /// The files in frame order.
    pub files: Vec<PathBuf>,
}

impl FrameListing {
    /// Whether this is surfcap's own layout (no prefix, numbered from 0), which goes unstated.
    pub fn is_native(&self) -> bool {
        self.pattern.prefix.is_empty() && self.first == 0
    }

    /// The reading in one line: `frames walk.%04d.obj, numbers 1 to 120 (120 files, 1-based)`.
    pub fn describe(&self) -> String {
        let n = self.files.len();
        let base = match self.first {
            0 => "0-based".to_string(),
            1 => "1-based".to_string(),
            k => format!("starting at {k}"),
        };
        format!(
            "frames {}, numbers {} to {} ({n} files, {base})",
            self.pattern,
            self.first,
            self.first + n - 1
        )
    }
}

/// Splits a mesh file name into `(prefix, number, digit count)`; `None` when
/// it is not a `.ply`/`.obj` file or its stem does not end in digits.
fn split_name(path: &Path) -> Option<(String, usize, usize)> {
    MeshFormat::from_path(path)?;
    let stem = path.file_stem()?.to_str()?;
    let digits = stem.bytes().rev().take_while(u8::is_ascii_digit).count();
    if digits == 0 {
        return None;
    }
    let (prefix, number) = stem.split_at(stem.len() - digits);
    Some((prefix.to_string(), number.parse().ok()?, digits))
}

fn file_name(p: &Path) -> String {
    p.file_name().unwrap_or_default().to_string_lossy().into_owned()
}

fn mesh_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        // A directory named like a frame stays in: reading it then says what it is.
        if MeshFormat::from_path(&path).is_some() {
            out.push(path);
        }
    }
    out.sort();
    Ok(out)
}

/// Orders numbered files and checks the numbering runs from the first number
/// without gaps or duplicates. `names` are `(number, digit count, path)`.
fn listing(dir: &Path, prefix: &str, mut found: Vec<(usize, usize, PathBuf)>) -> Result<FrameListing> {
    found.sort();
    let first = found[0].0;
    // Zero-padded when every number has the same digit count and one of them
    // has a leading zero.
    let w0 = found[0].1;
    let same = found.iter().all(|(_, w, _)| *w == w0);
    let padded = same && found.iter().any(|(n, w, _)| n.to_string().len() < *w);
    let ext = found[0]
        .2
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let pattern = FramePattern { prefix: prefix.to_string(), width: padded.then_some(w0), suffix: ext };
    for w in found.windows(2) {
        let ((a, _, pa), (b, _, pb)) = (&w[0], &w[1]);
        if a == b {
            return Err(Error::file(
                dir,
                format!("frame {a} appears twice ({} and {})", file_name(pa), file_name(pb)),
            ));
        }
        if *b != a + 1 {
            return Err(Error::file(
                dir,
                format!(
                    "gap in the frame numbering: {} is missing ({} is followed by {})",
                    pattern.example(a + 1),
                    file_name(pa),
                    file_name(pb)
                ),
            ));
        }
    }
    Ok(FrameListing { pattern, first, files: found.into_iter().map(|(_, _, p)| p).collect() })
}

/// Detects the frame files of `dir` (rules in the module doc).
pub fn detect(dir: impl AsRef<Path>) -> Result<FrameListing> {
    let dir = dir.as_ref();
    let mut groups: std::collections::BTreeMap<String, Vec<(usize, usize, PathBuf)>> = Default::default();
    for path in mesh_files(dir)? {
        if let Some((prefix, n, w)) = split_name(&path) {
            groups.entry(prefix).or_default().push((n, w, path));
        }
    }
    if let Some(own) = groups.remove("") {
        return listing(dir, "", own);
    }
    match groups.len() {
        0 => Err(Error::file(
            dir,
            "no frame files (000000.ply, 000001.ply, ... or .obj; or named like frame_0001.ply, walk.0001.obj, punch1.obj)",
        )),
        1 => {
            let (prefix, found) = groups.into_iter().next().expect("one group");
            listing(dir, &prefix, found)
        }
        _ => {
            let names: Vec<String> = groups
                .iter()
                .map(|(p, f)| format!("'{p}…' ({} files)", f.len()))
                .collect();
            Err(Error::file(
                dir,
                format!(
                    "frame files with {} different prefixes ({}): keep one sequence per folder or name one with a pattern such as --frames '{}%04d.obj'",
                    names.len(),
                    names.join(", "),
                    groups.keys().next().expect("two groups")
                ),
            ))
        }
    }
}

/// The frame files of `dir` that match `pattern` (other files are ignored),
/// numbered without gaps from the first.
pub fn list(dir: impl AsRef<Path>, pattern: &FramePattern) -> Result<FrameListing> {
    let dir = dir.as_ref();
    let mut found = Vec::new();
    for path in mesh_files(dir)? {
        if let Some(n) = pattern.number_of(&file_name(&path)) {
            let w = file_name(&path).len() - pattern.prefix.len() - pattern.suffix.len();
            found.push((n, w, path));
        }
    }
    if found.is_empty() {
        return Err(Error::file(dir, format!("no frame files match '{pattern}'")));
    }
    let mut l = listing(dir, &pattern.prefix, found)?;
    l.pattern = pattern.clone();
    Ok(l)
}
