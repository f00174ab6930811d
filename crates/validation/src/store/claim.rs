//! Claim files: which process works on a sweep point, so that several processes on one sweep
//! (a job array on a shared file system, two shells) never compute the same point twice; and
//! whether a process that left a file behind is still alive.
//!
//! ```text
//! claim     DIR/claim.json = { pid, host, process_start, since, nonce, boot_id }, created
//!           exclusively
//!           (hard link of a complete temporary file, which fails if the claim exists; or
//!           O_CREAT|O_EXCL where hard links are refused), so a reader never sees half a claim
//! busy      a claim that is not stale: another process has the point
//! stale     same machine (host name, and boot id where known) and the pid is gone, a zombie,
//!           or another process (its start time differs),
//!           or the claim's modification time is older than STALE_AFTER (any host: its holder
//!           refreshes it every HEARTBEAT while it works, so an old one lost its holder)
//! take-over rename(claim → .claim.stale-NONCE): one process wins the rename; the winner
//!           checks that it moved the stale claim it read (else it puts the live one back)
//!           and then claims the point exclusively like anyone else
//! release   the holder removes its claim (if still its own) when the point is done,
//!           failed or abandoned
//! ```
//!
//! Across hosts a claim is judged by its age alone (a lease renewed by the heartbeat): a
//! process killed on another node (a job that hit its time limit) blocks its point for at most
//! [`STALE_AFTER`], and a sweep process that has finished its own points waits for it and then
//! takes the point over (module `sweep::runner`). Liveness on this machine is read from
//! `/proc` (Linux: pid, start time, zombie state), the machine told by its host name and boot
//! id, so two nodes that share a host name never judge each other's pids; elsewhere only the
//! age counts. Only the modification time of the claim is compared with this host's clock:
//! nodes whose clocks disagree by more than a minute or two shorten or lengthen the lease.
//!
//! Source: docs/outputs.md ("Sweeps": claims, resuming).

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::store::io;

/// Name of the claim file inside a point's directory.
pub(crate) const CLAIM_FILE: &str = "claim.json";
/// How often a holder refreshes the modification time of its claims.
pub(crate) const HEARTBEAT: Duration = Duration::from_secs(30);
/// Age of a claim's modification time beyond which it is stale whatever its host (ten
/// missed heartbeats: slack for a loaded node and for attribute caching of network file
/// systems, which can delay a seen modification time by a minute).
pub(crate) const STALE_AFTER: Duration = Duration::from_secs(300);

/// The content of a claim file.
///
/// ```text
/// { pid, host, process_start (Linux: start time in clock ticks after boot), since (Unix s),
///   boot_id (Linux),
///   nonce (unique per claim) }
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) struct ClaimRecord {
    /// Process id of the holder.
    pub pid: u32,
    /// Host name of the holder.
    pub host: String,
    /// Start time of the holder process (field 22 of /proc/PID/stat), to tell a reused pid.
    pub process_start: Option<u64>,
    /// When the claim was made, seconds since the Unix epoch.
    pub since: u64,
    /// Unique token of this claim.
    pub nonce: String,
    /// Boot id of the holder's machine (Linux), so that a machine that shares the host name
    /// never judges the holder's pid; absent in claims of older versions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub boot_id: Option<String>,
}

impl ClaimRecord {
    /// A new claim of this process.
    pub(crate) fn mine() -> ClaimRecord {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let since = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let pid = std::process::id();
        ClaimRecord {
            pid,
            host: host_name().to_string(),
            process_start: process_start(pid),
            since,
            nonce: format!("{}-{pid}-{since}-{n}", host_name()),
            boot_id: boot_id().map(str::to_string),
        }
    }

    /// "host:pid", for messages.
    pub(crate) fn holder(&self) -> String {
        format!("{}:{}", self.host, self.pid)
    }
}

/// The host name (Linux: /proc/sys/kernel/hostname; else $HOSTNAME; else "unknown").
pub(crate) fn host_name() -> &'static str {
    static HOST: OnceLock<String> = OnceLock::new();
    HOST.get_or_init(|| {
        fs::read_to_string("/proc/sys/kernel/hostname")
            .ok()
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .or_else(|| std::env::var("HOSTNAME").ok().filter(|s| !s.is_empty()))
            .unwrap_or_else(|| "unknown".into())
    })
}

