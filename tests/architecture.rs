//! The layout of the crate, read from its sources so that it stays true: the
//! math modules import nothing of files, pipelines, drawing, experiments or
//! the command line; `io` knows only formats; no two files import each other
//! through a cycle; the binary stays thin and no function grows too long.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const SRC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src");

/// Modules that hold algorithms only.
const MATH: [&str; 10] = [
    "geom", "scan", "robot", "icp", "calib", "classic", "sim", "eval", "diagnose", "fleet",
];
/// What a math module must not import.
const ABOVE_MATH: [&str; 4] = ["io", "pipeline", "viz", "experiments"];
/// What `live` (the network side) must not import: it feeds the pipeline.
const ABOVE_LIVE: [&str; 3] = ["pipeline", "viz", "experiments"];
/// What `io` must not import.
const ALGORITHMS: [&str; 4] = ["icp", "calib", "classic", "diagnose"];

/// One source file of the library: its module path and its code without
/// comments, string contents and unit tests.
struct Source {
    #[allow(dead_code)]
    file: PathBuf,
    module: Vec<String>,
    code: String,
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let rs = |p: &Path| p.extension().is_some_and(|x| x == "rs");
    out.extend(crate::support::files_below(dir, &rs));
}

/// The module path of a file under `src/` (`calib/mod.rs` → `calib`).
fn module_of(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(SRC).unwrap();
    let mut parts: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if parts.last().is_some_and(|l| l == "mod" || l == "lib") {
        parts.pop();
    }
    parts
}

/// The code with comments, string and char literals emptied, and everything
/// from the first `#[cfg(test)]` on (the unit tests) cut.
fn strip(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => text,
    };
    blank(text)
}

/// The text with comments, string and char literals emptied; line breaks
/// are kept, so lines keep their numbers.
fn blank(text: &str) -> String {
    let (b, mut out, mut i) = (text.as_bytes(), String::new(), 0);
    let skip_to = |out: &mut String, from: usize, to: usize| {
        out.extend(text[from..to.min(b.len())].chars().filter(|c| *c == '\n'));
    };
    while i < b.len() {
        let end = if b[i..].starts_with(b"//") {
            text[i..].find('\n').map_or(b.len(), |k| i + k)
        } else if b[i..].starts_with(b"/*") {
            text[i + 2..].find("*/").map_or(b.len(), |k| i + 2 + k + 2)
        } else if b[i] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            out.push_str("\"\"");
            j + 1
        } else if b[i] == b'\'' && i + 2 < b.len() && (b[i + 2] == b'\'' || b[i + 1] == b'\\') {
            // A char literal ('x' or '\n'); lifetimes have no closing quote.
            out.push_str("' '");
            text[i + 1..].find('\'').map_or(b.len(), |k| i + 2 + k)
        } else {
            let c = text[i..].chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
            continue;
        };
        skip_to(&mut out, i, end);
        i = end;
    }
    out
}

fn library() -> Vec<Source> {
    let mut files = Vec::new();
    rust_files(Path::new(SRC), &mut files);
    files.sort();
    files
        .into_iter()
        .filter(|f| !f.ends_with("main.rs") && !f.starts_with(Path::new(SRC).join("cli")))
        .map(|f| Source {
            module: module_of(&f),
            code: strip(&std::fs::read_to_string(&f).unwrap()),
            file: f,
        })
        .collect()
}

/// Every path the code names from `crate`, `super` or `self`, made absolute
/// (`use super::{a, b::c}` gives both); each as module segments.
fn paths(src: &Source) -> Vec<Vec<String>> {
    let m = &src.module;
    // Inside `a/b.rs` (module `a::b`) and inside `a/b/mod.rs` alike, `self`
    // is `a::b` and `super` is `a`.
    let self_base = m.clone();
    let super_base = m[..m.len().saturating_sub(1)].to_vec();
    let mut out = Vec::new();
    let code = &src.code;
    for (start, word) in [("crate::", 0usize), ("super::", 1), ("self::", 2)] {
        let mut from = 0;
        while let Some(k) = code[from..].find(start) {
            let at = from + k;
            from = at + start.len();
            let before = code[..at].chars().last().unwrap_or(' ');
            if before.is_alphanumeric() || before == '_' || before == ':' {
                continue;
            }
            let base: Vec<String> = match word {
                0 => Vec::new(),
                1 => super_base.clone(),
                _ => self_base.clone(),
            };
            for tail in expand(&code[from..]) {
                let mut p = base.clone();
                p.extend(tail);
                out.push(p);
            }
        }
    }
    out
}

