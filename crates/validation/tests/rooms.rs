//! The workspace's rooms keep their shape (ARCHITECTURE.md, "Invariants"): in the `src` of every
//! member (crates/solver, model, validation, cli and python) no production file is over 1 000
//! lines and no source file imports one that imports it back, and crates/validation/src declares at most 150 `pub`
//! items (everything else is `pub(crate)`: the door is lib.rs).
//!
//! ```text
//! production part  the lines of a file before the #[cfg(test)] that opens its test module;
//!                  files of modules declared under #[cfg(test)] are tests, not production
//! pub item         a production line that starts with `pub ` and declares an item (fn,
//!                  struct, enum, const, static, type, trait, mod, union) or re-exports
//!                  (`pub use`, one statement counted once); fields and variants are not items
//! import           a path `crate::a::b…` (use groups `{…}` followed), `super::…`, or a path
//!                  through a child module, in the production part (comments left out),
//!                  resolved to the file of the longest module prefix; a circle is a strongly
//!                  connected set of two or more files
//! ```

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path (segments below the crate root) → file.
type Files = BTreeMap<Vec<String>, PathBuf>;

/// The `src` folder of a workspace member, `dir` relative to the workspace root.
fn member_src(dir: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(dir)
        .join("src")
}

fn crate_src(name: &str) -> PathBuf {
    member_src(&format!("crates/{name}"))
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            walk(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module path of a file below `src` (lib.rs → the root; a/mod.rs → a; a binary's
/// main.rs keeps its name, a root of its own).
fn module_of(src: &Path, f: &Path) -> Vec<String> {
    let rel = f.strip_prefix(src).unwrap().with_extension("");
    let mut segs: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(segs.last().map(String::as_str), Some("lib" | "mod")) {
        segs.pop();
    }
    segs
}

fn is_module_line(l: &str) -> Option<String> {
    let t = l.trim();
    let t = t
        .strip_prefix("pub(crate) ")
        .or_else(|| t.strip_prefix("pub "))
        .unwrap_or(t);
    let name = t.strip_prefix("mod ")?;
    Some(name.trim_end_matches([';', '{', ' ']).to_string())
}

/// The production part of a file (module doc).
fn production(text: &str) -> Vec<&str> {
    let lines: Vec<&str> = text.lines().collect();
    for (i, l) in lines.iter().enumerate() {
        if l.trim() == "#[cfg(test)]" {
            let next = lines[i + 1..]
                .iter()
                .find(|x| !x.trim().starts_with("#["))
                .copied()
                .unwrap_or("");
            if is_module_line(next).is_some() {
                return lines[..i].to_vec();
            }
        }
    }
    lines
}

/// The crate's source files that are not tests, by module path.
fn files(src: &Path) -> Files {
    let mut all = Vec::new();
    walk(src, &mut all);
    let by_module: Files = all.iter().map(|f| (module_of(src, f), f.clone())).collect();
    // Modules declared under #[cfg(test)], with everything below them.
    let mut tests: Vec<Vec<String>> = Vec::new();
    for (m, f) in &by_module {
        let text = std::fs::read_to_string(f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            if l.trim() == "#[cfg(test)]" {
                if let Some(name) = lines.get(i + 1).and_then(|n| is_module_line(n)) {
                    if lines[i + 1].trim_end().ends_with(';') {
                        let mut child = m.clone();
                        child.push(name);
                        tests.push(child);
                    }
                }
            }
        }
    }
    by_module
        .into_iter()
        .filter(|(m, _)| !tests.iter().any(|t| m.starts_with(t)))
        .collect()
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The paths of a use tree starting at `s` (after `crate::`): `a::b::{c::D, e}` → [a, b, c,
/// D], [a, b, e]; the returned paths are as long as written.
fn use_tree(s: &str) -> Vec<Vec<String>> {
    fn tree(s: &[char], i: &mut usize, prefix: &[String], out: &mut Vec<Vec<String>>) {
        let mut path = prefix.to_vec();
        loop {
            if s.get(*i) == Some(&'{') {
                *i += 1;
                loop {
                    while s.get(*i).is_some_and(|c| c.is_whitespace() || *c == ',') {
                        *i += 1;
                    }
                    match s.get(*i) {
                        None => return,
                        Some('}') => {
                            *i += 1;
                            return;
                        }
                        _ => tree(s, i, &path, out),
                    }
                }
            }
            let start = *i;
            while s.get(*i).copied().is_some_and(is_ident) {
                *i += 1;
            }
            if *i == start {
                out.push(path);
                return;
            }
            let seg: String = s[start..*i].iter().collect();
            if seg != "self" {
                path.push(seg);
            }
            if s.get(*i) == Some(&':') && s.get(*i + 1) == Some(&':') {
                *i += 2;
            } else {
                // ` as X`, `;`, `,`, `}` …: the path ends; skip an alias.
                let rest: String = s[*i..].iter().take(4).collect();
                if rest.starts_with(" as ") {
                    *i += 4;
                    while s.get(*i).copied().is_some_and(is_ident) {
                        *i += 1;
                    }
                }
                out.push(path);
                return;
            }
        }
    }
    let chars: Vec<char> = s.chars().collect();
    let mut out = Vec::new();
    tree(&chars, &mut 0, &[], &mut out);
    out
}

/// The import graph of `files` (module doc).
fn imports(files: &Files) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let resolve = |p: &[String]| -> Vec<String> {
        (0..=p.len())
            .rev()
            .map(|k| p[..k].to_vec())
            .find(|m| files.contains_key(m))
            .unwrap_or_default()
    };
    let mut edges = BTreeMap::new();
    for (m, f) in files {
        let text: String = production(&std::fs::read_to_string(f).unwrap())
            .iter()
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        let mut to = BTreeSet::new();
        let mut add = |path: Vec<String>| {
            let target = resolve(&path);
            if &target != m {
                to.insert(target);
            }
        };
        let base_of_super = m[..m.len().saturating_sub(1)].to_vec();
        for (marker, base) in [("crate::", Vec::new()), ("super::", base_of_super)] {
            let mut rest = text.as_str();
            while let Some(at) = rest.find(marker) {
                let before = rest[..at].chars().last();
                rest = &rest[at + marker.len()..];
                if before.is_some_and(|c| is_ident(c) || c == ':') {
                    continue;
                }
                for p in use_tree(rest) {
                    add(base.iter().cloned().chain(p).collect());
                }
                if rest.starts_with('*') {
                    add(base.clone());
                }
            }
        }
        // lib.rs's re-exports (`pub use room::…`) are imports of the rooms.
        if m.is_empty() {
            for l in text.split("pub use ").skip(1) {
                for p in use_tree(l) {
                    add(p);
                }
            }
        }
        // Paths through a child module: `child::…`.
        for child in files
            .keys()
            .filter(|k| k.len() == m.len() + 1 && k.starts_with(m))
        {
            let name = format!("{}::", child.last().unwrap());
            let mut rest = text.as_str();
            while let Some(at) = rest.find(&name) {
                let before = rest[..at].chars().last();
                rest = &rest[at + name.len()..];
                if !before.is_some_and(|c| is_ident(c) || c == ':') {
                    add(child.clone());
                }
            }
        }
        edges.insert(m.clone(), to);
    }
    edges
}

/// The strongly connected sets of two or more files (Tarjan).
fn circles(edges: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<Vec<Vec<String>>> {
    struct T<'a> {
        edges: &'a BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        index: BTreeMap<&'a Vec<String>, usize>,
        low: BTreeMap<&'a Vec<String>, usize>,
        stack: Vec<&'a Vec<String>>,
        out: Vec<Vec<Vec<String>>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a Vec<String>) {
        let n = t.index.len();
        t.index.insert(v, n);
        t.low.insert(v, n);
        t.stack.push(v);
        for w in &t.edges[v] {
            if !t.index.contains_key(w) {
                visit(t, w);
                let lw = t.low[w];
                let lv = t.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if t.stack.contains(&w) {
                let iw = t.index[w];
                let lv = t.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            loop {
                let w = t.stack.pop().unwrap();
                comp.push(w.clone());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !t.index.contains_key(v) {
            visit(&mut t, v);
        }
    }
    t.out
}

fn pub_items(lines: &[&str]) -> usize {
    const KINDS: [&str; 12] = [
        "fn ",
        "struct ",
        "enum ",
        "const ",
        "static ",
        "type ",
        "trait ",
        "mod ",
        "use ",
        "union ",
        "async fn ",
        "unsafe fn ",
    ];
    lines
        .iter()
        .filter_map(|l| l.trim_start().strip_prefix("pub "))
        .filter(|rest| KINDS.iter().any(|k| rest.starts_with(k)))
        .count()
}

#[test]
fn no_production_file_over_1000_lines_and_no_import_circle() {
    let mut broken = Vec::new();
    for krate in [
        "crates/solver",
        "crates/model",
        "crates/validation",
        "crates/cli",
        "python",
    ] {
        let src = member_src(krate);
        let files = files(&src);
        assert!(files.len() >= 7, "{krate}: {} files", files.len());
        for f in files.values() {
            let n = production(&std::fs::read_to_string(f).unwrap()).len();
            if n > 1000 {
                broken.push(format!("{}: {n} production lines", f.display()));
            }
        }
        let edges = imports(&files);
        for c in circles(&edges) {
            broken.push(format!("{krate}: import circle {c:?}"));
        }
    }
    assert!(broken.is_empty(), "{}", broken.join("\n"));
}

#[test]
fn the_engine_declares_at_most_150_pub_items() {
    let files = files(&crate_src("validation"));
    let n: usize = files
        .values()
        .map(|f| pub_items(&production(&std::fs::read_to_string(f).unwrap())))
        .sum();
    // The commands, their options and results, Error and Progress are most of them.
    assert!((80..=150).contains(&n), "{n} pub items");
}

#[test]
fn the_measures_see_what_they_measure() {
    // Use trees, aliases, self and globs.
    assert_eq!(
        use_tree("a::{b::{C, D as E}, self, f::G};"),
        [
            vec!["a", "b", "C"],
            vec!["a", "b", "D"],
            vec!["a"],
            vec!["a", "f", "G"]
        ]
    );
    assert_eq!(
        use_tree("run::prepare::Prepared;"),
        [vec!["run", "prepare", "Prepared"]]
    );
    // A circle of two files and one of three are found; a chain is not a circle.
    let m = |s: &str| -> Vec<String> { s.split("::").map(String::from).collect() };
    let mut e = BTreeMap::new();
    for (a, bs) in [
        ("a", vec!["b"]),
        ("b", vec!["a", "c"]),
        ("c", vec!["d"]),
        ("d", vec!["e"]),
        ("e", vec!["c"]),
        ("f", vec!["a"]),
    ] {
        e.insert(m(a), bs.into_iter().map(m).collect::<BTreeSet<_>>());
    }
    let mut c: Vec<usize> = circles(&e).iter().map(Vec::len).collect();
    c.sort();
    assert_eq!(c, [2, 3]);
    // The production part ends at the test module, not at an item-level #[cfg(test)].
    let text = "pub fn a() {}\n#[cfg(test)]\npub fn b() {}\n#[cfg(test)]\nmod tests {\n    pub fn c() {}\n}\n";
    assert_eq!(production(text).len(), 3);
    assert_eq!(pub_items(&production(text)), 2);
    assert_eq!(
        pub_items(&["pub(crate) fn x()", "    pub y: u8,", "pub use a::B;"]),
        1
    );
}
