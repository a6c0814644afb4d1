//! The documentation holds together: README.md is a front page of at most 300
//! lines with the two set-up commands, every relative link of README.md and
//! docs/ reaches its file and heading, the command reference is what the
//! command line generates today, CITATION.cff is a valid CFF 1.2.0 file, and
//! every paper key the code cites has its entry in docs/references.md.

use crate::support::{files_below, odocal};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn read(rel: &str) -> String {
    std::fs::read_to_string(Path::new(ROOT).join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// README.md and every markdown file below docs/.
fn pages() -> Vec<PathBuf> {
    let md = |p: &Path| p.extension().is_some_and(|x| x == "md");
    let mut out = vec![Path::new(ROOT).join("README.md")];
    out.extend(files_below(&Path::new(ROOT).join("docs"), &md));
    out
}

/// The lines of a markdown text outside fenced code blocks, with inline code
/// spans blanked (a link or heading inside code is not one).
fn prose_lines(text: &str) -> Vec<String> {
    let mut fenced = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut kept = String::new();
        let mut in_code = false;
        for c in line.chars() {
            if c == '`' {
                in_code = !in_code;
            } else if !in_code {
                kept.push(c);
            }
        }
        out.push(kept);
    }
    out
}

/// The anchor a git forge (GitHub's rule) gives a heading's text: lower
/// case, punctuation dropped, spaces as hyphens; repeated anchors numbered.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        let Some(title) = line.strip_prefix('#').map(|t| t.trim_start_matches('#')) else {
            continue;
        };
        if fenced || !title.starts_with(' ') {
            continue;
        }
        let slug: String = link_texts(title.trim())
            .to_lowercase()
            .chars()
            .filter_map(|c| match c {
                ' ' => Some('-'),
                c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                _ => None,
            })
            .collect();
        let n = seen.entry(slug.clone()).or_insert(0);
        out.insert(if *n == 0 {
            slug.clone()
        } else {
            format!("{slug}-{n}")
        });
        *n += 1;
    }
    out
}

/// `[text](target)` replaced by `text`.
fn link_texts(s: &str) -> String {
    let mut out = s.to_string();
    while let Some((start, mid, end)) = next_link(&out, 0) {
        let text = out[start + 1..mid].to_string();
        out.replace_range(start..=end, &text);
    }
    out
}

/// The next `[text](target)` at or after `from`: the byte offsets of `[`,
/// of the `]` before `(`, and of the closing `)`.
fn next_link(s: &str, from: usize) -> Option<(usize, usize, usize)> {
    let mut i = from;
    while let Some(mid) = s[i..].find("](").map(|k| i + k) {
        let start = s[..mid].rfind('[');
        let end = s[mid + 2..].find(')').map(|k| mid + 2 + k);
        if let (Some(start), Some(end)) = (start, end) {
            return Some((start, mid, end));
        }
        i = mid + 2;
    }
    None
}

/// Every link target of a markdown page's prose.
fn targets(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in prose_lines(text) {
        let mut i = 0;
        while let Some((_, mid, end)) = next_link(&line, i) {
            out.push(line[mid + 2..end].trim().to_string());
            i = end + 1;
        }
    }
    out
}

#[test]
fn every_relative_link_of_readme_and_the_manual_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (file, anchor) = target.split_once('#').unwrap_or((&target, ""));
            let path = if file.is_empty() {
                page.clone()
            } else {
                page.parent().unwrap().join(file)
            };
            let rel = page.strip_prefix(ROOT).unwrap().display().to_string();
            if !path.exists() {
                broken.push(format!("{rel}: {target} (no such file)"));
            } else if !anchor.is_empty() {
                let heads = anchors(&std::fs::read_to_string(&path).unwrap_or_default());
                if !heads.contains(anchor) {
                    broken.push(format!("{rel}: {target} (no such heading)"));
                }
            }
        }
    }
    assert!(
        checked > 100,
        "only {checked} links found: the scan is broken"
    );
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn readme_is_a_front_page_with_the_two_set_up_commands() {
    let readme = read("README.md");
    let n = readme.lines().count();
    assert!(n <= 300, "README.md has {n} lines; the manual is docs/");
    let commands: Vec<&str> = readme
        .lines()
        .filter(|l| l.starts_with("cargo run") || l.starts_with("tools/test-all.sh"))
        .collect();
    assert_eq!(commands.len(), 2, "{commands:?}");
    assert!(commands[0].starts_with("cargo run --release -- demo "));
    assert!(commands[1].starts_with("tools/test-all.sh "));
    // The demo, the own-bag commands and the picture come first.
    let first: String = readme.lines().take(80).collect::<Vec<_>>().join("\n");
    for needle in [
        "cargo run --release -- demo",
        "odocal inspect",
        "odocal calibrate",
        "ros2_control.yaml",
        "![",
    ] {
        assert!(
            first.contains(needle),
            "{needle:?} not in README's first 80 lines"
        );
    }
}