/// The paths after a `crate::`/`super::` prefix: `a::b::c` or a brace group
/// `{a, b::{c, d}}` (first level expanded, deeper groups cut at the brace).
fn expand(rest: &str) -> Vec<Vec<String>> {
    let rest = rest.trim_start();
    if let Some(inner) = rest.strip_prefix('{') {
        let mut depth = 1;
        let mut end = 0;
        for (i, c) in inner.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = i;
                        break;
                    }
                }
                _ => {}
            }
        }
        let mut items = Vec::new();
        let (mut level, mut cur) = (0, String::new());
        for c in inner[..end].chars() {
            match c {
                '{' => level += 1,
                '}' => level -= 1,
                ',' if level == 0 => items.push(std::mem::take(&mut cur)),
                _ if level == 0 => cur.push(c),
                _ => {}
            }
        }
        items.push(cur);
        return items
            .iter()
            .map(|s| segments(s))
            .filter(|s| !s.is_empty())
            .collect();
    }
    vec![segments(rest)]
}

fn segments(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    for part in s.trim().split("::") {
        let name: String = part
            .trim()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if name.is_empty() || name == "self" {
            break;
        }
        out.push(name.clone());
        if name.len() != part.trim().len() {
            break;
        }
    }
    out
}

/// The file module a path lands in: its longest prefix that is a module.
fn target(path: &[String], modules: &BTreeSet<Vec<String>>) -> Option<Vec<String>> {
    (1..=path.len())
        .rev()
        .map(|n| path[..n].to_vec())
        .find(|p| modules.contains(p))
}

/// File → files it imports from (not itself).
fn graph(lib: &[Source]) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let modules: BTreeSet<Vec<String>> = lib.iter().map(|s| s.module.clone()).collect();
    lib.iter()
        .map(|s| {
            let deps = paths(s)
                .iter()
                .filter_map(|p| target(p, &modules))
                .filter(|t| *t != s.module && !t.is_empty())
                // A parent `mod.rs` re-exporting a child is not a use of it.
                .filter(|t| !(t.len() > s.module.len() && t.starts_with(&s.module)))
                .collect();
            (s.module.clone(), deps)
        })
        .collect()
}

fn top(m: &[String]) -> &str {
    m.first().map_or("", String::as_str)
}

#[test]
fn math_modules_import_no_files_pipelines_drawing_experiments_or_command_line() {
    let lib = library();
    let g = graph(&lib);
    let mut bad = Vec::new();
    for s in &lib {
        let from = top(&s.module);
        let forbidden: &[&str] = if MATH.contains(&from) {
            &ABOVE_MATH
        } else if from == "io" {
            &ALGORITHMS
        } else if from == "live" {
            &ABOVE_LIVE
        } else {
            &[]
        };
        for t in &g[&s.module] {
            if forbidden.contains(&top(t)) {
                bad.push(format!("{} imports {}", s.module.join("::"), t.join("::")));
            }
        }
        if MATH.contains(&from) && (s.code.contains("clap::") || s.code.contains("use clap")) {
            bad.push(format!("{} uses clap", s.module.join("::")));
        }
    }
    assert!(bad.is_empty(), "layering broken:\n{}", bad.join("\n"));
    // The check sees imports at all: the pipeline does import the math.
    assert!(g[&vec!["pipeline".to_string(), "drive".to_string()]]
        .iter()
        .any(|t| top(t) == "icp"));
}

