//! Fuzz target: any bytes into `Scene::from_json_str`, and `Mechanism::from_scene` when it
//! parses. Nothing may panic, and every error names where (the property of
//! `crates/model/tests/scene_props.rs`, in its cheap form: a syntax error has a line, every
//! other error's message starts with its path).
#![no_main]

use lash_model::{Mechanism, Scene, SceneError};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let result = Scene::from_json_str(text).and_then(|s| Mechanism::from_scene(&s));
    match result {
        Ok(m) => {
            let y0 = m.initial_state();
            assert!(y0.iter().all(|v| v.is_finite()), "non-finite y0 {y0:?}");
            assert!(m.t_end() > m.t_start() && m.t_end().is_finite());
        }
        Err(SceneError::Syntax { line, .. }) => assert!(line >= 1),
        Err(
            ref e @ (SceneError::Schema { ref path, .. }
            | SceneError::Invalid { ref path, .. }
            | SceneError::Redundant { ref path, .. }
            | SceneError::Assembly { ref path, .. }
            | SceneError::Dynamics { ref path, .. }),
        ) => {
            assert!(!path.is_empty() || text.contains("\"\""), "{e:?}");
            assert!(e.to_string().starts_with(&format!("{path}: ")), "{e:?}");
        }
        Err(e) => panic!("not an error of parsing text: {e:?}"),
    }
});