#[test]
fn the_command_reference_is_generated_from_the_command_line() {
    let out = odocal(&["help-markdown"]);
    assert!(out.status.success());
    let generated = String::from_utf8(out.stdout).unwrap();
    let committed = read("docs/commands.md");
    assert!(
        generated == committed,
        "docs/commands.md is stale: run `odocal help-markdown > docs/commands.md`"
    );
    for command in [
        "demo",
        "simulate",
        "icp",
        "calibrate",
        "eval",
        "diagnose",
        "inspect",
        "experiment",
        "fleet",
    ] {
        assert!(
            committed.contains(&format!("## `odocal {command}`")),
            "{command}"
        );
    }
    assert!(
        !committed.contains("## `odocal help-markdown`"),
        "the hidden generator documents itself"
    );
}

/// The top-level keys of a CFF file and their blocks (YAML read as text:
/// `key: value` at column 0, the lines below it indented).
fn cff_blocks(text: &str) -> BTreeMap<String, String> {
    let mut out: BTreeMap<String, String> = BTreeMap::new();
    let mut key = String::new();
    for line in text.lines() {
        if line.trim_start().starts_with('#') || line.trim().is_empty() {
            continue;
        }
        if !line.starts_with(' ') && !line.starts_with('-') {
            let (k, v) = line.split_once(':').expect("a top-level `key: value`");
            key = k.trim().to_string();
            out.insert(key.clone(), v.trim().to_string());
        } else {
            let block = out.get_mut(&key).expect("an indented line under a key");
            block.push('\n');
            block.push_str(line);
        }
    }
    out
}

#[test]
fn citation_cff_is_a_valid_cff_1_2_file() {
    let text = read("CITATION.cff");
    let cff: serde_yaml_ng::Value = serde_yaml_ng::from_str(&text).expect("CITATION.cff is YAML");
    let get = |k: &str| {
        cff.get(k)
            .unwrap_or_else(|| panic!("CITATION.cff lacks {k}"))
    };
    assert_eq!(get("cff-version").as_str(), Some("1.2.0"));
    for k in ["message", "title", "type"] {
        assert!(get(k).as_str().is_some_and(|s| !s.is_empty()), "{k}");
    }
    assert_eq!(get("type").as_str(), Some("software"));
    // CFF takes SPDX identifiers, a list for a choice of licences: Cargo.toml's.
    let ids: Vec<&str> = match get("license") {
        serde_yaml_ng::Value::Sequence(s) => s.iter().filter_map(|v| v.as_str()).collect(),
        v => v.as_str().into_iter().collect(),
    };
    let cargo = read("Cargo.toml");
    assert!(
        cargo.contains(&format!("license = \"{}\"", ids.join(" OR "))),
        "the licence {ids:?} is not Cargo.toml's"
    );
    let authors = |v: &serde_yaml_ng::Value, what: &str| {
        let list = v.get("authors").and_then(|a| a.as_sequence()).cloned();
        let list = list.unwrap_or_else(|| panic!("{what}: authors"));
        assert!(!list.is_empty(), "{what}: no authors");
        for a in &list {
            assert!(
                a.get("family-names").is_some() || a.get("name").is_some(),
                "{what}: an author without family-names or name: {a:?}"
            );
        }
    };
    authors(&cff, "odocal");
    let works: Vec<serde_yaml_ng::Value> = cff
        .get("references")
        .and_then(|r| r.as_sequence())
        .cloned()
        .unwrap_or_default()
        .into_iter()
        .chain(cff.get("preferred-citation").cloned())
        .collect();
    assert!(works.len() >= 3, "the papers odocal implements are cited");
    for w in &works {
        let title = w
            .get("title")
            .and_then(|t| t.as_str())
            .expect("a work's title");
        assert!(
            w.get("type").and_then(|t| t.as_str()).is_some(),
            "{title}: type"
        );
        authors(w, title);
    }
    // Every top-level key is one CFF 1.2.0 defines.
    let known = [
        "abstract",
        "authors",
        "cff-version",
        "commit",
        "contact",
        "date-released",
        "doi",
        "identifiers",
        "keywords",
        "license",
        "license-url",
        "message",
        "preferred-citation",
        "references",
        "repository",
        "repository-artifact",
        "repository-code",
        "title",
        "type",
        "url",
        "version",
    ];
    for key in cff_blocks(&text).keys() {
        assert!(
            known.contains(&key.as_str()),
            "{key} is not a CFF 1.2.0 key"
        );
    }
}

