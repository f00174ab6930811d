//! Atomic file output: nothing half-written ever lands in an output directory, and a
//! directory never mixes two runs.
//!
//! ```text
//! write(path, bytes):  tmp = dir(path)/.NAME.tmp-PID-N[.EXT]
//!                      write bytes → fsync(tmp) → rename(tmp, path) → fsync(dir)
//! OutDir (a run's whole directory DIR):
//!   create   clean stale temporaries of dead processes beside DIR; DIR must be absent, empty
//!            or an earlier run's: its marker RUN_MARKER (.lash-run, lash's own) present and
//!            every other entry a file a run writes (else exit 2: nothing of the user's is
//!            ever deleted, and a directory of someone's files that happen to be named like a
//!            run's is not taken for one); work = PARENT/.NAME.tmp-PID-N, a fresh directory
//!            holding the marker
//!   write    every file into work
//!   commit   fsync(work); rename(DIR, PARENT/.NAME.old-PID-N); rename(work, DIR);
//!            remove the old one; fsync(PARENT)
//!   dropped uncommitted (an error): work removed, DIR untouched
//! stale    a name .X.tmp-PID-N[.EXT] or .X.old-PID-N whose process PID is gone (a killed run):
//!          removed by the next create_dir or OutDir::create of the same place; an .old
//!          directory whose DIR is missing (a run killed between the two renames of commit)
//!          is renamed back to DIR first
//! ```
//!
//! A rename within one directory is atomic on POSIX file systems (rename(2)), so a reader sees
//! either the old file or the complete new one. A directory cannot be renamed onto a non-empty
//! one, so [`OutDir::commit`] takes two renames, between which DIR is briefly absent (never
//! mixed). The temporary file keeps the extension of the target because some writers (the PNG
//! encoder) choose the format from it. On any failure the temporary file is removed. Whether a
//! process is alive is read from `/proc/PID` (Linux); without `/proc` nothing is treated as
//! stale.

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

/// The marker of a run directory written by lash ([`OutDir`]): only a directory holding it is
/// replaced as an earlier run.
pub(crate) const RUN_MARKER: &str = ".lash-run";

/// Counter that makes temporary names unique within the process (threads write in parallel).
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Creates the directory `dir` and its parents if needed, and removes the stale temporary
/// files of dead processes in it (module doc).
pub(crate) fn create_dir(dir: &Path) -> Result<(), Error> {
    fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    if !dir.is_dir() {
        return Err(Error::Input(format!(
            "{} is not a directory",
            dir.display()
        )));
    }
    clean_stale(dir);
    Ok(())
}

/// The PID in a temporary name `.X.tmp-PID-N[.EXT]` or `.X.old-PID-N`, and whether it is an
/// `.old` directory; None for any other name.
pub(crate) fn temp_owner(name: &str) -> Option<(u32, bool)> {
    if !name.starts_with('.') {
        return None;
    }
    let (pos, old) = match (name.rfind(".tmp-"), name.rfind(".old-")) {
        (Some(a), Some(b)) if b > a => (b, true),
        (Some(a), _) => (a, false),
        (None, Some(b)) => (b, true),
        (None, None) => return None,
    };
    let rest = &name[pos + 5..];
    let (pid, rest) = rest.split_once('-')?;
    let n: &str = rest.split('.').next()?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if pos == 0 || !digits(pid) || !digits(n) || (old && n.len() != rest.len()) {
        return None;
    }
    Some((pid.parse().ok()?, old))
}

/// Whether process `pid` is alive; true when it cannot be told (no `/proc`).
fn alive(pid: u32) -> bool {
    if pid == std::process::id() || !Path::new("/proc/self").exists() {
        return true;
    }
    Path::new("/proc").join(pid.to_string()).exists()
}

/// The target name of an `.old` directory `.NAME.old-PID-N`.
fn old_target(name: &str) -> Option<&str> {
    let pos = name.rfind(".old-")?;
    name.get(1..pos).filter(|s| !s.is_empty())
}