/// Strongly connected components of more than one file (Tarjan).
fn cycles(g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<Vec<String>> {
    struct T<'a> {
        g: &'a BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        index: BTreeMap<&'a Vec<String>, usize>,
        low: BTreeMap<&'a Vec<String>, usize>,
        stack: Vec<&'a Vec<String>>,
        on: BTreeSet<&'a Vec<String>>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a Vec<String>) {
        let i = t.index.len();
        t.index.insert(v, i);
        t.low.insert(v, i);
        t.stack.push(v);
        t.on.insert(v);
        for w in t.g.get(v).into_iter().flatten() {
            let Some((w, _)) = t.g.get_key_value(w) else {
                continue;
            };
            if !t.index.contains_key(w) {
                visit(t, w);
                let l = t.low[w].min(t.low[v]);
                t.low.insert(v, l);
            } else if t.on.contains(w) {
                let l = t.index[w].min(t.low[v]);
                t.low.insert(v, l);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                comp.push(w.join("::"));
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
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !t.index.contains_key(v) {
            visit(&mut t, v);
        }
    }
    t.out
}

#[test]
fn no_two_files_import_each_other_through_a_cycle() {
    let c = cycles(&graph(&library()));
    assert!(c.is_empty(), "import cycles between files: {c:?}");
    // The detector finds a cycle where there is one.
    let m = |s: &str| vec![s.to_string()];
    let mut g = BTreeMap::new();
    g.insert(m("a"), BTreeSet::from([m("b")]));
    g.insert(m("b"), BTreeSet::from([m("c")]));
    g.insert(m("c"), BTreeSet::from([m("a")]));
    assert_eq!(cycles(&g).len(), 1);
}

/// Top-level module → top-level modules its files import from.
fn module_graph(
    g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut out: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (from, to) in g {
        let f = vec![top(from).to_string()];
        let entry = out.entry(f.clone()).or_default();
        for t in to {
            let t = vec![top(t).to_string()];
            if t != f && !t[0].is_empty() {
                entry.insert(t);
            }
        }
    }
    out
}

#[test]
fn no_two_modules_import_each_other_through_a_cycle() {
    let g = module_graph(&graph(&library()));
    let c = cycles(&g);
    assert!(c.is_empty(), "import cycles between modules: {c:?}");
    // The collapse sees the modules: the pipeline imports calib and io.
    let p = &g[&vec!["pipeline".to_string()]];
    assert!(p.contains(&vec!["calib".to_string()]) && p.contains(&vec!["io".to_string()]));
}

/// `(lines, file, first line, name)` of every `fn` of the code (brace matched).
fn functions(file: &Path) -> Vec<(usize, String, usize, String)> {
    let text = std::fs::read_to_string(file).unwrap();
    let lines: Vec<String> = blank(&text).lines().map(str::to_string).collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let t = t
            .strip_prefix("pub(crate) ")
            .or_else(|| t.strip_prefix("pub "))
            .unwrap_or(t);
        let t = t.strip_prefix("const ").unwrap_or(t);
        let t = t.strip_prefix("unsafe ").unwrap_or(t);
        let Some(rest) = t.strip_prefix("fn ") else {
            continue;
        };
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let (mut depth, mut started) = (0i64, false);
        for (j, m) in lines.iter().enumerate().skip(i) {
            for c in m.chars() {
                match c {
                    '{' => {
                        depth += 1;
                        started = true;
                    }
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            if (started && depth <= 0) || (!started && m.trim_end().ends_with(';')) {
                out.push((j - i + 1, file.display().to_string(), i + 1, name.clone()));
                break;
            }
        }
    }
    out
}

#[test]
fn the_binary_is_thin_and_no_function_is_over_100_lines() {
    let main = std::fs::read_to_string(Path::new(SRC).join("main.rs")).unwrap();
    assert!(
        main.lines().count() < 300,
        "main.rs has {} lines",
        main.lines().count()
    );
    let mut files = Vec::new();
    rust_files(Path::new(SRC), &mut files);
    let long: Vec<String> = files
        .iter()
        .flat_map(|f| functions(f))
        .filter(|f| f.0 > 100)
        .map(|(n, f, l, name)| format!("{f}:{l} {name}: {n} lines"))
        .collect();
    assert!(
        long.is_empty(),
        "functions over 100 lines:\n{}",
        long.join("\n")
    );
    // The measure sees functions at all.
    let drive = functions(&Path::new(SRC).join("pipeline/drive.rs"));
    assert!(drive
        .iter()
        .any(|f| f.3 == "run_calibration_from" && f.0 > 20));
}
