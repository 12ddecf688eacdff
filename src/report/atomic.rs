//! Writing output files so that no reader ever sees half of one and no file is destroyed
//! by mistake: a regular file (or a new one) is written to a hidden temporary file beside
//! it and renamed into place; a symbolic link is written through, to its target; a special
//! file (a device such as `/dev/null` or `/dev/stdout`, a FIFO) is written directly, since
//! renaming over it would replace the device. Every error is reported, a full disk
//! (`ENOSPC`, `/dev/full`) included.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The marker in temporary file names: `.<name>.afford-tmp-<pid>`.
const TEMP_MARK: &str = ".afford-tmp-";

/// Writes `bytes` to `path` (see [`write_with`]).
pub fn write_bytes(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_with(path, |w| w.write_all(bytes))
}

/// Writes what `fill` writes to `path`: atomically for a regular or new file (a hidden
/// temporary file renamed into place; removed on error), through a symbolic link to its
/// target, directly to a special file. Temporary files of the same target left by a
/// process that no longer runs (killed during a write) are removed first.
pub fn write_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let target = resolve(path);
    if let Ok(m) = fs::metadata(&target) {
        if !m.is_file() && !m.is_dir() {
            let mut w = BufWriter::new(OpenOptions::new().write(true).open(&target)?);
            fill(&mut w)?;
            return w.flush();
        }
    }
    remove_stale_temps(&target);
    let tmp = temp_path(&target);
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        fill(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        fs::rename(&tmp, &target)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// The file a write to `path` lands in: the end of its chain of symbolic links (a dangling
/// link's target is created), or `path` itself.
fn resolve(path: &Path) -> PathBuf {
    let mut p = path.to_path_buf();
    // A bounded walk: a cycle of links is left to the open to report.
    for _ in 0..40 {
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => match fs::read_link(&p) {
                Ok(t) => {
                    p = match p.parent() {
                        Some(dir) => dir.join(t),
                        None => t,
                    }
                }
                Err(_) => return p,
            },
            _ => return p,
        }
    }
    p
}

/// `<dir>/.<name>.afford-tmp-<pid>` beside `path`.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}{TEMP_MARK}{}", std::process::id()))
}

/// Removes `.<name>.afford-tmp-<pid>` files beside `target` whose process is gone (on
/// systems with `/proc`; elsewhere nothing is removed).
fn remove_stale_temps(target: &Path) {
    let Some(name) = target.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return;
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !Path::new("/proc/self").exists() {
        return;
    }
    let prefix = format!(".{name}{TEMP_MARK}");
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = file.strip_prefix(&prefix) else {
            continue;
        };
        if pid.parse::<u32>().is_ok() && !Path::new("/proc").join(pid).exists() {
            let _ = fs::remove_file(e.path());
        }
    }
}

/// Whether `a` and `b` name the same existing file (after links).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (fs::canonicalize(a), fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_file_is_written_and_no_temporary_file_is_left() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("out.json");
        write_bytes(&p, b"{}\n").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"{}\n");
        assert_eq!(fs::read_dir(d.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_failing_fill_leaves_the_old_file_and_no_temporary_file() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("out.csv");
        fs::write(&p, b"old").unwrap();
        let e = write_with(&p, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("stop"))
        });
        assert!(e.is_err());
        assert_eq!(fs::read(&p).unwrap(), b"old");
        assert_eq!(fs::read_dir(d.path()).unwrap().count(), 1);
    }
}