/// Removes the stale temporaries of dead processes in `dir` (module doc); best effort.
pub(crate) fn clean_stale(dir: &Path) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let mut stale: Vec<(PathBuf, String, bool)> = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if let Some((pid, old)) = temp_owner(&name) {
            if !alive(pid) {
                stale.push((e.path(), name, old));
            }
        }
    }
    // A run killed between the two renames of a commit left DIR missing: its previous
    // contents come back.
    for (path, name, old) in &stale {
        if let (true, Some(target)) = (*old, old_target(name)) {
            let t = dir.join(target);
            if !t.exists() {
                let _ = fs::rename(path, &t);
            }
        }
    }
    for (path, _, _) in stale {
        if let Ok(m) = fs::symlink_metadata(&path) {
            let _ = if m.is_dir() {
                fs::remove_dir_all(&path)
            } else {
                fs::remove_file(&path)
            };
        }
    }
}

/// A run's output directory, written whole into a fresh sibling and swapped in when complete
/// (module doc): DIR never mixes two runs, and a run that fails to write leaves DIR as it was.
///
/// ```text
/// create(DIR, owns) → write into path() → commit() | drop (work removed)
/// ```
///
/// Source: docs/outputs.md ("General rules").
#[derive(Debug)]
pub(crate) struct OutDir {
    target: PathBuf,
    work: PathBuf,
    committed: bool,
}

impl OutDir {
    /// Prepares to replace `target`: cleans stale temporaries beside it, checks that every
    /// entry of an existing `target` is one a run writes (`owns(name, is_dir)`, or a
    /// temporary name), and creates the fresh working directory. Errors: `target` names no
    /// directory (`.`, `/`), is a file, or holds other files (exit 2: nothing is deleted).
    pub(crate) fn create(
        target: &Path,
        owns: &dyn Fn(&str, bool) -> bool,
    ) -> Result<OutDir, Error> {
        let Some(name) = target.file_name().map(|n| n.to_string_lossy().into_owned()) else {
            return Err(Error::Input(format!(
                "output directory {} must name a directory, not . or / (a run replaces its \
                 directory as a whole)",
                target.display()
            )));
        };
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        fs::create_dir_all(&parent).map_err(|e| Error::io(&parent, e))?;
        clean_stale(&parent);
        match fs::symlink_metadata(target) {
            Ok(m) if m.is_dir() => {
                let marked = target.join(RUN_MARKER).is_file();
                let mut foreign = Vec::new();
                for e in fs::read_dir(target).map_err(|e| Error::io(target, e))? {
                    let e = e.map_err(|e| Error::io(target, e))?;
                    let n = e.file_name().to_string_lossy().into_owned();
                    let is_dir = e.file_type().map(|t| t.is_dir()).unwrap_or(false);
                    if n == RUN_MARKER && !is_dir {
                        continue;
                    }
                    if !(marked && owns(&n, is_dir)) && temp_owner(&n).is_none() {
                        foreign.push(n);
                    }
                }
                if !foreign.is_empty() {
                    foreign.sort();
                    let more = if foreign.len() > 3 {
                        format!(" and {} more", foreign.len() - 3)
                    } else {
                        String::new()
                    };
                    foreign.truncate(3);
                    let why = if marked {
                        "holds files that are not a run's"
                    } else {
                        "is not a lash run directory (no .lash-run marker) and holds files"
                    };
                    return Err(Error::Input(format!(
                        "output directory {} {why} ({}{more}): a run replaces its directory as \
                         a whole, so give a new or empty one",
                        target.display(),
                        foreign.join(", ")
                    )));
                }
            }
            Ok(_) => {
                return Err(Error::Input(format!(
                    "{} is not a directory",
                    target.display()
                )))
            }
            Err(_) => {}
        }
        let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let work = parent.join(format!(".{name}.tmp-{}-{n}", std::process::id()));
        fs::create_dir(&work).map_err(|e| Error::io(&work, e))?;
        let out = OutDir {
            target: target.to_path_buf(),
            work: work.clone(),
            committed: false,
        };
        // Dropped on error: the work directory goes with it.
        fs::write(
            work.join(RUN_MARKER),
            concat!("lash ", env!("CARGO_PKG_VERSION"), "\n"),
        )
        .map_err(|e| Error::io(&work, e))?;
        Ok(out)
    }

