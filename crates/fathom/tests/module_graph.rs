//! The import graph between the modules of each crate has no circle: every `crate::` path in
//! a crate's sources (comments and test modules left out) is an edge from the module that
//! writes it to the module it names, and the test fails with the circles and the files
//! behind each edge. A circle means two rooms that cannot be understood (or moved) one
//! without the other; data goes below, what needs it above.
//!
//! A module is a file under `src/` (a folder's `mod.rs` and its sub-files count as one
//! module, the folder's). Grouping folders whose children the crate root re-exports
//! (`pub use animation::{binding, flight};` in fathom-core) make each child its own module.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Files that only tests compile (whole-file test modules and test helpers).
const TEST_FILES: &[&str] = &[
    "tests.rs",
    "tape_props.rs",
    "testkit.rs",
    "fuzz.rs",
    "testing.rs",
    "deep_tests.rs",
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n != "tests") {
                rust_files(&p, out);
            }
        } else if p.extension().is_some_and(|x| x == "rs")
            && !TEST_FILES.contains(&p.file_name().unwrap().to_str().unwrap())
        {
            out.push(p);
        }
    }
}

/// The source without comments and without its inline `#[cfg(test)] mod tests { .. }` block
/// (which by the project's convention ends the file).
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests {") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn ident_at(s: &str) -> &str {
    let end = s
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}

/// Grouping folders: `pub use group::{a, b};` in the crate root, child name -> group.
fn groups(root_code: &str) -> BTreeMap<String, String> {
    let mut g = BTreeMap::new();
    for stmt in root_code.split(';') {
        let stmt = stmt.trim();
        let Some(rest) = stmt.strip_prefix("pub use ") else {
            continue;
        };
        let group = ident_at(rest);
        let Some(list) = rest[group.len()..].strip_prefix("::{") else {
            continue;
        };
        for item in list.trim_end_matches('}').split(',') {
            let item = item.trim();
            if !item.is_empty() && item.chars().all(|c| c.is_ascii_lowercase() || c == '_') {
                g.insert(item.to_string(), group.to_string());
            }
        }
    }
    g
}

/// The module a file belongs to.
fn module_of(src: &Path, file: &Path, groups: &BTreeMap<String, String>) -> Option<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .filter(|c| c != "mod")
        .collect();
    let first = parts.first()?;
    if first == "lib" || first == "main" {
        return None;
    }
    if parts.len() > 1 && groups.get(&parts[1]) == Some(first) {
        return Some(parts[1].clone());
    }
    Some(first.clone())
}

/// The modules a piece of code names through `crate::` paths.
fn references(code: &str, groups: &BTreeMap<String, String>) -> BTreeSet<String> {
    let mut refs = BTreeSet::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        if let Some(list) = rest.strip_prefix('{') {
            let end = list.find('}').unwrap_or(list.len());
            for word in list[..end].split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
                refs.insert(word.to_string());
            }
            continue;
        }
        let first = ident_at(rest);
        refs.insert(first.to_string());
        // `crate::group::child`: the child is the module.
        if let Some(after) = rest[first.len()..].strip_prefix("::") {
            let child = ident_at(after);
            if groups.get(child).map(String::as_str) == Some(first) {
                refs.insert(child.to_string());
            }
        }
    }
    refs
}

type Edges = BTreeMap<String, BTreeMap<String, BTreeSet<String>>>;

/// Strongly connected components with more than one module (Tarjan).
fn circles(edges: &Edges) -> Vec<Vec<String>> {
    struct State<'a> {
        edges: &'a Edges,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        s.on.insert(v);
        if let Some(ws) = s.edges.get(v) {
            for w in ws.keys() {
                if !s.index.contains_key(w.as_str()) {
                    visit(s, w);
                    let lw = s.low[w.as_str()];
                    let lv = s.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if s.on.contains(w.as_str()) {
                    let iw = s.index[w.as_str()];
                    let lv = s.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
        }
        if s.low[v] == s.index[v] {
            let mut c = Vec::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on.remove(w);
                c.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if c.len() > 1 {
                c.sort();
                s.out.push(c);
            }
        }
    }
    let mut s = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The import graph of the crate whose sources are in `src`.
fn crate_edges(src: &Path) -> Edges {
    let root = ["lib.rs", "main.rs"]
        .iter()
        .map(|f| src.join(f))
        .find(|p| p.exists())
        .unwrap();
    let groups = groups(&code(&std::fs::read_to_string(root).unwrap()));
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut modules = BTreeMap::new();
    for f in &files {
        if let Some(m) = module_of(src, f, &groups) {
            modules.insert(f.clone(), m);
        }
    }
    let known: BTreeSet<&String> = modules.values().collect();
    let mut edges = Edges::new();
    for (f, m) in &modules {
        let text = code(&std::fs::read_to_string(f).unwrap());
        for r in references(&text, &groups) {
            if &r != m && known.contains(&r) {
                let file = f.strip_prefix(src).unwrap().display().to_string();
                edges
                    .entry(m.clone())
                    .or_default()
                    .entry(r)
                    .or_default()
                    .insert(file);
            }
        }
    }
    edges
}

#[test]
fn no_module_imports_itself_through_others() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut report = String::new();
    let mut checked = 0;
    for e in std::fs::read_dir(crates).unwrap() {
        let src = e.unwrap().path().join("src");
        if !src.is_dir() {
            continue;
        }
        checked += 1;
        let edges = crate_edges(&src);
        for c in circles(&edges) {
            report += &format!("{}: circle {}\n", src.display(), c.join(" "));
            for a in &c {
                for (b, files) in &edges[a] {
                    if c.contains(b) {
                        report += &format!("  {a} -> {b} in {files:?}\n");
                    }
                }
            }
        }
    }
    assert!(
        checked >= 10,
        "found only {checked} crates under {}",
        crates.display()
    );
    assert!(
        report.is_empty(),
        "import circles between modules:\n{report}"
    );
}

#[test]
fn the_graph_sees_a_circle_when_there_is_one() {
    let dir = std::env::temp_dir().join(format!("fathom-module-graph-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("group")).unwrap();
    let w = |f: &str, t: &str| std::fs::write(src.join(f), t).unwrap();
    w(
        "lib.rs",
        "pub mod group;\npub use group::{scene, binding};\npub mod tape;\n",
    );
    w("group.rs", "pub mod scene;\npub mod binding;\n");
    w(
        "group/scene.rs",
        "use crate::binding::Binding; // crate::tape in a comment\n",
    );
    w("group/binding.rs", "use crate::{scene::Scene, tape};\n");
    w(
        "tape.rs",
        "pub struct Tape;\n#[cfg(test)]\nmod tests {\n    use crate::scene;\n}\n",
    );
    let edges = crate_edges(&src);
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(
        circles(&edges),
        vec![vec!["binding".to_string(), "scene".to_string()]]
    );
    assert!(!edges.contains_key("tape"), "test modules are not edges");
    assert!(
        !edges["scene"].contains_key("tape"),
        "comments are not edges"
    );
}
