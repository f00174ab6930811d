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

/// The error of an unknown tag: "unknown WHAT `x`, expected one of `a`, `b`, …" (with two
/// kinds: "expected `a` or `b`"), at the tag's own path.
pub(crate) fn unknown_kind<'de, D: Deserializer<'de>>(
    tag: &str,
    what: &str,
    other: &str,
    kinds: &[&str],
) -> D::Error {
    let list: Vec<String> = kinds.iter().map(|k| format!("`{k}`")).collect();
    let expected = match list.as_slice() {
        [a, b] => format!("expected {a} or {b}"),
        _ => format!("expected one of {}", list.join(", ")),
    };
    D::Error::custom(format!(
        "{PATH_MARK}{tag}{PATH_MARK}unknown {what} `{other}`, {expected}"
    ))
}

/// The table of an internally tagged enum of the scene format: one line per kind emits the
/// variant (serialised with its tag), its entry in `KINDS` (the "expected one of" list, in
/// order), its arm of `type_name()` and of the `Deserialize` that keeps the JSON path of an
/// error inside the variant (module doc). With `named`, every variant holds a struct with a
/// `name` field and `name()` is emitted too.
///
/// ```text
/// tagged_kinds! {
///     /// doc
///     pub enum JointSpec named, tag "type", unknown "joint type" {
///         /// doc
///         "revolute" => Revolute(RevoluteSpec),
///         …
///     }
/// }
/// ```
/// A kind without data (`"none" => None`) reads an empty object ([`NoData`]). A line may
/// start with `@cfg(…)` (before its doc): the `#[cfg(…)]` of all that it emits.
macro_rules! tagged_kinds {
    (@variant $d:ident, $obj:ident, $tag:literal, $path:path, $ty:ty) => {
        $crate::scene::de::variant::<$d, $ty>($obj, $tag).map($path)
    };
    (@variant $d:ident, $obj:ident, $tag:literal, $path:path) => {
        $crate::scene::de::variant::<$d, $crate::scene::de::NoData>($obj, $tag).map(|_| $path)
    };
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident named, tag $tag:literal, unknown $what:literal {
            $(
                $(@cfg($cfg:meta))?
                $(#[$vmeta:meta])*
                $kind:literal => $variant:ident($ty:ty)
            ),+ $(,)?
        }
    ) => {
        $crate::scene::de::tagged_kinds! {
            $(#[$meta])*
            $vis enum $name, tag $tag, unknown $what {
                $( $(@cfg($cfg))? $(#[$vmeta])* $kind => $variant($ty) ),+
            }
        }
        impl $name {
            /// The name of the part (its `"name"` field).
            pub fn name(&self) -> &str {
                match self {
                    $( $(#[cfg($cfg)])? $name::$variant(s) => &s.name, )+
                }
            }
        }
    };
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident, tag $tag:literal, unknown $what:literal {
            $(
                $(@cfg($cfg:meta))?
                $(#[$vmeta:meta])*
                $kind:literal => $variant:ident $(($ty:ty))?
            ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug, PartialEq, serde::Serialize)]
        #[serde(tag = $tag)]
        $vis enum $name {
            $(
                $(#[cfg($cfg)])?
                $(#[$vmeta])*
                #[serde(rename = $kind)]
                $variant $(($ty))?,
            )+
        }
        impl $name {
            /// Every kind's tag, in the order of the variants.
            pub const KINDS: &'static [&'static str] = &[$( $(#[cfg($cfg)])? $kind ),+];

            /// The tag of this kind.
            pub fn type_name(&self) -> &'static str {
                match self {
                    $( $(#[cfg($cfg)])? $name::$variant { .. } => $kind, )+
                }
            }
        }
        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let (tag, obj) = $crate::scene::de::tagged_object::<D>(d, $tag)?;
                match tag.as_str() {
                    $(
                        $(#[cfg($cfg)])?
                        $kind => $crate::scene::de::tagged_kinds!(
                            @variant D, obj, $tag, $name::$variant $(, $ty)?
                        ),
                    )+
                    other => Err($crate::scene::de::unknown_kind::<D>(
                        $tag, $what, other, Self::KINDS,
                    )),
                }
            }
        }
    };
}
pub(crate) use tagged_kinds;
