//! A cache of finished runs, keyed by the hash of their inputs: what lets `lash study` and
//! `lash extremes` resume after an interruption without redoing what had finished.
//!
//! ```text
//! key    = sha256( canonical JSON { build, kind, inputs } )          (64 hex digits)
//!          build  = lash's version + sha256 of the running executable (build_id): a rebuilt
//!                   lash never reuses results of another build
//!          kind   = what the entry is ("study run", "extremes reference", …)
//!          inputs = everything the result depends on (the scene, the solver options, …)
//! file   = DIR/KEY[..32].json = { key, value }, written atomically when the run finishes;
//!          read back only if it parses and holds the whole key (anything else is ignored
//!          and the run done again)
//! ```
//!
//! Results come back bit for bit (serde_json's float round trip), so a resumed command
//! writes the same numbers as an uninterrupted one; only wall times differ (a reused run
//! keeps the wall time it was measured with). Deleting DIR makes everything run again.
//!
//! Source: docs/outputs.md ("Progress and interrupting a command", `cache/`).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

use crate::error::Error;
use crate::run::case::sha256_hex;
use crate::store::claim;
use crate::store::io;

/// Name of the cache folder inside a command's output directory.
pub(crate) const CACHE_DIR: &str = "cache";

/// The build a cache entry was made by: `VERSION+` the first 16 hex digits of sha256 of the
/// running executable (`VERSION+unknown` where it cannot be read).
pub(crate) fn build_id() -> &'static str {
    static ID: OnceLock<String> = OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe().and_then(std::fs::read);
        let hash = exe.map_or_else(|_| "unknown".to_string(), |b| sha256_hex(&b)[..16].into());
        format!("{}+{hash}", env!("CARGO_PKG_VERSION"))
    })
}

/// A cache of finished runs in one folder.
///
/// Source: this module.
#[derive(Clone, Debug)]
pub(crate) struct RunCache {
    dir: PathBuf,
}

#[derive(Serialize, serde::Deserialize)]
struct Entry<K, T> {
    key: K,
    value: T,
}

impl RunCache {
    /// The cache in `dir` (created on the first store; temporary files that processes gone
    /// from this host left there are removed).
    pub(crate) fn new(dir: &Path) -> RunCache {
        claim::remove_dead_temporaries(dir);
        RunCache {
            dir: dir.to_path_buf(),
        }
    }

    /// The cache folder.
    pub(crate) fn dir(&self) -> &Path {
        &self.dir
    }

    /// The key of a run of `kind` with these inputs (module doc).
    pub(crate) fn key<I: Serialize + ?Sized>(
        &self,
        kind: &str,
        inputs: &I,
    ) -> Result<String, Error> {
        let v = serde_json::json!({
            "build": build_id(),
            "kind": kind,
            "inputs": serde_json::to_value(inputs)
                .map_err(|e| Error::Internal(format!("cache key of {kind}: {e}")))?,
        });
        Ok(sha256_hex(canonical(&v).as_bytes()))
    }

    fn path(&self, key: &str) -> PathBuf {
        self.dir.join(format!("{}.json", &key[..32.min(key.len())]))
    }

    /// Whether an entry for `key` is there (not whether it is readable).
    pub(crate) fn contains(&self, key: &str) -> bool {
        self.path(key).is_file()
    }

    /// The value stored under `key`, if its file parses and holds this key.
    pub(crate) fn load<T: DeserializeOwned>(&self, key: &str) -> Option<T> {
        let bytes = std::fs::read(self.path(key)).ok()?;
        let e: Entry<String, T> = serde_json::from_slice(&bytes).ok()?;
        (e.key == key).then_some(e.value)
    }

    /// Stores `value` under `key` (atomically; the folder is created if needed).
    pub(crate) fn store<T: Serialize>(&self, key: &str, value: &T) -> Result<(), Error> {
        io::create_dir(&self.dir)?;
        let path = self.path(key);
        let bytes = serde_json::to_vec(&Entry { key, value })
            .map_err(|e| Error::Internal(format!("cache {}: {e}", path.display())))?;
        io::write_atomic(&path, &bytes)
    }
}

/// Serialises a JSON value with object keys sorted at every level: the form that is hashed
/// for cache keys and sweep point ids.
pub(crate) fn canonical(v: &Value) -> String {
    match v {
        Value::Object(m) => {
            let mut keys: Vec<&String> = m.keys().collect();
            keys.sort();
            let parts: Vec<String> = keys
                .into_iter()
                .map(|k| format!("{}:{}", Value::String(k.clone()), canonical(&m[k])))
                .collect();
            format!("{{{}}}", parts.join(","))
        }
        Value::Array(a) => {
            let parts: Vec<String> = a.iter().map(canonical).collect();
            format!("[{}]", parts.join(","))
        }
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_come_back_bit_for_bit_under_their_own_key_only() {
        let d = tempfile::tempdir().unwrap();
        let c = RunCache::new(&d.path().join("cache"));
        let k = c
            .key("test", &serde_json::json!({"rtol": 1e-10, "case": "a"}))
            .unwrap();
        // The same inputs written in another order give the same key; other inputs another.
        assert_eq!(
            k,
            c.key("test", &serde_json::json!({"case": "a", "rtol": 1e-10}))
                .unwrap()
        );
        assert_ne!(
            k,
            c.key(
                "test",
                &serde_json::json!({"case": "a", "rtol": 1e-10 * (1.0 + f64::EPSILON)})
            )
            .unwrap()
        );
        assert_ne!(
            k,
            c.key("other", &serde_json::json!({"case": "a", "rtol": 1e-10}))
                .unwrap()
        );
        assert!(!c.contains(&k) && c.load::<Vec<f64>>(&k).is_none());
        // Numbers that need all 17 digits survive the round trip exactly.
        let v = vec![
            0.1 + 0.2,
            std::f64::consts::PI / 3.0,
            -1.234_567_890_123_456_7e-300,
        ];
        c.store(&k, &v).unwrap();
        assert_eq!(c.load::<Vec<f64>>(&k).unwrap(), v);
        // A file whose key differs (another entry sharing the 32-digit name) is not used.
        let mut forged = k.clone();
        forged.replace_range(40..41, if &k[40..41] == "0" { "1" } else { "0" });
        assert!(c.load::<Vec<f64>>(&forged).is_none());
        // A corrupt file is ignored.
        std::fs::write(c.path(&k), b"{\"key\": ").unwrap();
        assert!(c.contains(&k) && c.load::<Vec<f64>>(&k).is_none());
        assert!(build_id().starts_with(env!("CARGO_PKG_VERSION")));
    }
}
