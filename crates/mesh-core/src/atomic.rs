//! Atomic file and folder output: write under a temporary name in the
//! destination's folder, flush to disk, then rename onto the destination. A
//! failed, interrupted or killed stage therefore never leaves a partial
//! output under its final name.
//!
//! Temporary names carry the writer's process id and host
//! (`.surfcap-<pid>@<host>-*.tmp` for files,
//! `.surfcap-<name>.<pid>@<host>.<n>.tmpdir` for folders); each write first
//! removes the temporaries of dead processes of this host in the same folder
//! (left by a `kill -9` or a power cut), so they do not accumulate. Another
//! host's temporaries on a shared file system are never touched: its
//! processes cannot be seen from here.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

const PREFIX: &str = ".surfcap-";

/// The folder `path` is written into (`.` for a bare file name).
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Whether process `pid` still runs (conservatively `true` where this cannot be told).
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        pid == std::process::id() || Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// This host's name reduced to ASCII letters and digits (`host` if unknown),
/// so that it cannot contain the separators of temporary names.
fn host() -> &'static str {
    static HOST: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    HOST.get_or_init(|| {
        let raw = std::fs::read_to_string("/proc/sys/kernel/hostname")
            .or_else(|_| std::fs::read_to_string("/etc/hostname"))
            .unwrap_or_default();
        let h: String = raw.chars().filter(char::is_ascii_alphanumeric).take(32).collect();
        if h.is_empty() { "host".to_string() } else { h }
    })
}

/// `<pid>@<host>` of this process, as temporary names carry it.
fn owner_tag() -> String {
    format!("{}@{}", std::process::id(), host())
}

/// The writer's pid in a temporary name written by this module on this host.
fn temp_owner(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(PREFIX)?;
    let tag = if let Some(body) = rest.strip_suffix(".tmp") {
        // .surfcap-<pid>@<host>-<random>.tmp
        body.split('-').next()?
    } else {
        // .surfcap-<name>.<pid>@<host>.<n>.tmpdir / .old
        let body = rest.strip_suffix(".tmpdir").or_else(|| rest.strip_suffix(".old"))?;
        let mut fields = body.rsplit('.');
        fields.next()?;
        fields.next()?
    };
    let (pid, h) = tag.split_once('@')?;
    if h != host() {
        return None;
    }
    pid.parse().ok()
}

/// Removes temporaries of dead writers from `dir` (best effort: another
/// cleaner may remove the same entry first).
pub fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_owner) else {
            continue;
        };
        if process_alive(pid) {
            continue;
        }
        let path = entry.path();
        let _ = match entry.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(&path),
            _ => std::fs::remove_file(&path),
        };
    }
}

/// Writes `path` atomically. `fill` receives a buffered writer; if it fails,
/// the temporary file is removed and `path` is left untouched.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    write_atomic_with(path, |w| fill(w).map_err(|e| Error::io(path, e)))
}

/// [`write_atomic`] with a `fill` that fails with its own error (e.g. one naming an input file
/// it was reading while it wrote), returned as it is.
pub fn write_atomic_with<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    let dir = parent_of(path);
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    if path.is_dir() {
        return Err(Error::file(path, "is a directory: cannot write a file there"));
    }
    remove_stale_temporaries(dir);
    let mut builder = tempfile::Builder::new();
    let prefix = format!("{PREFIX}{}-", owner_tag());
    builder.prefix(&prefix).suffix(".tmp");
    // Temporary files are created owner-only (0600); outputs are ordinary
    // files that other users and web servers may read.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o644));
    }
    let tmp = builder
        .tempfile_in(dir)
        .map_err(|e| Error::io(path, without_path(e)))?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w)?;
        w.flush().map_err(|e| Error::io(path, e))?;
    }
    tmp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// A scratch file for a stage's intermediate data, in the folder `output` is written into (the
/// same file system and the user's chosen place, not `/tmp`), named as this module's temporaries
/// are: removed when dropped, or, after a kill, by the next atomic write in that folder.
pub fn scratch_file(output: &Path) -> Result<tempfile::NamedTempFile> {
    let dir = parent_of(output);
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    remove_stale_temporaries(dir);
    tempfile::Builder::new()
        .prefix(&format!("{PREFIX}{}-", owner_tag()))
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| Error::io(output, without_path(e)))
}

