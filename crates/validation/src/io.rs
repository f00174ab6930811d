//! Atomic file output: nothing half-written ever lands in an output directory.
//!
//! ```text
//! write(path, bytes):  tmp = dir(path)/.NAME.tmp-PID-N[.EXT]
//!                      write bytes → fsync(tmp) → rename(tmp, path) → fsync(dir)
//! ```
//!
//! A rename within one directory is atomic on POSIX file systems (rename(2)), so a reader sees
//! either the old file or the complete new one. The temporary file keeps the extension of the
//! target because some writers (the PNG encoder) choose the format from it. On any failure the
//! temporary file is removed.

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::Error;

/// What a command wrote: its result, the output directory and the files in it.
///
/// ```text
/// Written { result, dir, files }   files in the order written, each inside dir
/// ```
///
/// Source: this module.
#[derive(Debug)]
pub struct Written<T> {
    /// The command's result.
    pub result: T,
    /// The output directory.
    pub dir: PathBuf,
    /// The files written.
    pub files: Vec<PathBuf>,
}

/// Counter that makes temporary names unique within the process (threads write in parallel).
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Creates the directory `dir` and its parents if needed.
pub fn create_dir(dir: &Path) -> Result<(), Error> {
    fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    if !dir.is_dir() {
        return Err(Error::Input(format!(
            "{} is not a directory",
            dir.display()
        )));
    }
    Ok(())
}

/// A temporary path beside `path`: same directory, hidden name, same extension.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp = format!(".{name}.tmp-{}-{n}", std::process::id());
    if let Some(ext) = path.extension() {
        tmp.push('.');
        tmp.push_str(&ext.to_string_lossy());
    }
    path.with_file_name(tmp)
}

/// Writes a file atomically by letting `write` produce it at a temporary path beside `path`,
/// then syncing it and renaming it onto `path`. The parent directory must exist.
pub fn write_atomic_with<F>(path: &Path, write: F) -> Result<(), Error>
where
    F: FnOnce(&Path) -> Result<(), Error>,
{
    let tmp = temp_path(path);
    let result = write(&tmp).and_then(|()| {
        File::open(&tmp)
            .and_then(|f| f.sync_all())
            .map_err(|e| Error::io(&tmp, e))?;
        fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
    });
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
        return result;
    }
    sync_parent(path);
    Ok(())
}

/// Writes `bytes` to `path` atomically (temporary name, fsync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    write_atomic_with(path, |tmp| {
        let mut f = File::create(tmp).map_err(|e| Error::io(tmp, e))?;
        f.write_all(bytes).map_err(|e| Error::io(tmp, e))
    })
}

/// Writes `value` as pretty JSON (with a final newline) to `path` atomically.
pub fn write_json_atomic<T: serde::Serialize + ?Sized>(
    path: &Path,
    value: &T,
) -> Result<(), Error> {
    let mut s = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Internal(format!("serialising {}: {e}", path.display())))?;
    s.push('\n');
    write_atomic(path, s.as_bytes())
}

/// Syncs the directory holding `path` so that the rename itself is durable (best effort: some
/// file systems refuse to open directories).
fn sync_parent(path: &Path) {
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn write_atomic_replaces_and_leaves_no_temporary() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.json");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second");
        assert_eq!(entries(d.path()), vec!["a.json".to_string()]);
    }

    #[test]
    fn failed_writer_leaves_target_untouched() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("t.csv");
        write_atomic(&p, b"complete").unwrap();
        let r = write_atomic_with(&p, |tmp| {
            fs::write(tmp, b"half").unwrap();
            Err(Error::Internal("interrupted".into()))
        });
        assert!(matches!(r, Err(Error::Internal(_))));
        assert_eq!(fs::read(&p).unwrap(), b"complete");
        assert_eq!(entries(d.path()), vec!["t.csv".to_string()]);
    }

    #[test]
    fn temp_path_keeps_directory_and_extension() {
        let t = temp_path(Path::new("out/fig.png"));
        assert_eq!(t.parent().unwrap(), Path::new("out"));
        assert_eq!(t.extension().unwrap(), "png");
        assert!(t
            .file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with(".fig.png.tmp-"));
        assert_ne!(t, temp_path(Path::new("out/fig.png")));
    }

    #[test]
    fn create_dir_makes_parents_and_rejects_a_file() {
        let d = tempfile::tempdir().unwrap();
        let nested = d.path().join("x/y/z");
        create_dir(&nested).unwrap();
        assert!(nested.is_dir());
        let f = d.path().join("file");
        fs::write(&f, b"").unwrap();
        let e = create_dir(&f).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput);
    }

    #[test]
    fn missing_directory_is_an_io_error_naming_the_path() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("nope/a.txt");
        let e = write_atomic(&p, b"x").unwrap_err();
        assert!(matches!(e, Error::Io { .. }));
        assert!(e.to_string().contains("nope"));
    }
}