/// Start time of process `pid` in clock ticks after boot (Linux: field 22 of
/// /proc/PID/stat); None where it cannot be read.
pub(crate) fn process_start(pid: u32) -> Option<u64> {
    let stat = fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count after the last ')'.
    let rest = &stat[stat.rfind(')')? + 1..];
    rest.split_whitespace().nth(19)?.parse().ok()
}

/// Whether a process on this host is alive: Some(true/false) where /proc tells (Linux), None
/// where it cannot be known. A pid whose start time differs from `start` is another process;
/// a zombie (state Z or X in /proc/PID/stat: killed, not yet reaped) is dead.
pub(crate) fn alive_here(pid: u32, start: Option<u64>) -> Option<bool> {
    if !Path::new("/proc/self/stat").exists() {
        return None;
    }
    let Ok(stat) = fs::read_to_string(format!("/proc/{pid}/stat")) else {
        return Some(false);
    };
    let state = stat
        .rfind(')')
        .and_then(|i| stat[i + 1..].split_whitespace().next());
    if matches!(state, Some("Z" | "X")) {
        return Some(false);
    }
    match process_start(pid) {
        None => Some(false),
        Some(s) => Some(start.is_none_or(|want| want == s)),
    }
}

/// This machine's boot id (Linux: /proc/sys/kernel/random/boot_id), which tells two machines
/// apart when they share a host name (containers, cloned images); None elsewhere.
pub(crate) fn boot_id() -> Option<&'static str> {
    static BOOT: OnceLock<Option<String>> = OnceLock::new();
    BOOT.get_or_init(|| {
        fs::read_to_string("/proc/sys/kernel/random/boot_id")
            .ok()
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
    })
    .as_deref()
}

/// Whether a claim is stale (module doc): its holder is gone from this host, or it is older
/// than [`STALE_AFTER`].
pub(crate) fn is_stale(c: &ClaimRecord, age: Duration) -> bool {
    // The same machine: the same host name and, where both are known, the same boot.
    let here = c.host == host_name()
        && match (c.boot_id.as_deref(), boot_id()) {
            (Some(a), Some(b)) => a == b,
            _ => true,
        };
    if here && alive_here(c.pid, c.process_start) == Some(false) {
        return true;
    }
    age > STALE_AFTER
}

/// What [`try_claim`] found.
///
/// Source: this module.
#[derive(Debug)]
pub(crate) enum Claimed {
    /// The point is ours until the guard is dropped.
    Mine(ClaimGuard),
    /// Another live process holds it.
    Busy(ClaimRecord),
}

/// A held claim: released (the file removed, if it is still ours) on drop.
///
/// Source: this module.
#[derive(Debug)]
pub(crate) struct ClaimGuard {
    path: PathBuf,
    nonce: String,
}

