//! The top-level modules of `src` form layers: each uses only modules
//! listed before it, in the order ARCHITECTURE.md's "The parts" gives.

use std::collections::BTreeSet;

/// Lowest first; `crate` is `lib.rs` and `main.rs`.
const ORDER: &[&str] = &[
    "source",
    "number",
    "codes",
    "block",
    "geom",
    "fx_hasher",
    "diag",
    "parse",
    "program",
    "emit",
    "settings",
    "rules",
    "eval",
    "library",
    "machine",
    "runtime",
    "controller",
    "config",
    "flatten",
    "view",
    "cli",
    "crate",
];

/// The module a source file belongs to.
fn module_of(rel: &std::path::Path) -> String {
    let first = rel
        .components()
        .next()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .unwrap_or_default();
    match first.strip_suffix(".rs") {
        Some("lib" | "main") => "crate".into(),
        Some(m) => m.into(),
        None => first,
    }
}

/// The top-level modules `text` names (`crate::m`, and in the crate root
/// `m::`), leaving out comments and unit tests.
fn uses(text: &str, root: bool) -> BTreeSet<String> {
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
    let mut found = BTreeSet::new();
    for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
        for m in ORDER {
            let path = format!("{m}::");
            let mut rest = line;
            while let Some(i) = rest.find(&path) {
                let before = &rest[..i];
                let word_start = !before.ends_with(|c: char| c.is_alphanumeric() || c == '_');
                let crate_path = before.ends_with("crate::") || before.ends_with("crate::{");
                if word_start && (crate_path || (root && !before.ends_with("::"))) {
                    found.insert((*m).to_string());
                }
                rest = &rest[i + path.len()..];
            }
        }
        if let Some(group) = line.split("use crate::{").nth(1) {
            for m in ORDER {
                if group.split([',', '{', '}', ' ']).any(|w| w == *m) {
                    found.insert((*m).to_string());
                }
            }
        }
    }
    found
}

#[test]
fn modules_use_only_lower_layers() {
    let src = crate::root().join("src");
    let mut modules = BTreeSet::new();
    let mut wrong = Vec::new();
    for e in walkdir::WalkDir::new(&src).into_iter().flatten() {
        let p = e.path();
        if p.extension().is_none_or(|x| x != "rs") || p.file_name().is_some_and(|n| n == "tests.rs")
        {
            continue;
        }
        let rel = p.strip_prefix(&src).expect("under src");
        let module = module_of(rel);
        let Some(level) = ORDER.iter().position(|m| *m == module) else {
            wrong.push(format!(
                "{}: module {module} is not in the layer order",
                rel.display()
            ));
            continue;
        };
        modules.insert(module.clone());
        let text = std::fs::read_to_string(p).expect("source file");
        for used in uses(&text, module == "crate") {
            let at = ORDER.iter().position(|m| *m == used).unwrap_or(0);
            if used != module && at > level {
                wrong.push(format!(
                    "{}: {module} uses {used}, a higher layer",
                    rel.display()
                ));
            }
        }
    }
    assert!(modules.len() > 12, "modules found: {modules:?}");
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// ARCHITECTURE.md's "The parts" names the modules in the same order.
#[test]
fn architecture_states_the_layer_order() {
    let text =
        std::fs::read_to_string(crate::root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let design = text
        .split_once("## The parts\n")
        .map(|(_, rest)| rest.split("\n## ").next().unwrap_or(rest))
        .expect("a section 'The parts'");
    let first = |m: &str| design.find(&format!("`{m}`"));
    let mut last = 0;
    for m in ORDER.iter().filter(|m| **m != "crate") {
        let at = first(m).unwrap_or_else(|| panic!("ARCHITECTURE.md does not name `{m}`"));
        assert!(at >= last, "ARCHITECTURE.md names `{m}` out of order");
        last = at;
    }
}

/// The evaluator's parts (`src/eval`), lowest first: each uses only those
/// before it. `eval/mod.rs`, which holds them all, is above them.
const EVAL_ORDER: &[&str] = &["expr", "state", "flow", "read", "write", "exec"];

/// The parts of the evaluator `text` names: `eval::part::`, and from its
/// own files `super::part::` (`super::super::part::` one folder down).
fn eval_uses(text: &str) -> BTreeSet<String> {
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
    let mut found = BTreeSet::new();
    for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
        for part in EVAL_ORDER {
            let named = |prefix: &str| {
                let path = format!("{prefix}{part}::");
                line.match_indices(&path)
                    .any(|(i, _)| !line[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_'))
            };
            if named("eval::") || named("super::") {
                found.insert((*part).to_string());
            }
        }
    }
    found
}

/// Whether `text` (its code: comments and unit tests left out) names the
/// evaluator itself, `Interp`: a part that does can change every other.
fn names_interp(text: &str) -> bool {
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
    code.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .flat_map(|l| l.split(|c: char| !(c.is_alphanumeric() || c == '_')))
        .any(|w| w == "Interp")
}

#[test]
fn evaluator_parts_use_only_lower_parts() {
    let eval = crate::root().join("src").join("eval");
    let mut wrong = Vec::new();
    let mut files = 0;
    for e in walkdir::WalkDir::new(&eval).into_iter().flatten() {
        let p = e.path();
        if p.extension().is_none_or(|x| x != "rs") || p.file_name().is_some_and(|n| n == "tests.rs")
        {
            continue;
        }
        let rel = p.strip_prefix(&eval).expect("under src/eval");
        let name = rel.to_string_lossy().replace('\\', "/");
        let part = module_of(rel);
        if part == "mod" {
            continue;
        }
        let Some(level) = EVAL_ORDER.iter().position(|m| *m == part) else {
            wrong.push(format!("eval/{name}: part {part} is not in the order"));
            continue;
        };
        files += 1;
        let text = std::fs::read_to_string(p).expect("source file");
        if part != "exec" && names_interp(&text) {
            wrong.push(format!(
                "eval/{name}: {part} names Interp (only exec's steps may)"
            ));
        }
        for used in eval_uses(&text) {
            let at = EVAL_ORDER.iter().position(|m| *m == used).unwrap_or(0);
            if at > level {
                wrong.push(format!("eval/{name}: {part} uses {used}, a higher part"));
            }
        }
    }
    assert!(files > 30, "files found: {files}");
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
