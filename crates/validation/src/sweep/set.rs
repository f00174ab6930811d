//! Sweeps of any scene field: the `"set": {PATH: [values…]}` of a sweep file, its paths in the
//! notation scene errors print, and a point's values laid over the base scene.
//!
//! ```text
//! PATH    = SEGMENT ("." SEGMENT)*,   SEGMENT = KEY ("[" INDEX "]")*
//! INDEX   = a whole number (the array's element)  |  a name (the element whose "name" is it)
//! e.g.    joints[3].friction.mu,  forces[0].stall_torque,  bodies[2].mass,
//!         joints[coupler_rocker].friction.mu
//! apply   the base scene as JSON (every field, defaults written out) → the field at PATH
//!         replaced by the value → parsed and validated as a scene file is; a path that does
//!         not reach an existing field, or a value the scene rejects, is an input error
//!         naming the path
//! ```
//!
//! Source: docs/outputs.md ("Sweeps": `set`); docs/scene-format.md (the error paths).

use std::collections::BTreeMap;

use lash_model::Scene;
use serde_json::Value;

use crate::error::Error;

/// One step of a path: an object key, an array index, or an array element by its name.
#[derive(Clone, Debug, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
    Name(String),
}

/// Parses a PATH of the module doc; an error says what is wrong with it.
fn parse_path(path: &str) -> Result<Vec<Step>, String> {
    if path.is_empty() {
        return Err("an empty path".into());
    }
    let mut steps = Vec::new();
    for seg in path.split('.') {
        let (key, mut rest) = match seg.find('[') {
            Some(i) => (&seg[..i], &seg[i..]),
            None => (seg, ""),
        };
        if key.is_empty() {
            return Err(format!("'{seg}' has no field name"));
        }
        steps.push(Step::Key(key.to_string()));
        while !rest.is_empty() {
            let Some(end) = rest.find(']').filter(|_| rest.starts_with('[')) else {
                return Err(format!("'{seg}': expected [INDEX] or [NAME]"));
            };
            let inner = &rest[1..end];
            if inner.is_empty() {
                return Err(format!("'{seg}': an empty []"));
            }
            steps.push(match inner.parse::<usize>() {
                Ok(i) => Step::Index(i),
                Err(_) => Step::Name(inner.to_string()),
            });
            rest = &rest[end + 1..];
        }
    }
    Ok(steps)
}

/// The field at `path` in `v` (mutable), or why there is none.
fn field<'a>(v: &'a mut Value, path: &str) -> Result<&'a mut Value, String> {
    let steps = parse_path(path)?;
    let mut cur = v;
    let mut at = String::new();
    for s in &steps {
        cur = match s {
            Step::Key(k) => {
                let here = if at.is_empty() {
                    k.clone()
                } else {
                    format!("{at}.{k}")
                };
                let Value::Object(m) = cur else {
                    return Err(format!("{at} is not an object"));
                };
                let keys: Vec<String> = m.keys().cloned().collect();
                at = here;
                m.get_mut(k)
                    .ok_or_else(|| format!("no field '{k}' (the scene has {})", keys.join(", ")))?
            }
            Step::Index(i) => {
                let Value::Array(a) = cur else {
                    return Err(format!("{at} is not a list"));
                };
                let n = a.len();
                at = format!("{at}[{i}]");
                a.get_mut(*i)
                    .ok_or_else(|| format!("{at}: the list has {n} element(s)"))?
            }
            Step::Name(name) => {
                let Value::Array(a) = cur else {
                    return Err(format!("{at} is not a list"));
                };
                let list = at.clone();
                at = format!("{at}[{name}]");
                a.iter_mut()
                    .find(|e| e.get("name").and_then(Value::as_str) == Some(name))
                    .ok_or_else(|| format!("{list} has no element named '{name}'"))?
            }
        };
    }
    Ok(cur)
}

/// Checks that `path` is well-formed (module doc), saying what is wrong with it if not.
pub(crate) fn check_path(path: &str) -> Result<(), String> {
    parse_path(path).map(|_| ())
}

/// Checks the `set` lists of a sweep file: each path well-formed, each list non-empty, no
/// value twice; the first failure names its key.
pub(crate) fn check_set(set: &BTreeMap<String, Vec<Value>>) -> Result<(), Error> {
    let bad = |m: String| Err(Error::Input(format!("sweep: {m}")));
    for (path, values) in set {
        if let Err(e) = parse_path(path) {
            return bad(format!("set['{path}']: {e}"));
        }
        if values.is_empty() {
            return bad(format!("set['{path}'] is an empty list"));
        }
        for (i, v) in values.iter().enumerate() {
            if values[..i].contains(v) {
                return bad(format!("set['{path}'] lists {v} twice"));
            }
        }
    }
    Ok(())
}

/// The scene with the values of `set` laid over it (module doc); `point` names the point in
/// errors ("point 3 (ID)").
pub(crate) fn apply_set(
    scene: &Scene,
    set: &BTreeMap<String, Value>,
    point: &str,
) -> Result<Scene, Error> {
    if set.is_empty() {
        return Ok(scene.clone());
    }
    let mut v = serde_json::to_value(scene)
        .map_err(|e| Error::Internal(format!("sweep: the base scene as JSON: {e}")))?;
    for (path, value) in set {
        let f = field(&mut v, path)
            .map_err(|e| Error::Input(format!("sweep: set['{path}'] ({point}): {e}")))?;
        *f = value.clone();
    }
    let text = v.to_string();
    let s = Scene::from_json_str(&text).map_err(|e| {
        let which: Vec<String> = set.iter().map(|(p, x)| format!("{p} = {x}")).collect();
        Error::Input(format!(
            "sweep: {point} ({}): the scene rejects it: {e}",
            which.join(", ")
        ))
    })?;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_read_as_scene_errors_print_them() {
        assert_eq!(
            parse_path("joints[3].friction.mu").unwrap(),
            vec![
                Step::Key("joints".into()),
                Step::Index(3),
                Step::Key("friction".into()),
                Step::Key("mu".into())
            ]
        );
        assert_eq!(
            parse_path("joints[coupler_rocker].friction.mu").unwrap()[1],
            Step::Name("coupler_rocker".into())
        );
        for bad in ["", "a..b", "a[", "a[]", ".a", "a[1]x"] {
            assert!(parse_path(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_field_is_found_by_index_or_name_or_said_missing() {
        let mut v: Value = serde_json::json!({
            "joints": [{"name": "a", "k": 1}, {"name": "b", "friction": {"mu": 0.1}}]
        });
        *field(&mut v, "joints[b].friction.mu").unwrap() = serde_json::json!(0.3);
        assert_eq!(v["joints"][1]["friction"]["mu"], 0.3);
        *field(&mut v, "joints[0].k").unwrap() = serde_json::json!(2);
        assert_eq!(v["joints"][0]["k"], 2);
        let e = field(&mut v, "joints[c].k").unwrap_err();
        assert!(e.contains("joints has no element named 'c'"), "{e}");
        let e = field(&mut v, "joints[5].k").unwrap_err();
        assert!(e.contains("joints[5]: the list has 2 element(s)"), "{e}");
        let e = field(&mut v, "joints[0].mu").unwrap_err();
        assert!(e.contains("no field 'mu'"), "{e}");
        let e = field(&mut v, "bodies").unwrap_err();
        assert!(e.contains("no field 'bodies'"), "{e}");
    }
}
