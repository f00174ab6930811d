//! Parsing a scene from JSON text: syntax first, duplicate keys, the typed pass with paths.

use std::fmt;
use std::path::Path;

use serde::de::Error as _;
use serde::Deserializer;

use crate::scene::de::{split_marked, PATH_MARK};
use crate::scene::error::SceneError;
use crate::scene::format::Scene;

// ---------------------------------------------------------------------------------------------
// Parsing
// ---------------------------------------------------------------------------------------------

impl Scene {
    /// Parses and validates a scene from JSON text.
    ///
    /// Text that is not JSON gets a [`SceneError::Syntax`] (its first syntax error), never a
    /// schema error about the part read before it; a missing field's path names the field.
    pub fn from_json_str(text: &str) -> Result<Scene, SceneError> {
        // Syntax first, on the whole text: the typed pass below stops at the first value of
        // the wrong type, which may come before a syntax error (`0x`, a truncated file).
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| syntax_error(&e))?;
        if !value.is_object() {
            return Err(SceneError::Schema {
                path: ".".into(),
                message: format!("expected a JSON object (the scene), got {}", kind(&value)),
            });
        }
        // A repeated key would silently keep one of its values (docs/scene-format.md).
        check_duplicate_keys(text)?;
        let de = &mut serde_json::Deserializer::from_str(text);
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|e| {
            let outer = e.path().to_string();
            let inner = e.into_inner();
            use serde_json::error::Category;
            match inner.classify() {
                // The text is JSON (checked above): serde_json reports an array longer than a
                // fixed-size field (`[1, 2, 3]` for [x, y]) as "trailing characters".
                Category::Syntax | Category::Eof => SceneError::Schema {
                    path: outer,
                    message: format!(
                        "{}: the array has more elements than the field takes",
                        strip_position(&inner.to_string())
                    ),
                },
                Category::Io => syntax_error(&inner),
                Category::Data => {
                    let msg = inner.to_string();
                    let (path, message) = match split_marked(&msg) {
                        // (The inner path starts with a key: a variant is an object.)
                        Some((p, m)) => (join_path(&outer, p), m.to_string()),
                        None => (outer, msg),
                    };
                    // serde reports a missing field at its object: name the field itself.
                    let path = match message
                        .strip_prefix("missing field `")
                        .and_then(|r| r.split_once('`'))
                    {
                        Some((field, _)) => join_path(&path, field),
                        None => path,
                    };
                    SceneError::Schema { path, message }
                }
            }
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Reads, parses and validates a scene file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let p = path.as_ref();
        let text = std::fs::read_to_string(p).map_err(|e| SceneError::Io {
            path: p.display().to_string(),
            message: e.to_string(),
        })?;
        Scene::from_json_str(&text)
    }

    /// The scene as pretty-printed JSON.
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(self).expect("a scene always serialises")
    }
}

/// The first key that an object of `text` repeats, as a [`SceneError::Schema`] at its path.
fn check_duplicate_keys(text: &str) -> Result<(), SceneError> {
    use serde::de::DeserializeSeed;
    let mut de = serde_json::Deserializer::from_str(text);
    NoDuplicates(".".into()).deserialize(&mut de).map_err(|e| {
        let msg = strip_position(&e.to_string());
        match split_marked(&msg) {
            Some((path, m)) => SceneError::Schema {
                path: path.to_string(),
                message: m.to_string(),
            },
            None => syntax_error(&e),
        }
    })
}

/// Walks a JSON document and fails at the first repeated key of an object.
struct NoDuplicates(String);

