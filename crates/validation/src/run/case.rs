//! Case references: a scene file or a built-in test problem.
//!
//! ```text
//! CASE = "testset:NAME"   a built-in test problem (summary.case = "testset:NAME",
//!                         scene_sha256 = null)
//!      | PATH             a JSON scene file (summary.case = file stem,
//!                         scene_sha256 = hex sha256 of the file's bytes)
//! Case::press(CASE)       (API only) a press case built in code (run::press::PressCase:
//!                         summary.case = its file stem in cases/press/; scene_sha256 = null)
//! ```
//!
//! Source: docs/outputs.md (`summary.json` fields `case`, `scene_sha256`). Loading checks that
//! the file exists and is well-formed JSON; the model crate validates the scene itself.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::error::Error;
use crate::run::press::PressCase;

/// Prefix of built-in test problems.
pub(crate) const BUILTIN_PREFIX: &str = "testset:";

/// Names (after the prefix) of the built-in test problems: the stiff problems of the IVP Test
/// Set in `lash_solver::testset` (rober, vdpolm, hires, orego).
pub(crate) const BUILTIN_NAMES: &[&str] = &lash_solver::testset::NAMES;

/// Where a case comes from.
///
/// ```text
/// File { path, bytes, sha256 = sha256(bytes), json } | BuiltIn(NAME) | Press(CASE)
/// ```
///
/// Source: docs/outputs.md (`case`, `scene_sha256`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum CaseSource {
    /// A scene file.
    File {
        /// Its path, as given (resolved against the base directory if relative).
        path: PathBuf,
        /// Its bytes.
        bytes: Vec<u8>,
        /// Hex sha256 of the bytes.
        sha256: String,
        /// The parsed JSON (syntax checked only).
        json: serde_json::Value,
    },
    /// A built-in test problem, by its name after `testset:`.
    BuiltIn(String),
    /// A press case of the paper, its scene built in code (the scene of its file in
    /// `cases/press/`).
    Press(PressCase),
}

/// A loaded case reference.
///
/// ```text
/// name = file stem | "testset:" NAME;   sha256 = sha256(file bytes) | none
/// ```
///
/// Source: docs/outputs.md (`case`, `scene_sha256`).
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The name recorded in summary.json (`case`).
    pub name: String,
    /// The file or the built-in.
    pub(crate) source: CaseSource,
}

impl Case {
    /// Resolves `spec` (a path or `testset:NAME`). A relative path is taken relative to
    /// `base_dir` when one is given (a sweep file's directory), else to the working directory.
    pub fn load(spec: &str, base_dir: Option<&Path>) -> Result<Case, Error> {
        if let Some(name) = spec.strip_prefix(BUILTIN_PREFIX) {
            return Case::builtin(name);
        }
        if spec.is_empty() {
            return Err(Error::Input("case: empty name".into()));
        }
        let given = Path::new(spec);
        let path = match base_dir {
            Some(b) if given.is_relative() => b.join(given),
            _ => given.to_path_buf(),
        };
        if !path.is_file() {
            return Err(Error::Input(format!(
                "case file {} not found",
                path.display()
            )));
        }
        let bytes = std::fs::read(&path).map_err(|e| Error::io(&path, e))?;
        let json: serde_json::Value = serde_json::from_slice(&bytes).map_err(|e| {
            Error::Input(format!(
                "case file {} is not valid JSON: {e}",
                path.display()
            ))
        })?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .ok_or_else(|| Error::Input(format!("case file {} has no name", path.display())))?;
        Ok(Case {
            name,
            source: CaseSource::File {
                path,
                sha256: sha256_hex(&bytes),
                bytes,
                json,
            },
        })
    }

    /// A scene given as JSON text in memory (a library caller's scene, e.g. a Python dict),
    /// named `name`: recorded like a file case (`case` = name, `scene_sha256` = sha256 of the
    /// bytes); errors name the case by `name`. Text that is not JSON is an input error.
    pub fn from_json_bytes(name: &str, bytes: Vec<u8>) -> Result<Case, Error> {
        if name.is_empty() {
            return Err(Error::Input("case: empty name".into()));
        }
        let json: serde_json::Value = serde_json::from_slice(&bytes)
            .map_err(|e| Error::Input(format!("case {name} is not valid JSON: {e}")))?;
        Ok(Case {
            name: name.to_string(),
            source: CaseSource::File {
                path: PathBuf::from(name),
                sha256: sha256_hex(&bytes),
                bytes,
                json,
            },
        })
    }

