//! No import cycles between the library's files: the `use crate::...`, `use super::...`
//! and inline `crate::a::b` paths of every file under src/ and core/src/ (each crate
//! its own graph) (tests excluded: a file's
//! `#[cfg(test)]` part and `*tests.rs` files) form a graph whose strongly connected
//! components must all be single files.
//!
//! A path resolves to the deepest module that has a file (`crate::scene::file::X` ->
//! src/scene/file.rs). A `mod.rs` that re-exports a child's item (`pub use file::X`) is
//! a facade, not a dependency: a path through the re-export resolves to the child's
//! file, and the `pub use` itself is no edge.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Module = Vec<String>;

/// Every library file under `src` by its module path (`[]` for lib.rs), main.rs and
/// test files left out.
fn module_files(src: &Path) -> BTreeMap<Module, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            if !name.ends_with(".rs") || name.ends_with("tests.rs") || name == "main.rs" {
                continue;
            }
            let rel = path.strip_prefix(src).unwrap().with_extension("");
            let mut module: Module = rel.iter().map(|s| s.to_string_lossy().into()).collect();
            if matches!(module.last().map(String::as_str), Some("mod" | "lib")) {
                module.pop();
            }
            out.insert(module, path);
        }
    }
    out
}

/// The file's code without comments and without its `#[cfg(test)]` part.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
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

/// `a::{b, c::{d, e as f}}` -> `a::b`, `a::c::d`, `a::c::e`.
fn expand(tree: &str) -> Vec<String> {
    let tree: String = tree.split_whitespace().collect::<Vec<_>>().join(" ");
    let Some(open) = tree.find('{') else {
        let path = tree.split(" as ").next().unwrap_or("");
        return vec![path.replace(' ', "")];
    };
    let prefix = tree[..open].replace(' ', "");
    let close = tree.rfind('}').filter(|&c| c > open).unwrap_or(tree.len());
    let body = &tree[open + 1..close];
    let (mut parts, mut depth, mut current) = (Vec::new(), 0, String::new());
    for c in body.chars() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            _ => {}
        }
        if c == ',' && depth == 0 {
            parts.push(std::mem::take(&mut current));
        } else {
            current.push(c);
        }
    }
    parts.push(current);
    parts
        .iter()
        .filter(|p| !p.trim().is_empty())
        .flat_map(|p| expand(p).into_iter().map(|s| format!("{prefix}{s}")))
        .collect()
}

/// The `use` statements of `code` (`pub`: only the re-exports, else only the others),
/// expanded.
fn uses(code: &str, public: bool) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("use ") {
        let before = &rest[..i];
        let end = rest[i..].find(';').map_or(rest.len(), |e| i + e);
        // a `use` item starts its line (after indentation and a visibility), never
        // inside a string or an expression
        let line_start = before.rfind('\n').map_or(0, |k| k + 1);
        let lead = before[line_start..].trim();
        let visibility = ["", "pub", "pub(crate)", "pub(super)"];
        if visibility.contains(&lead) {
            let is_pub = !lead.is_empty();
            if is_pub == public {
                out.extend(expand(&rest[i + 4..end]));
            }
        }
        rest = &rest[(end + 1).min(rest.len())..];
    }
    out
}

/// Inline `crate::a::b` and `super::a` paths.
fn inline_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    for start in ["crate::", "super::"] {
        let mut from = 0;
        while let Some(i) = code[from..].find(start) {
            let i = from + i;
            let boundary = i == 0
                || !code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':');
            let len = code[i..]
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(code.len() - i);
            if boundary {
                out.push(code[i..i + len].trim_end_matches(':').to_string());
            }
            from = i + len.max(1);
        }
    }
    out
}

/// The module path `path` names from the file of module `here`, or None for an
/// external crate or std.
fn absolute(path: &str, here: &Module, files: &BTreeMap<Module, PathBuf>) -> Option<Module> {
    let segs: Vec<String> = path
        .split("::")
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect();
    let first = segs.first()?.as_str();
    // `super` of a file `a/b.rs` (module a::b) is `a`; `a/mod.rs` is module `a` and
    // its `super` the crate root
    let (mut base, rest) = match first {
        "crate" => (Vec::new(), &segs[1..]),
        "self" => (here.clone(), &segs[1..]),
        "super" => {
            let mut base = here.clone();
            let mut rest = &segs[..];
            while rest.first().map(String::as_str) == Some("super") {
                base.pop();
                rest = &rest[1..];
            }
            (base, rest)
        }
        child => {
            // a child module declared in this file (`use file::X` in scene/mod.rs)
            let mut m = here.clone();
            m.push(child.to_string());
            if !files.contains_key(&m) {
                return None;
            }
            (here.clone(), &segs[..])
        }
    };
    base.extend(rest.iter().cloned());
    Some(base)
}

