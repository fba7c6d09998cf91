//! The house keeps its floor plan: the top-level modules of `src/` form a stack in which every
//! import points down (docs/architecture.md, the map in `src/lib.rs`). This test reads every
//! `crate::…` path in the code (comments stripped) and fails on an import of a layer above,
//! which also rules out every cycle between top-level modules, and on a top-level module that
//! the stack does not place.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The layers, bottom first. A module may import the modules before it, never one after it.
const STACK: &[&str] = &[
    "resources",
    "mesh",
    "la",
    "partition",
    "material",
    "fem",
    "loads",
    "contact",
    "model",
    "step",
    "time",
    "output",
    "error",
    "driver",
    "scenario",
    "studies",
];

/// The crate root's re-exports (`src/lib.rs`) and the layers they come from.
const ROOT_EXPORTS: &[(&str, &str)] = &[
    ("Error", "error"),
    ("Interruption", "error"),
    ("Problem", "model"),
    ("ProblemBuilder", "model"),
    ("State", "model"),
    ("Scenario", "scenario"),
    ("SolverParams", "step"),
];

/// Files outside the stack: the crate root (its re-exports are the public face) and the
/// command line, which sit on top of everything.
const ROOTS: &[&str] = &["lib.rs", "main.rs"];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The text of a Rust file without its comments (line, doc and block comments) and without
/// its string and character literals: `crate::` in a comment or a string is not an import.
fn code_of(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let at = |i: usize, s: &str| s.chars().enumerate().all(|(k, x)| c.get(i + k) == Some(&x));
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < c.len() {
        if at(i, "//") {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if at(i, "/*") {
            let mut depth = 0;
            while i < c.len() {
                if at(i, "/*") {
                    depth += 1;
                    i += 2;
                } else if at(i, "*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if c[i] == 'r' && (at(i + 1, "\"") || at(i + 1, "#")) && !c[i.saturating_sub(1)].is_alphanumeric() {
            // A raw string r"…" or r#"…"#.
            let hashes = c[i + 1..].iter().take_while(|&&x| x == '#').count();
            let close: String = std::iter::once('"').chain(std::iter::repeat_n('#', hashes)).collect();
            i += 2 + hashes;
            while i < c.len() && !at(i, &close) {
                i += 1;
            }
            i += close.chars().count();
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if c[i] == '\'' && (c.get(i + 2) == Some(&'\'') || c.get(i + 1) == Some(&'\\')) {
            // A character literal ('"', '\'', '\n'); a lifetime has no closing quote.
            i += 1;
            while i < c.len() && c[i] != '\'' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The top-level modules a piece of code names through `crate::`: `crate::a::…` and each
/// top-level name of a `crate::{a::…, b, …}` group.
fn imported_modules(code: &str) -> Vec<String> {
    let mut found = Vec::new();
    let mut rest = code;
    while let Some(p) = rest.find("crate::") {
        let before = rest[..p].chars().next_back();
        rest = &rest[p + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // `thermocontact::…` in a doc test is not this crate's `crate::`
        }
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0;
            let mut item = String::new();
            for c in group.chars() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    _ => {}
                }
                if c == ',' && depth == 0 {
                    found.push(head(&item));
                    item.clear();
                } else {
                    item.push(c);
                }
            }
            found.push(head(&item));
        } else {
            found.push(head(rest));
        }
    }
    found.retain(|m| !m.is_empty());
    found
}

/// The first path segment of `a::b::…`.
fn head(path: &str) -> String {
    path.trim_start()
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The top-level module a file of `src/` belongs to (`None` for the roots).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let relative = file.strip_prefix(src).unwrap();
    let first = relative.components().next().unwrap().as_os_str().to_str().unwrap();
    if ROOTS.contains(&first) {
        return None;
    }
    Some(first.trim_end_matches(".rs").to_string())
}

#[test]
fn every_import_points_down_the_stack() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let rank: BTreeMap<&str, usize> = STACK.iter().enumerate().map(|(i, m)| (*m, i)).collect();
    let mut unplaced = Vec::new();
    let mut upward = Vec::new();
    for file in &files {
        let Some(module) = module_of(&src, file) else { continue };
        let Some(&own) = rank.get(module.as_str()) else {
            unplaced.push(file.display().to_string());
            continue;
        };
        let code = code_of(&std::fs::read_to_string(file).unwrap());
        for imported in imported_modules(&code) {
            match rank.get(imported.as_str()) {
                Some(&r) if r > own => upward.push(format!(
                    "{} ({module}) imports `crate::{imported}`, a layer above it",
                    file.strip_prefix(&src).unwrap().display()
                )),
                Some(_) => {}
                // The crate root's re-exports belong to the layers that define them.
                None if ROOT_EXPORTS.iter().any(|(name, _)| *name == imported) => {
                    let (_, layer) = ROOT_EXPORTS.iter().find(|(name, _)| *name == imported).unwrap();
                    if rank[layer] > own {
                        upward.push(format!(
                            "{} ({module}) imports `crate::{imported}` of `{layer}`, a layer above it",
                            file.strip_prefix(&src).unwrap().display()
                        ));
                    }
                }
                None => upward.push(format!(
                    "{} imports `crate::{imported}`, which the stack does not place",
                    file.strip_prefix(&src).unwrap().display()
                )),
            }
        }
    }
    assert!(
        unplaced.is_empty(),
        "modules not in the stack of tests/layering.rs: {unplaced:?}"
    );
    assert!(upward.is_empty(), "upward imports:\n{}", upward.join("\n"));
}

/// The check itself sees what it must: a grouped import, a path in code, and no path in a
/// comment or a string.
#[test]
fn the_import_reader_sees_groups_and_skips_comments_and_strings() {
    let text = r#"
        use crate::{la::CsrMatrix, model::{Problem, State}};
        // use crate::driver::run;
        /* crate::scenario */
        let s = "crate::output";
        let x = crate::step::direct::norm(1.0);
        /// [`crate::time::march`]
    "#;
    let code = code_of(text);
    assert_eq!(imported_modules(&code), ["la", "model", "step"]);
}