impl NoDuplicates {
    fn key(&self, k: &str) -> String {
        join_path(&self.0, k)
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for NoDuplicates {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for NoDuplicates {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }
    fn visit_u64<E>(self, _: u64) -> Result<(), E> {
        Ok(())
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let mut i = 0usize;
        while seq
            .next_element_seed(NoDuplicates(format!("{}[{i}]", self.0)))?
            .is_some()
        {
            i += 1;
        }
        Ok(())
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let mut seen = std::collections::HashSet::new();
        while let Some(k) = map.next_key::<String>()? {
            let path = self.key(&k);
            if !seen.insert(k.clone()) {
                return Err(A::Error::custom(format!(
                    "{PATH_MARK}{path}{PATH_MARK}duplicate key `{k}`: an object must not \
                     repeat a key"
                )));
            }
            map.next_value_seed(NoDuplicates(path))?;
        }
        Ok(())
    }
}

/// The JSON type of a value, for messages.
fn kind(v: &serde_json::Value) -> &'static str {
    match v {
        serde_json::Value::Null => "null",
        serde_json::Value::Bool(_) => "a boolean",
        serde_json::Value::Number(_) => "a number",
        serde_json::Value::String(_) => "a string",
        serde_json::Value::Array(_) => "an array",
        serde_json::Value::Object(_) => "an object",
    }
}

/// `outer.inner`; `.` (the root) on either side is left out.
fn join_path(outer: &str, inner: &str) -> String {
    if inner == "." {
        outer.to_string()
    } else if outer == "." {
        inner.to_string()
    } else {
        format!("{outer}.{inner}")
    }
}

fn syntax_error(e: &serde_json::Error) -> SceneError {
    SceneError::Syntax {
        line: e.line(),
        column: e.column(),
        message: strip_position(&e.to_string()),
    }
}

fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

#[cfg(test)]
mod tests {
    //! The tagged-kind table: its "expected one of" text, its `KINDS`, and that the tag a
    //! variant serialises with is the one it reads back.
    use crate::clearance::contact::{FrictionSpec, NormalSpec};
    use crate::elements::ForceElementSpec;
    use crate::scene::format::{JointSpec, Scene};

    fn error(joints: &str, forces: &str) -> String {
        let text = format!(
            r#"{{"bodies": [{{"name": "b", "mass": 1.0, "inertia": 1.0, "points": {{"p": [0, 0]}}}}],
                "joints": [{joints}], "forces": [{forces}], "t_end": 1.0}}"#
        );
        Scene::from_json_str(&text).unwrap_err().to_string()
    }

    #[test]
    fn an_unknown_tag_lists_every_kind_in_table_order() {
        let e = error(r#"{"type": "hinge", "name": "j"}"#, "");
        assert!(
            e.starts_with(
                "joints[0].type: unknown joint type `hinge`, expected one of `revolute`, \
                 `translational`, `driver`, `clearance`, `prismatic_clearance` at line"
            ),
            "{e}"
        );
        let e = error("", r#"{"type": "spring", "name": "s"}"#);
        let list: Vec<String> = ForceElementSpec::KINDS
            .iter()
            .map(|k| format!("`{k}`"))
            .collect();
        assert!(
            e.starts_with(&format!(
                "forces[0].type: unknown force element type `spring`, expected one of {}",
                list.join(", ")
            )),
            "{e}"
        );
        // A tagged kind inside a variant keeps its full path; with two kinds the list is
        // "`a` or `b`".
        let clearance = |friction: &str| {
            format!(
                r#"{{"type": "clearance", "name": "c",
                    "bearing": {{"body": "ground", "at": [0, 0], "radius": 0.01}},
                    "journal": {{"body": "b", "point": "p", "radius": 0.009}},
                    "normal": {{"law": "impact", "k": 1e9, "c_max": 0, "d_max": 1e-5}},
                    "friction": {friction}}}"#
            )
        };
        let e = error(&clearance(r#"{"law": "viscous"}"#), "");
        assert!(
            e.starts_with(
                "joints[0].friction.law: unknown friction law `viscous`, expected `none` or \
                 `coulomb` at line"
            ),
            "{e}"
        );
    }

    #[test]
    fn the_tables_list_their_kinds_and_each_tag_round_trips() {
        assert_eq!(
            JointSpec::KINDS,
            [
                "revolute",
                "translational",
                "driver",
                "clearance",
                "prismatic_clearance"
            ]
        );
        assert_eq!(
            NormalSpec::KINDS,
            ["impact", "lankarani_nikravesh", "flores", "hunt_crossley"]
        );
        assert_eq!(FrictionSpec::KINDS, ["none", "coulomb"]);
        for kind in ForceElementSpec::KINDS {
            assert!(!kind.is_empty());
        }
        // Serialised, a variant carries its tag; read back, the same variant.
        let f: FrictionSpec = serde_json::from_str(r#"{"law": "none"}"#).unwrap();
        assert_eq!(f, FrictionSpec::None);
        assert_eq!(f.type_name(), "none");
        assert_eq!(
            serde_json::to_value(&f).unwrap(),
            serde_json::json!({"law": "none"})
        );
        let n: NormalSpec =
            serde_json::from_str(r#"{"law": "flores", "k": 1e9, "restitution": 0.5}"#).unwrap();
        assert_eq!(n.type_name(), "flores");
        let back: NormalSpec = serde_json::from_value(serde_json::to_value(&n).unwrap()).unwrap();
        assert_eq!(back, n);
    }
}