/// The file-to-file dependency graph of the tree under `src`.
fn graph(src: &Path) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let files = module_files(src);
    let texts: BTreeMap<&Module, String> = files
        .iter()
        .map(|(m, p)| (m, code(&std::fs::read_to_string(p).unwrap())))
        .collect();
    // re-exports: (facade module, item) -> the child's file
    let mut reexports: BTreeMap<(Module, String), PathBuf> = BTreeMap::new();
    for (m, text) in &texts {
        for u in uses(text, true) {
            let Some(abs) = absolute(&u, m, &files) else {
                continue;
            };
            if abs.len() == m.len() + 2 && abs.starts_with(m) {
                let child: Module = abs[..m.len() + 1].to_vec();
                if let Some(f) = files.get(&child) {
                    reexports.insert(((*m).clone(), abs[m.len() + 1].clone()), f.clone());
                }
            }
        }
    }
    let mut edges: BTreeMap<PathBuf, BTreeSet<PathBuf>> = BTreeMap::new();
    for (m, text) in &texts {
        let from = &files[*m];
        for path in uses(text, false).into_iter().chain(inline_paths(text)) {
            let Some(abs) = absolute(&path, m, &files) else {
                continue;
            };
            let Some(k) = (0..=abs.len())
                .rev()
                .find(|&k| files.contains_key(&abs[..k]))
            else {
                continue;
            };
            let module = abs[..k].to_vec();
            if module.is_empty() {
                continue; // the crate root
            }
            let to = match abs
                .get(k)
                .and_then(|item| reexports.get(&(module.clone(), item.clone())))
            {
                Some(f) => f.clone(),
                None => files[&module].clone(),
            };
            if &to != from {
                edges.entry(from.clone()).or_default().insert(to);
            }
        }
    }
    edges
}

/// The strongly connected components with more than one file (Tarjan).
fn cycles(edges: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<Vec<PathBuf>> {
    struct Tarjan<'a> {
        edges: &'a BTreeMap<PathBuf, BTreeSet<PathBuf>>,
        index: BTreeMap<&'a PathBuf, usize>,
        low: BTreeMap<&'a PathBuf, usize>,
        stack: Vec<&'a PathBuf>,
        out: Vec<Vec<PathBuf>>,
    }
    impl<'a> Tarjan<'a> {
        fn visit(&mut self, v: &'a PathBuf) {
            let i = self.index.len();
            self.index.insert(v, i);
            self.low.insert(v, i);
            self.stack.push(v);
            for w in self.edges.get(v).into_iter().flatten() {
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let lw = self.low[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if self.stack.contains(&w) {
                    let iw = self.index[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                while let Some(w) = self.stack.pop() {
                    component.push(w.clone());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.out.push(component);
                }
            }
        }
    }
    let mut t = Tarjan {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !t.index.contains_key(v) {
            t.visit(v);
        }
    }
    t.out
}

fn describe(src: &Path, edges: &BTreeMap<PathBuf, BTreeSet<PathBuf>>, c: &[PathBuf]) -> String {
    let rel = |p: &PathBuf| p.strip_prefix(src).unwrap().display().to_string();
    let mut lines = vec![c.iter().map(rel).collect::<Vec<_>>().join(", ")];
    for a in c {
        for b in edges.get(a).into_iter().flatten().filter(|b| c.contains(b)) {
            lines.push(format!("    {} -> {}", rel(a), rel(b)));
        }
    }
    lines.join("\n")
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // the edges' crate (src/), the core's (core/src/) and the Python bindings'
    // (python/src/), each its own graph
    for (src, (a, b)) in [
        (root.join("src"), ("scene/file.rs", "scene/contact.rs")),
        (root.join("core/src"), ("ribbon/sim.rs", "ribbon/step.rs")),
        (root.join("python/src"), ("simulation.rs", "save.rs")),
    ] {
        let edges = graph(&src);
        // the graph is not trivially empty: a known edge is in it
        assert!(edges[&src.join(a)].contains(&src.join(b)), "{a} -> {b}");
        let found = cycles(&edges);
        let text: Vec<String> = found.iter().map(|c| describe(&src, &edges, c)).collect();
        assert!(
            found.is_empty(),
            "import cycles between files:\n{}",
            text.join("\n")
        );
    }
}

/// A tree of files, each `(path, text)`, under a fresh temporary `src`.
fn tree(name: &str, files: &[(&str, &str)]) -> PathBuf {
    let src = std::env::temp_dir()
        .join(format!("import_cycles_{}_{name}", std::process::id()))
        .join("src");
    let _ = std::fs::remove_dir_all(&src);
    for (path, text) in files {
        let p = src.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    src
}

#[test]
fn a_cycle_is_found_and_a_facade_is_not_one() {
    let src = tree(
        "cycle",
        &[
            ("lib.rs", "pub mod a;\npub mod s;\n"),
            ("a/mod.rs", "mod b;\nmod c;\npub use b::Bee;\n"),
            // b uses c's item inline, c uses b's through the facade: a cycle b <-> c
            ("a/b.rs", "pub struct Bee(crate::a::c::Sea);\n"),
            ("a/c.rs", "use super::Bee; // c -> b via the re-export\npub struct Sea;\n"),
            // the facade alone (s/mod.rs re-exports t, t uses s's own item) is no cycle
            ("s/mod.rs", "mod t;\npub use t::Tee;\npub struct Own;\n"),
            ("s/t.rs", "use super::Own;\npub struct Tee(Own);\n#[cfg(test)]\nmod tests { use crate::a::Bee; }\n"),
        ],
    );
    let edges = graph(&src);
    let found = cycles(&edges);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0], vec![src.join("a/b.rs"), src.join("a/c.rs")]);
    // t -> s/mod.rs (Own lives there) but s/mod.rs's re-export is no edge back
    assert!(edges[&src.join("s/t.rs")].contains(&src.join("s/mod.rs")));
    assert!(!edges.contains_key(&src.join("s/mod.rs")));
    // the test part of t is ignored
    assert!(!edges[&src.join("s/t.rs")].contains(&src.join("a/b.rs")));
}