/// `e` without the temporary file's path `tempfile` adds to it: it wraps the OS error in a
/// private error type whose message is `<OS error> at path ".surfcap-….tmp"`, so the OS error's
/// code cannot be recovered and the message is cut before ` at path`. The line then names the
/// output, e.g. `out.pca: Read-only file system (os error 30)`.
fn without_path(e: std::io::Error) -> std::io::Error {
    if let Some(code) = e.raw_os_error() {
        return std::io::Error::from_raw_os_error(code);
    }
    let text = e.to_string();
    match text.split_once(" at path ") {
        Some((problem, _)) => std::io::Error::new(e.kind(), problem.to_string()),
        None => e,
    }
}

/// Writes a byte buffer atomically.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

static FOLDER_SERIAL: AtomicU64 = AtomicU64::new(0);

/// A fresh sibling name of `dir` for this process: `.surfcap-<name>.<pid>@<host>.<n>.<suffix>`.
fn sibling(parent: &Path, name: &str, suffix: &str) -> PathBuf {
    let n = FOLDER_SERIAL.fetch_add(1, Ordering::Relaxed);
    parent.join(format!("{PREFIX}{name}.{}.{n}.{suffix}", owner_tag()))
}

/// Hard-links (or copies) every entry of `from` that `keep` accepts and
/// `to` does not already have into `to`, recursively.
fn carry_over(from: &Path, to: &Path, keep: &dyn Fn(&Path) -> bool) -> std::io::Result<()> {
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        if !keep(&src) || dst.exists() {
            continue;
        }
        let t = entry.file_type()?;
        if t.is_dir() {
            std::fs::create_dir(&dst)?;
            carry_over(&src, &dst, &|_| true)?;
        } else if t.is_file() && std::fs::hard_link(&src, &dst).is_err() {
            std::fs::copy(&src, &dst)?;
        }
    }
    Ok(())
}

/// Writes the folder `dir` atomically: `fill` writes the new contents into a
/// temporary sibling folder, which then replaces `dir` by rename. Entries of
/// an existing `dir` that `keep` accepts (and `fill` did not write) are
/// carried over into the new folder; the rest of the old folder is removed.
/// If a racing writer replaces `dir` during the carry-over, the entries not yet
/// carried are left to it.
///
/// Readers see the old folder, no folder (for the instant between two
/// renames), or the complete new one; never a mix. Two writers racing on one
/// folder each install a complete folder, and the last rename wins. If `fill`
/// fails, the temporary folder is removed and `dir` is left untouched.
pub fn write_dir_atomic<F>(dir: &Path, keep: &dyn Fn(&Path) -> bool, fill: F) -> Result<()>
where
    F: FnOnce(&Path) -> Result<()>,
{
    let name = match dir.file_name().and_then(|n| n.to_str()) {
        Some(n) if n != "." && n != ".." => n.to_string(),
        _ => return Err(Error::file(dir, "an output folder needs a plain name (not '.' or '..')")),
    };
    let parent = parent_of(dir);
    std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
    // One stat: a racing writer may move `dir` away between two.
    if std::fs::metadata(dir).is_ok_and(|m| !m.is_dir()) {
        return Err(Error::file(dir, "exists and is not a folder"));
    }
    remove_stale_temporaries(parent);
    let tmp = sibling(parent, &name, "tmpdir");
    // Errors name the output folder, not its temporary sibling.
    std::fs::create_dir(&tmp).map_err(|e| Error::io(dir, e))?;
    let filled = fill(&tmp).and_then(|()| {
        match carry_over(dir, &tmp, keep) {
            // No old folder, or another writer moved it away meanwhile (its own complete
            // folder replaces it): nothing more to carry over.
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            r => r.map_err(|e| Error::io(dir, e))?,
        }
        sync_dir(&tmp).map_err(|e| Error::io(dir, e))
    });
    if let Err(e) = filled {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(e);
    }
    let mut retired = Vec::new();
    let mut installed = Err(std::io::Error::other("no attempt"));
    for _ in 0..64 {
        installed = std::fs::rename(&tmp, dir);
        if installed.is_ok() {
            break;
        }
        // One stat of what stands at `dir` now (a racing writer may change it between two).
        match std::fs::metadata(dir) {
            // A folder (not empty): move it aside, then try again (another writer may move it
            // first, or install its own).
            Ok(m) if m.is_dir() => {
                let old = sibling(parent, &name, "old");
                if std::fs::rename(dir, &old).is_ok() {
                    retired.push(old);
                }
            }
            Ok(_) => break,
            // `dir` vanished since the rename: the next rename installs.
            Err(_) => {}
        }
    }
    for old in &retired {
        let _ = std::fs::remove_dir_all(old);
    }
    if let Err(e) = installed {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(Error::io(dir, e));
    }
    sync_dir(parent).map_err(|e| Error::io(parent, e))
}