/// Rust, Python, shell and TOML sources of the repository (not its data).
fn sources() -> Vec<PathBuf> {
    let code = |p: &Path| {
        p.extension()
            .is_some_and(|x| ["rs", "py", "pyi", "sh", "toml"].iter().any(|e| x == *e))
    };
    [
        "src", "tests", "tools", "benches", "python", "examples", "scans",
    ]
    .iter()
    .flat_map(|d| files_below(&Path::new(ROOT).join(d), &code))
    .collect()
}

/// The keys cited as `\[Key\]` or `[Key, eq. …]` (and Sec., Table, Fig.) in a text.
fn cited_keys(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (i, _) in text.match_indices('[') {
        let rest = &text[i + 1..];
        let key: String = rest
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric())
            .collect();
        let after = &rest[key.len()..];
        let locator = ["eq.", "eqs.", "Sec.", "Table", "Tables", "Fig.", "Figs."]
            .iter()
            .any(|l| after.starts_with(&format!(", {l}")));
        let escaped = text[..i].ends_with('\\') && after.starts_with("\\]");
        let plausible = key.len() >= 5
            && key.starts_with(|c: char| c.is_ascii_uppercase())
            && key
                .chars()
                .nth(1)
                .is_some_and(|c| c.is_ascii_lowercase() || c == 'A');
        if plausible && (locator || escaped) {
            out.insert(key);
        }
    }
    out
}

#[test]
fn every_cited_paper_has_its_reference_and_none_is_cited_by_number() {
    let references = read("docs/references.md");
    let defined: BTreeSet<String> = references
        .lines()
        .filter_map(|l| l.strip_prefix("### "))
        .map(|k| k.trim().to_string())
        .collect();
    let numbered = ["seed", " 00"].concat();
    let mut missing = Vec::new();
    let mut cited = BTreeSet::new();
    for file in sources() {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        let rel = file.strip_prefix(ROOT).unwrap().display().to_string();
        let lower = text.to_lowercase().replace('_', " ");
        assert!(
            !lower.contains(&numbered),
            "{rel} cites a paper by number; use its key (docs/references.md)"
        );
        for key in cited_keys(&text) {
            if !defined.contains(&key) {
                missing.push(format!("{rel}: {key}"));
            }
            cited.insert(key);
        }
    }
    for key in [
        "Farina",
        "Paryanto",
        "GAHeading",
        "Censi2013",
        "Kummerle2009",
    ] {
        assert!(
            cited.contains(key),
            "{key} is cited nowhere: the scan is broken"
        );
    }
    assert!(
        missing.is_empty(),
        "keys without an entry in docs/references.md:\n{}",
        missing.join("\n")
    );
    // Each entry carries a BibTeX record under its own key.
    for key in &defined {
        assert!(
            references.contains(&format!("{{{key},")),
            "docs/references.md: {key} has no BibTeX entry"
        );
    }
}
