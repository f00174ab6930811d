//! Deserialisation helpers: structs only as objects, and internally tagged enums that keep
//! the JSON path of an error inside a variant.

use std::fmt;

use serde::de::{DeserializeOwned, Error as _};
use serde::{Deserialize, Deserializer, Serialize};

/// An empty object (the `none` friction law has no data).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoData {}

// ---------------------------------------------------------------------------------------------
// Structs only as objects.
//
// serde's derive also reads a struct from an array of its fields in order (`"baumgarte": [5, 5]`,
// a body as `["crank", 1.0, 0.1]`). The format has no such form: these read a struct through
// `deserialize_map`, so an array is "invalid type: sequence, expected an object" at its own path
// (the map access passed on is serde_path_to_error's, so deeper paths are kept).
// ---------------------------------------------------------------------------------------------

struct Obj<T>(T);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Obj<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for V<T> {
            type Value = T;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an object")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
                T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
            }
        }
        d.deserialize_map(V(std::marker::PhantomData)).map(Obj)
    }
}

pub(crate) fn object<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<T, D::Error> {
    Obj::deserialize(d).map(|o| o.0)
}

pub(crate) fn object_opt<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> Result<Option<T>, D::Error> {
    Option::<Obj<T>>::deserialize(d).map(|o| o.map(|o| o.0))
}

pub(crate) fn objects<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> Result<Vec<T>, D::Error> {
    Vec::<Obj<T>>::deserialize(d).map(|v| v.into_iter().map(|o| o.0).collect())
}

// ---------------------------------------------------------------------------------------------
// Internally tagged enums with full error paths.
//
// serde's derive for internally tagged enums buffers the object, so errors inside a variant lose
// their path. These impls read the object as a JSON value, dispatch on the tag, and deserialize
// the variant struct with path tracking; the inner path travels in the error message between
// PATH_MARK characters and `SceneError` joins it to the outer path.
// ---------------------------------------------------------------------------------------------

pub(crate) const PATH_MARK: char = '\u{1}';

pub(crate) fn variant<'de, D: Deserializer<'de>, T: DeserializeOwned>(
    mut obj: serde_json::Map<String, serde_json::Value>,
    tag: &str,
) -> Result<T, D::Error> {
    obj.remove(tag);
    serde_path_to_error::deserialize(serde_json::Value::Object(obj)).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        // Nested marks (a tagged enum inside a variant) carry a deeper path: join them.
        let (path, inner) = match split_marked(&inner) {
            Some((p, m)) if path == "." => (p.to_string(), m.to_string()),
            Some((p, m)) => (format!("{path}.{p}"), m.to_string()),
            None => (path, inner),
        };
        if path == "." {
            // At the variant object itself (a missing field): the outer path says where.
            D::Error::custom(inner)
        } else {
            D::Error::custom(format!("{PATH_MARK}{path}{PATH_MARK}{inner}"))
        }
    })
}

pub(crate) fn split_marked(msg: &str) -> Option<(&str, &str)> {
    let rest = msg.strip_prefix(PATH_MARK)?;
    let end = rest.find(PATH_MARK)?;
    Some((&rest[..end], &rest[end + 1..]))
}

pub(crate) fn tagged_object<'de, D: Deserializer<'de>>(
    d: D,
    tag: &str,
) -> Result<(String, serde_json::Map<String, serde_json::Value>), D::Error> {
    let v = serde_json::Value::deserialize(d)?;
    let serde_json::Value::Object(obj) = v else {
        return Err(D::Error::custom(format!(
            "expected an object with a \"{tag}\" field"
        )));
    };
    let tag_value = match obj.get(tag) {
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(_) => {
            return Err(D::Error::custom(format!(
                "{PATH_MARK}{tag}{PATH_MARK}must be a string"
            )))
        }
        None => return Err(D::Error::custom(format!("missing field `{tag}`"))),
    };
    Ok((tag_value, obj))
}