/// Flushes a folder's entries (the renames into it) to disk.
fn sync_dir(dir: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    std::fs::File::open(dir)?.sync_all()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder where no file can be created, even by root (procfs refuses new files): the
    /// error names the destination, never the temporary `tempfile` tried to create.
    #[test]
    fn a_temporary_that_cannot_be_created_is_reported_under_the_destination_name() {
        let dest = Path::new("/proc/self/surfcap-out.bin");
        if !dest.parent().is_some_and(Path::is_dir) {
            eprintln!("no /proc/self here: skipped");
            return;
        }
        let err = write_bytes_atomic(dest, b"x").unwrap_err().to_string();
        assert!(err.starts_with("/proc/self/surfcap-out.bin: "), "{err}");
        assert!(!err.contains(".surfcap-") && !err.contains(" at path "), "{err}");
        assert!(!dest.exists());
    }

    #[test]
    fn a_scratch_file_is_a_temporary_beside_the_output_and_goes_when_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let scratch = scratch_file(&dir.path().join("out")).unwrap();
        let name = scratch.path().file_name().unwrap().to_str().unwrap().to_string();
        assert_eq!(scratch.path().parent(), Some(dir.path()));
        assert_eq!(temp_owner(&name), Some(std::process::id()), "{name}");
        drop(scratch);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn failed_fill_leaves_nothing_behind() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.bin");
        let r = write_atomic(&out, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert!(!out.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "temporary file left behind");
    }

    #[test]
    fn an_old_folder_moved_away_during_the_carry_over_is_not_an_error() {
        // Another writer moves the old folder away while this one carries over its kept
        // entries (simulated in `keep`): the write still installs its complete folder.
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("seq");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("a.keep"), "old").unwrap();
        std::fs::write(out.join("b.keep"), "old").unwrap();
        let away = root.path().join("moved");
        let keep = |p: &Path| {
            if out.exists() {
                std::fs::rename(&out, &away).unwrap();
            }
            !p.ends_with("new.txt")
        };
        write_dir_atomic(&out, &keep, |tmp| {
            std::fs::write(tmp.join("new.txt"), "new").map_err(|e| Error::io(tmp, e))
        })
        .unwrap();
        assert_eq!(std::fs::read_to_string(out.join("new.txt")).unwrap(), "new");
    }

    #[cfg(unix)]
    #[test]
    fn outputs_are_world_readable() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.bin");
        write_bytes_atomic(&out, b"x").unwrap();
        let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode & 0o044, 0o044, "mode {mode:o}");
    }

    #[test]
    fn stale_temporaries_of_dead_local_writers_only_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let dead = u32::MAX - 1; // no such process
        let names = [
            format!(".surfcap-{dead}@{}-abc.tmp", host()),
            format!(".surfcap-seq.{dead}@{}.0.tmpdir", host()),
            format!(".surfcap-{dead}@otherhost-abc.tmp"),
            format!(".surfcap-{}-abc.tmp", owner_tag()),
            "notes.tmp".to_string(),
        ];
        for n in &names[..3] {
            std::fs::create_dir_all(dir.path().join(n)).unwrap();
        }
        for n in &names[3..] {
            std::fs::write(dir.path().join(n), "x").unwrap();
        }
        remove_stale_temporaries(dir.path());
        let mut left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        let mut want = names[2..].to_vec();
        want.sort();
        assert_eq!(left, want);
    }

    #[test]
    fn success_replaces_existing_file() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("sub/a.bin");
        write_bytes_atomic(&out, b"one").unwrap();
        write_bytes_atomic(&out, b"two").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"two");
    }
}