    /// A built-in test problem by its name (without the prefix).
    pub(crate) fn builtin(name: &str) -> Result<Case, Error> {
        if !BUILTIN_NAMES.contains(&name) {
            let known = if BUILTIN_NAMES.is_empty() {
                "none in this build".to_string()
            } else {
                BUILTIN_NAMES.join(", ")
            };
            return Err(Error::Input(format!(
                "unknown built-in case '{BUILTIN_PREFIX}{name}' (known: {known})"
            )));
        }
        Ok(Case {
            name: format!("{BUILTIN_PREFIX}{name}"),
            source: CaseSource::BuiltIn(name.to_string()),
        })
    }

    /// A press case of the paper (its scene built in code), named by its file stem.
    pub(crate) fn press(case: PressCase) -> Case {
        Case {
            name: case.to_string(),
            source: CaseSource::Press(case),
        }
    }

    /// The scene's sha256 (hex), None for built-ins and catalogue scenes.
    pub(crate) fn sha256(&self) -> Option<&str> {
        match &self.source {
            CaseSource::File { sha256, .. } => Some(sha256),
            CaseSource::BuiltIn(_) | CaseSource::Press(_) => None,
        }
    }
}

/// Lower-case hex sha256 of `bytes` (FIPS 180-4).
pub(crate) fn sha256_hex(bytes: &[u8]) -> String {
    let digest = Sha256::digest(bytes);
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_matches_fips_test_vector() {
        // FIPS 180-4 example "abc".
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn file_case_has_stem_and_hash() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("dry_150rpm_c0.1.json");
        std::fs::write(&p, b"{\"a\": 1}").unwrap();
        let c = Case::load("dry_150rpm_c0.1.json", Some(d.path())).unwrap();
        assert_eq!(c.name, "dry_150rpm_c0.1");
        assert_eq!(c.sha256(), Some(sha256_hex(b"{\"a\": 1}").as_str()));
        let abs = Case::load(p.to_str().unwrap(), None).unwrap();
        assert_eq!(abs, c);
    }

    #[test]
    fn a_case_from_memory_is_a_file_case_of_that_name() {
        let c = Case::from_json_bytes("mine", b"{\"a\": 1}".to_vec()).unwrap();
        assert_eq!(c.name, "mine");
        assert_eq!(c.sha256(), Some(sha256_hex(b"{\"a\": 1}").as_str()));
        let e = Case::from_json_bytes("mine", b"{oops".to_vec()).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput);
        assert!(
            e.to_string().starts_with("case mine is not valid JSON"),
            "{e}"
        );
        assert!(Case::from_json_bytes("", b"{}".to_vec()).is_err());
    }

    #[test]
    fn missing_and_invalid_cases_are_input_errors() {
        let d = tempfile::tempdir().unwrap();
        let e = Case::load("nope.json", Some(d.path())).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput);
        assert!(e.to_string().contains("nope.json not found"), "{e}");
        std::fs::write(d.path().join("bad.json"), b"{oops").unwrap();
        let e = Case::load("bad.json", Some(d.path())).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput);
        assert!(e.to_string().contains("not valid JSON"), "{e}");
        assert!(!e.to_string().contains('\n'));
        let e = Case::load("testset:nosuch", None).unwrap_err();
        assert!(e
            .to_string()
            .starts_with("unknown built-in case 'testset:nosuch'"));
        assert!(Case::load("", None).is_err());
    }

    #[test]
    fn press_cases_are_named_like_their_files_and_have_no_hash() {
        let c = Case::press(PressCase::dry(150, 100));
        assert_eq!(c.name, "dry_150rpm_c0.1");
        assert_eq!(c.sha256(), None);
        // The generator writes cases/press/NAME.json: the same stem.
        let file = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/press")
            .join(format!("{}.json", c.name));
        assert!(file.is_file(), "{}", file.display());
    }
}
