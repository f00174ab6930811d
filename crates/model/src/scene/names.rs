//! The scene's body index by name, kept beside its public fields.
//!
//! [`Scene::body_index`](crate::Scene::body_index) is called once per joint, element and output
//! that names a body, so a linear search made building an N-body chain O(N²). The scene's fields
//! are public (a sweep or a Python caller may rename or replace bodies at any time), so the index
//! is a cache that cannot answer with a stale index: a hit is returned only when the body at that
//! index still has that name (names are unique in a valid scene), and a miss
//! falls back to the linear search, rebuilding the index when that search finds the name. An
//! absent name therefore still costs one linear search, as before.

use std::collections::HashMap;
use std::sync::RwLock;

/// A cache of body name → index (module doc). It takes no part in a scene's equality, clone,
/// debug output or serialisation.
#[derive(Default)]
pub(crate) struct BodyNames(RwLock<HashMap<String, usize>>);

impl BodyNames {
    /// Index of the body named `name` among `len` bodies whose names `name_at` gives: the first
    /// such body (as a linear search) whenever names are unique, which validation requires.
    pub(crate) fn index<'a>(
        &self,
        name: &str,
        len: usize,
        name_at: impl Fn(usize) -> &'a str,
    ) -> Option<usize> {
        if let Ok(map) = self.0.read() {
            if let Some(&k) = map.get(name) {
                if k < len && name_at(k) == name {
                    return Some(k);
                }
            }
        }
        let k = (0..len).position(|i| name_at(i) == name)?;
        if let Ok(mut map) = self.0.write() {
            map.clear();
            for i in 0..len {
                map.entry(name_at(i).to_owned()).or_insert(i);
            }
        }
        Some(k)
    }
}

impl Clone for BodyNames {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl PartialEq for BodyNames {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for BodyNames {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("BodyNames")
    }
}

#[cfg(test)]
mod tests {
    use super::BodyNames;

    fn find(cache: &BodyNames, names: &[String], name: &str) -> Option<usize> {
        cache.index(name, names.len(), |k| names[k].as_str())
    }

    /// The cache answers as a linear search would, after the names are renamed, reordered,
    /// shortened or extended behind its back (the scene's fields are public).
    #[test]
    fn answers_as_a_linear_search_through_changes() {
        let cache = BodyNames::default();
        let mut names: Vec<String> = (0..50).map(|k| format!("link{k}")).collect();
        let check = |cache: &BodyNames, names: &[String]| {
            for probe in ["link0", "link7", "link49", "link50", "crank", ""] {
                let linear = names.iter().position(|n| n == probe);
                assert_eq!(find(cache, names, probe), linear, "{probe}");
            }
        };
        check(&cache, &names);
        names.swap(3, 7);
        names[10] = "crank".into();
        check(&cache, &names);
        names.truncate(5);
        check(&cache, &names);
        names.push("link50".into());
        names.insert(0, "link49".into());
        check(&cache, &names);
    }
}