    /// Where the files go until [`OutDir::commit`].
    pub(crate) fn path(&self) -> &Path {
        &self.work
    }

    /// `path` (inside the working directory) as it will be after the commit.
    pub(crate) fn final_path(&self, path: &Path) -> PathBuf {
        match path.strip_prefix(&self.work) {
            Ok(rel) => self.target.join(rel),
            Err(_) => path.to_path_buf(),
        }
    }

    /// Swaps the complete working directory in for the target (module doc).
    pub(crate) fn commit(mut self) -> Result<PathBuf, Error> {
        if let Ok(d) = File::open(&self.work) {
            let _ = d.sync_all();
        }
        let parent = self.work.parent().unwrap_or(Path::new(".")).to_path_buf();
        let old = if self.target.exists() {
            let name = self
                .target
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
            let old = parent.join(format!(".{name}.old-{}-{n}", std::process::id()));
            fs::rename(&self.target, &old).map_err(|e| Error::io(&self.target, e))?;
            Some(old)
        } else {
            None
        };
        if let Err(e) = fs::rename(&self.work, &self.target) {
            if let Some(old) = &old {
                let _ = fs::rename(old, &self.target);
            }
            return Err(Error::io(&self.target, e));
        }
        self.committed = true;
        if let Some(old) = old {
            let _ = fs::remove_dir_all(old);
        }
        if let Ok(d) = File::open(&parent) {
            let _ = d.sync_all();
        }
        Ok(self.target.clone())
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.work);
        }
    }
}

/// A temporary path beside `path`: same directory, hidden name, same extension.
pub(crate) fn temp_path(path: &Path) -> PathBuf {
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
pub(crate) fn write_atomic_with<F>(path: &Path, write: F) -> Result<(), Error>
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
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    write_atomic_with(path, |tmp| {
        let mut f = File::create(tmp).map_err(|e| Error::io(tmp, e))?;
        f.write_all(bytes).map_err(|e| Error::io(tmp, e))
    })
}