impl ClaimGuard {
    /// The claim file.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for ClaimGuard {
    fn drop(&mut self) {
        if read_claim(&self.path).is_some_and(|(c, _)| c.nonce == self.nonce) {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// The claim at `path` and its age, if it exists and parses.
pub(crate) fn read_claim(path: &Path) -> Option<(ClaimRecord, Duration)> {
    let bytes = fs::read(path).ok()?;
    let c: ClaimRecord = serde_json::from_slice(&bytes).ok()?;
    Some((c, age_of(path)))
}

fn age_of(path: &Path) -> Duration {
    fs::metadata(path)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| SystemTime::now().duration_since(t).ok())
        .unwrap_or_default()
}

/// Creates `path` with `bytes` only if it does not exist; Ok(false) if it exists.
fn create_exclusive(path: &Path, bytes: &[u8]) -> Result<bool, Error> {
    let tmp = io::temp_path(path);
    let mut f = File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
    // No fsync: other processes read the claim through the page cache (or, on NFS, after the
    // close-to-open flush of `drop`), and a claim need not outlive a crash of its machine (its
    // holder is dead then: the claim is stale). An fsync here cost 3.5 ms a point, a quarter
    // of a short sweep point's wall time (BENCHMARKS.md, "Sweeps: parallel efficiency").
    let written = f.write_all(bytes);
    drop(f);
    if let Err(e) = written {
        let _ = fs::remove_file(&tmp);
        return Err(Error::io(&tmp, e));
    }
    let linked = fs::hard_link(&tmp, path);
    let _ = fs::remove_file(&tmp);
    match linked {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
        Err(_) => {
            // A file system without hard links: O_CREAT | O_EXCL (a reader may then see an
            // empty claim for a moment, which it takes as busy).
            match fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(path)
            {
                Ok(mut f) => {
                    f.write_all(bytes).map_err(|e| Error::io(path, e))?;
                    Ok(true)
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
                Err(e) => Err(Error::io(path, e)),
            }
        }
    }
}

/// Claims the point whose directory is `dir` (which must exist): creates `dir/claim.json`
/// exclusively, taking over a stale claim (module doc).
pub(crate) fn try_claim(dir: &Path) -> Result<Claimed, Error> {
    let path = dir.join(CLAIM_FILE);
    let me = ClaimRecord::mine();
    let bytes = serde_json::to_vec_pretty(&me)
        .map_err(|e| Error::Internal(format!("claim {}: {e}", path.display())))?;
    // A stale claim is taken over at most a few times (each round another process may win).
    for _ in 0..4 {
        if create_exclusive(&path, &bytes)? {
            return Ok(Claimed::Mine(ClaimGuard {
                path,
                nonce: me.nonce,
            }));
        }
        let Some((held, age)) = read_claim(&path) else {
            // Half-written (no hard links) or just removed: busy unless it is old.
            if path.exists() && age_of(&path) <= STALE_AFTER {
                return Ok(Claimed::Busy(ClaimRecord {
                    pid: 0,
                    host: "?".into(),
                    process_start: None,
                    since: 0,
                    nonce: String::new(),
                    boot_id: None,
                }));
            }
            let _ = fs::remove_file(&path);
            continue;
        };
        if !is_stale(&held, age) {
            return Ok(Claimed::Busy(held));
        }
        let grave = dir.join(format!(".claim.stale-{}", me.nonce));
        match fs::rename(&path, &grave) {
            Ok(()) => {
                let moved = fs::read(&grave)
                    .ok()
                    .and_then(|b| serde_json::from_slice::<ClaimRecord>(&b).ok());
                if moved.as_ref().is_some_and(|m| m.nonce != held.nonce) {
                    // A live claim made after we read the stale one: put it back.
                    let _ = fs::hard_link(&grave, &path);
                }
                let _ = fs::remove_file(&grave);
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(Error::io(&path, e)),
        }
    }
    match read_claim(&path) {
        Some((held, _)) => Ok(Claimed::Busy(held)),
        None => Err(Error::Internal(format!(
            "claim {}: could not be taken",
            path.display()
        ))),
    }
}

/// Refreshes the modification time of a claim file (the heartbeat).
pub(crate) fn touch(path: &Path) {
    if let Ok(f) = fs::OpenOptions::new().append(true).open(path) {
        let _ = f.set_modified(SystemTime::now());
    }
}

/// Removes the temporary files ([`io::temp_path`]: `.NAME.tmp-PID-N…`) in `dir` left by
/// processes that are gone from this host; returns how many. Files of live processes, and of
/// processes whose liveness cannot be known, stay.
pub(crate) fn remove_dead_temporaries(dir: &Path) -> usize {
    let Ok(rd) = fs::read_dir(dir) else {
        return 0;
    };
    let mut n = 0;
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = temp_pid(&name) else {
            continue;
        };
        if alive_here(pid, None) == Some(false) && fs::remove_file(e.path()).is_ok() {
            n += 1;
        }
    }
    n
}

/// Removes every temporary file ([`io::temp_path`]) in `dir`, whoever wrote it: for a
/// directory this process holds the claim of, whose earlier holders are gone.
pub(crate) fn remove_all_temporaries(dir: &Path) -> usize {
    let Ok(rd) = fs::read_dir(dir) else {
        return 0;
    };
    let mut n = 0;
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if temp_pid(&name).is_some() && fs::remove_file(e.path()).is_ok() {
            n += 1;
        }
    }
    n
}

/// The pid in a temporary file name `.NAME.tmp-PID-N[.EXT]`.
pub(crate) fn temp_pid(name: &str) -> Option<u32> {
    if !name.starts_with('.') {
        return None;
    }
    let rest = &name[name.rfind(".tmp-")? + 5..];
    rest.split('-').next()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_claim_is_busy_and_a_released_one_free() {
        let d = tempfile::tempdir().unwrap();
        let Claimed::Mine(g) = try_claim(d.path()).unwrap() else {
            panic!("first claim refused")
        };
        let (c, _) = read_claim(g.path()).unwrap();
        assert_eq!(c.pid, std::process::id());
        assert_eq!(c.host, host_name());
        // This process is alive: its own claim is busy to a second claimant.
        match try_claim(d.path()).unwrap() {
            Claimed::Busy(h) => assert_eq!(h.nonce, c.nonce),
            Claimed::Mine(_) => panic!("claimed twice"),
        }
        drop(g);
        assert!(!d.path().join(CLAIM_FILE).exists());
        assert!(matches!(try_claim(d.path()).unwrap(), Claimed::Mine(_)));
        // No temporary file is left beside the claim.
        let names: Vec<String> = fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.is_empty(), "{names:?}");
    }

    #[test]
    fn a_claim_of_a_dead_process_or_an_old_one_is_taken_over() {
        let d = tempfile::tempdir().unwrap();
        // A pid of this host that does not run: past the kernel's pid_max (at most 2^22).
        let dead = ClaimRecord {
            pid: 4_194_305,
            ..ClaimRecord::mine()
        };
        fs::write(
            d.path().join(CLAIM_FILE),
            serde_json::to_vec(&dead).unwrap(),
        )
        .unwrap();
        if alive_here(dead.pid, None) == Some(false) {
            let Claimed::Mine(g) = try_claim(d.path()).unwrap() else {
                panic!("stale claim of a dead pid not taken over")
            };
            assert_eq!(read_claim(g.path()).unwrap().0.pid, std::process::id());
        }
        // Another host's claim: live while its heartbeat is fresh, stale once older than
        // STALE_AFTER.
        let other = ClaimRecord {
            host: format!("{}-elsewhere", host_name()),
            pid: 1,
            ..ClaimRecord::mine()
        };
        assert!(!is_stale(&other, Duration::from_secs(10)));
        assert!(is_stale(&other, STALE_AFTER + Duration::from_secs(1)));
        // A reused pid (this process's, with another start time) is not its holder.
        let reused = ClaimRecord {
            process_start: process_start(std::process::id()).map(|s| s + 1),
            ..ClaimRecord::mine()
        };
        if reused.process_start.is_some() {
            assert!(is_stale(&reused, Duration::ZERO));
        }
        assert!(!is_stale(&ClaimRecord::mine(), Duration::ZERO));
    }

    /// A killed process not yet reaped (a zombie) is dead; a claim from a machine that shares
    /// this host name but not its boot is judged by its age only, whatever its pid.
    #[test]
    fn zombies_are_dead_and_other_machines_pids_are_not_judged() {
        if alive_here(std::process::id(), None).is_none() {
            return; // no /proc: only ages count
        }
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let t0 = std::time::Instant::now();
        // Until it has exited (a zombie until waited for).
        while alive_here(child.id(), None) != Some(false) {
            assert!(
                t0.elapsed() < Duration::from_secs(10),
                "a zombie counted as alive"
            );
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(process_start(child.id()).is_some(), "reaped too early");
        child.wait().unwrap();
        let twin = ClaimRecord {
            pid: 4_194_305,
            boot_id: Some("another-machine".into()),
            ..ClaimRecord::mine()
        };
        if boot_id().is_some() {
            assert!(!is_stale(&twin, Duration::from_secs(10)));
            assert!(is_stale(&twin, STALE_AFTER + Duration::from_secs(1)));
        }
        let here = ClaimRecord {
            pid: 4_194_305,
            ..ClaimRecord::mine()
        };
        assert!(is_stale(&here, Duration::ZERO));
    }

    #[test]
    fn temporaries_of_dead_processes_are_removed() {
        let d = tempfile::tempdir().unwrap();
        let mine = io::temp_path(&d.path().join("summary.json"));
        fs::write(&mine, b"x").unwrap();
        let dead = d.path().join(".summary.json.tmp-4194305-0.json");
        fs::write(&dead, b"x").unwrap();
        fs::write(d.path().join("result.json"), b"{}").unwrap();
        assert_eq!(temp_pid(".a.json.tmp-123-4.json"), Some(123));
        assert_eq!(temp_pid("a.json"), None);
        if alive_here(4_194_305, None) == Some(false) {
            assert_eq!(remove_dead_temporaries(d.path()), 1);
            assert!(mine.exists() && !dead.exists());
        }
        assert_eq!(remove_all_temporaries(d.path()), 1);
        assert!(!mine.exists() && d.path().join("result.json").exists());
    }
}
