//! Citations that point into the docs exist: every `docs/model.md §N` (or `model.md §N.M`,
//! ranges `§5–§7` and lists `§2, §4`) names a section of docs/model.md, and every BENCHMARKS.md
//! section cited by its title (`BENCHMARKS.md, "Extremes"`, `BENCHMARKS.md ("Results")`,
//! nested `"Extremes" → "What the matrix found"`) or by its letter (`BENCHMARKS.md (g)`) names
//! a heading of BENCHMARKS.md — in every .rs, .md and .py file of the repository (target/, .git/
//! and other hidden folders left out, and this file, whose code spells the forms it parses).
//!
//! A title matches a heading when it is the heading's text, or the heading's text up to its
//! first parenthetical qualifier (`## Results (targets -- …)` is cited as "Results").

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("the repository root")
}

/// The .rs, .md and .py files under `dir`, skipping target/ and hidden folders.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            if name == "target" || name.starts_with('.') || name == "__pycache__" {
                continue;
            }
            sources(&p, out);
        } else if [".rs", ".md", ".py"].iter().any(|x| name.ends_with(x)) {
            out.push(p);
        }
    }
}

/// The text of a file with comment markers and line breaks folded away, so that a citation
/// that wraps from one comment line to the next reads as one.
fn flattened(text: &str) -> String {
    text.lines()
        .map(|l| {
            let t = l.trim_start();
            let t = ["//!", "///", "//", "#"]
                .iter()
                .find_map(|m| t.strip_prefix(m))
                .unwrap_or(t);
            t.trim()
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// A heading of a markdown file: its level (number of `#`) and its text.
fn headings(md: &str) -> Vec<(usize, String)> {
    let mut in_code = false;
    let mut out = Vec::new();
    for l in md.lines() {
        if l.starts_with("```") {
            in_code = !in_code;
        }
        if in_code {
            continue;
        }
        let level = l.chars().take_while(|c| *c == '#').count();
        if level > 0 && l[level..].starts_with(' ') {
            out.push((level, l[level..].trim().to_string()));
        }
    }
    out
}

/// docs/model.md's section numbers: `## 4. Title` → "4", `### 3.1 Title` → "3.1".
fn model_sections(md: &str) -> Vec<String> {
    headings(md)
        .into_iter()
        .filter(|(level, _)| *level >= 2)
        .filter_map(|(_, h)| {
            let num: String = h
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            let num = num.trim_end_matches('.').to_string();
            (!num.is_empty()).then_some(num)
        })
        .collect()
}

/// The § numbers cited after each `model.md` in `text` (ranges give both ends).
fn model_citations(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(at) = rest.find("model.md") {
        rest = &rest[at + "model.md".len()..];
        // Up to a few characters of punctuation before the first §.
        let lead: String = rest.chars().take_while(|c| " ,(".contains(*c)).collect();
        let mut s = &rest[lead.len()..];
        // §N, §N.M, joined by "–", "-", ", ", " and ".
        while let Some(after) = s.strip_prefix('§') {
            let num: String = after
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            let num = num.trim_end_matches('.');
            if num.is_empty() {
                break;
            }
            out.push(num.to_string());
            s = &after[num.len()..];
            let sep = ["–", "-", ", ", " and ", ",§"]
                .iter()
                .find(|sep| s.starts_with(**sep) && s[sep.len()..].starts_with('§'));
            match sep {
                Some(sep) => s = &s[sep.len()..],
                None => break,
            }
        }
    }
    out
}

/// The BENCHMARKS.md sections cited in `text`: each a path of titles (outer first), or a
/// letter `(g)`.
fn benchmark_citations(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(at) = rest.find("BENCHMARKS.md") {
        rest = &rest[at + "BENCHMARKS.md".len()..];
        let lead: String = rest.chars().take_while(|c| " ,(".contains(*c)).collect();
        let s = &rest[lead.len()..];
        if let Some(q) = s.strip_prefix('"') {
            let mut path = Vec::new();
            let mut s = q;
            while let Some(end) = s.find('"') {
                path.push(s[..end].to_string());
                s = &s[end + 1..];
                match s.strip_prefix(" → \"") {
                    Some(next) => s = next,
                    None => break,
                }
            }
            out.push(path);
        } else if lead.contains('(') || lead.ends_with(", ") {
            // A letter: BENCHMARKS.md (g), BENCHMARKS.md, (d).
            let s = s.strip_prefix('(').unwrap_or(s);
            let mut cs = s.chars();
            if let (Some(c), Some(')')) = (cs.next(), cs.next()) {
                if c.is_ascii_lowercase() {
                    out.push(vec![format!("({c})")]);
                }
            }
        }
    }
    out
}

/// Whether `cited` names `heading` (module doc).
fn names(cited: &str, heading: &str) -> bool {
    heading == cited || heading.split(" (").next() == Some(cited)
}

/// The index of the heading `cited` names among `hs[from..]` at any level deeper than
/// `parent` (None: anywhere), stopping at the parent's next sibling.
fn find(hs: &[(usize, String)], cited: &str, from: usize, parent: Option<usize>) -> Option<usize> {
    for (i, (level, h)) in hs.iter().enumerate().skip(from) {
        if let Some(p) = parent {
            if *level <= p {
                return None;
            }
        }
        let letter = cited.len() == 3 && cited.starts_with('(') && h.starts_with(cited);
        if names(cited, h) || letter {
            return Some(i);
        }
    }
    None
}

#[test]
fn every_cited_model_section_and_benchmark_section_exists() {
    let root = root();
    let model = std::fs::read_to_string(root.join("docs/model.md")).unwrap();
    let sections = model_sections(&model);
    let benchmarks = std::fs::read_to_string(root.join("BENCHMARKS.md")).unwrap();
    let hs = headings(&benchmarks);
    let mut files = Vec::new();
    sources(&root, &mut files);
    assert!(files.len() > 100, "{} files", files.len());
    let (mut n_model, mut n_bench) = (0, 0);
    let mut missing = Vec::new();
    // This file holds the citation forms as code, to parse them.
    let me = Path::new(file!()).file_name().unwrap();
    for f in files.iter().filter(|f| f.file_name() != Some(me)) {
        let text = flattened(&std::fs::read_to_string(f).unwrap());
        let rel = f.strip_prefix(&root).unwrap().display().to_string();
        for s in model_citations(&text) {
            n_model += 1;
            if !sections.contains(&s) {
                missing.push(format!("{rel}: docs/model.md §{s}"));
            }
        }
        for path in benchmark_citations(&text) {
            n_bench += 1;
            let mut at: Option<(usize, usize)> = None;
            for t in &path {
                let found = match at {
                    None => find(&hs, t, 0, None),
                    Some((i, level)) => find(&hs, t, i + 1, Some(level)),
                };
                match found {
                    Some(i) => at = Some((i, hs[i].0)),
                    None => {
                        missing.push(format!("{rel}: BENCHMARKS.md {path:?}"));
                        break;
                    }
                }
            }
        }
    }
    assert!(
        missing.is_empty(),
        "cited but absent:\n{}",
        missing.join("\n")
    );
    // The scan finds the citations there are (a parser that found none would pass).
    assert!(
        n_model > 50 && n_bench > 20,
        "{n_model} model, {n_bench} BENCHMARKS citations"
    );
}

#[test]
fn the_parsers_read_each_form_and_reject_an_absent_section() {
    assert_eq!(
        model_citations("(docs/model.md §5–§7, §9; x) and model.md §1.8."),
        ["5", "7", "9", "1.8"]
    );
    assert_eq!(model_citations("docs/model.md, §2 and §4"), ["2", "4"]);
    assert_eq!(
        benchmark_citations(
            r#"(BENCHMARKS.md, "Extremes" → "What the matrix found"), BENCHMARKS.md ("Results"), BENCHMARKS.md (g)"#
        ),
        [
            vec!["Extremes".to_string(), "What the matrix found".into()],
            vec!["Results".into()],
            vec!["(g)".into()]
        ]
    );
    let md = "# B\n## Results (how)\n### (g) Close\n## Extremes\n### What the matrix found\n## Other\n### Inner\n```\n## not a heading\n```\n";
    let hs = headings(md);
    assert_eq!(hs.len(), 7);
    assert_eq!(find(&hs, "Results", 0, None), Some(1));
    assert_eq!(find(&hs, "(g)", 0, None), Some(2));
    assert_eq!(find(&hs, "Extreme", 0, None), None);
    assert_eq!(find(&hs, "What the matrix found", 4, Some(2)), Some(4));
    // A subsection of another section is not the cited one's.
    assert_eq!(find(&hs, "Inner", 4, Some(2)), None);
    assert_eq!(find(&hs, "not a heading", 0, None), None);
    assert_eq!(
        model_sections("## 4. Film\n### 3.1 Normal\n## Intro\n"),
        ["4", "3.1"]
    );
}