/// Writes `value` as pretty JSON (with a final newline) to `path` atomically.
pub(crate) fn write_json_atomic<T: serde::Serialize + ?Sized>(
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
    fn temporary_names_are_recognised_and_nothing_else() {
        let t = temp_path(Path::new("out/fig.png"));
        let name = t.file_name().unwrap().to_string_lossy().into_owned();
        assert_eq!(temp_owner(&name), Some((std::process::id(), false)));
        assert_eq!(temp_owner(".run.tmp-12-3"), Some((12, false)));
        assert_eq!(temp_owner(".summary.json.tmp-77-0"), Some((77, false)));
        assert_eq!(temp_owner(".run.old-12-3"), Some((12, true)));
        for other in [
            "run.tmp-12-3",
            ".tmp-12-3",
            ".run.tmp-12",
            ".run.tmp-x-3",
            ".run.old-12-3.png",
            "summary.json",
            ".git",
            ".claim-12",
        ] {
            assert_eq!(temp_owner(other), None, "{other}");
        }
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_cleaned() {
        if !Path::new("/proc/self").exists() {
            return;
        }
        let d = tempfile::tempdir().unwrap();
        // A PID above the kernel's maximum (4194304) is never alive.
        let dead = 4_999_999;
        let mine = std::process::id();
        fs::write(d.path().join(format!(".a.csv.tmp-{dead}-0.csv")), b"x").unwrap();
        fs::create_dir(d.path().join(format!(".run.tmp-{dead}-1"))).unwrap();
        fs::write(d.path().join(format!(".b.tmp-{mine}-2")), b"mine").unwrap();
        fs::write(d.path().join("keep.txt"), b"x").unwrap();
        // A run killed between the renames of its commit: DIR comes back from .old.
        let old = d.path().join(format!(".r.old-{dead}-3"));
        fs::create_dir(&old).unwrap();
        fs::write(old.join("summary.json"), b"{}").unwrap();
        clean_stale(d.path());
        assert_eq!(
            entries(d.path()),
            vec![format!(".b.tmp-{mine}-2"), "keep.txt".into(), "r".into()]
        );
        assert_eq!(fs::read(d.path().join("r/summary.json")).unwrap(), b"{}");
    }

    /// Issue 23(b): a directory holding only someone's file named like a run's (summary.json)
    /// is not an earlier run: it is refused and kept, not replaced. An empty one is taken.
    #[test]
    fn out_dir_recognises_a_run_by_its_marker_not_by_file_names() {
        let d = tempfile::tempdir().unwrap();
        let target = d.path().join("theirs");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("summary.json"), b"their notes").unwrap();
        let owns = |n: &str, dir: bool| !dir && n == "summary.json";
        let e = OutDir::create(&target, &owns).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput);
        assert!(e.to_string().contains("no .lash-run marker"), "{e}");
        assert_eq!(
            fs::read(target.join("summary.json")).unwrap(),
            b"their notes"
        );
        let empty = d.path().join("empty");
        fs::create_dir(&empty).unwrap();
        let o = OutDir::create(&empty, &owns).unwrap();
        fs::write(o.path().join("summary.json"), b"ours").unwrap();
        o.commit().unwrap();
        assert_eq!(entries(&empty), vec![RUN_MARKER, "summary.json"]);
        // Now it is a run of lash's: the next one replaces it.
        let o = OutDir::create(&empty, &owns).unwrap();
        o.commit().unwrap();
        assert_eq!(entries(&empty), vec![RUN_MARKER]);
    }

    #[test]
    fn out_dir_replaces_a_run_whole_or_not_at_all() {
        let d = tempfile::tempdir().unwrap();
        let target = d.path().join("run");
        let owns = |n: &str, dir: bool| !dir && (n.ends_with(".csv") || n.ends_with(".json"));
        // A first run.
        let o = OutDir::create(&target, &owns).unwrap();
        fs::write(o.path().join("summary.json"), b"first").unwrap();
        fs::write(o.path().join("a.csv"), b"first").unwrap();
        assert!(!target.exists());
        assert_eq!(o.final_path(&o.path().join("a.csv")), target.join("a.csv"));
        o.commit().unwrap();
        // A second run that fails before its commit leaves the first intact, and no trace.
        let o = OutDir::create(&target, &owns).unwrap();
        fs::write(o.path().join("b.csv"), b"second").unwrap();
        drop(o);
        assert_eq!(entries(&target), vec![RUN_MARKER, "a.csv", "summary.json"]);
        assert_eq!(entries(d.path()), vec!["run"]);
        // A third run replaces it: nothing of the first remains.
        let o = OutDir::create(&target, &owns).unwrap();
        fs::write(o.path().join("summary.json"), b"third").unwrap();
        o.commit().unwrap();
        assert_eq!(entries(&target), vec![RUN_MARKER, "summary.json"]);
        assert_eq!(fs::read(target.join("summary.json")).unwrap(), b"third");
        assert_eq!(entries(d.path()), vec!["run"]);
        // A directory with the user's files is refused, and kept.
        fs::write(target.join("notes.txt"), b"mine").unwrap();
        let e = OutDir::create(&target, &owns).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput);
        assert!(e.to_string().contains("(notes.txt)"), "{e}");
        assert!(target.join("notes.txt").is_file());
        for bad in [Path::new("."), Path::new("/")] {
            assert!(OutDir::create(bad, &owns).is_err());
        }
        let file = d.path().join("f");
        fs::write(&file, b"").unwrap();
        assert!(OutDir::create(&file, &owns).is_err());
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
