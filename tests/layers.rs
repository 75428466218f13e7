//! The edges are layers (ARCHITECTURE.md, "Layers"): each top-level module of the
//! `developable_sim` crate may import the core and the modules of lower layers, never a
//! module of its own layer or above. Checked on every `crate::<module>` path (in `use`
//! items and inline) of every library file under src/, comments and `#[cfg(test)]`
//! parts left out (a unit test may reach upwards to build its fixture).
//!
//! The table below is the one place the layers are written; the error names the
//! offending file, the import and both layers.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Layer of each top-level module, lowest first. 0 is the core (its own crate,
/// `developable_core`, re-exported by lib.rs).
const LAYERS: &[(&str, u32)] = &[
    // 0: the simulation core
    ("baseline", 0),
    ("camera", 0),
    ("contact", 0),
    ("geometry", 0),
    ("metrics", 0),
    ("optim", 0),
    ("paper", 0),
    ("ribbon", 0),
    ("sim", 0),
    // 1: scene files, run statistics
    ("scene", 1),
    ("stats", 1),
    // plots and pages shared by the tools (report, stress); no scene, no run
    ("plot", 1),
    // 2: messages, CDR, schemas, QoS, the stamping clock; offline pictures of a scene
    ("wire", 2),
    ("render", 2),
    // 3: a simulation as the node runs it (no transport); headless runs
    ("session", 3),
    ("runner", 3),
    // 4: transports that need no DDS: bags and replay, the Foxglove server
    ("record", 4),
    ("foxglove", 4),
    // 5: the ROS 2 node over DDS (drives the recorder and Foxglove)
    ("ros", 5),
    // 6: tools built on runs
    ("report", 6),
    ("stress", 6),
    // 7: the command line
    ("cli", 7),
];

fn layer_of(module: &str) -> Option<u32> {
    LAYERS.iter().find(|(m, _)| *m == module).map(|(_, l)| *l)
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

/// The top-level modules a file's code names as `crate::<module>`, or through
/// `super::<module>` from a file directly under src/ (where `super` is the crate).
fn imported_modules(code: &str, top_level_file: bool) -> Vec<String> {
    let mut out = Vec::new();
    let prefixes: &[&str] = if top_level_file {
        &["crate::", "super::"]
    } else {
        &["crate::"]
    };
    for prefix in prefixes {
        let mut from = 0;
        while let Some(i) = code[from..].find(prefix) {
            let i = from + i;
            let boundary = i == 0
                || !code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':');
            let rest = &code[i + prefix.len()..];
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if boundary && !name.is_empty() {
                out.push(name);
            }
            from = i + prefix.len();
        }
    }
    // `use crate::{a, b::c}`: the modules inside the braces
    let mut from = 0;
    while let Some(i) = code[from..].find("crate::{") {
        let start = from + i + "crate::{".len();
        let end = code[start..].find('}').map_or(code.len(), |e| start + e);
        for part in code[start..end].split(',') {
            let name: String = part
                .trim()
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
        from = end;
    }
    out
}

/// Every library file under `src` with its top-level module (lib.rs and main.rs left
/// out: they declare and dispatch).
fn library_files(src: &Path) -> BTreeMap<PathBuf, String> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let rel = path.strip_prefix(src).unwrap();
            let name = rel.to_string_lossy().to_string();
            if !name.ends_with(".rs") || name == "lib.rs" || name == "main.rs" {
                continue;
            }
            let first = rel.iter().next().unwrap().to_string_lossy().to_string();
            let module = first.trim_end_matches(".rs").to_string();
            out.insert(path, module);
        }
    }
    out
}

/// Every import that points to the file's own layer (another module) or above:
/// `file: module (layer a) imports other (layer b)`.
fn violations(src: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for (path, module) in library_files(src) {
        let rel = path.strip_prefix(src).unwrap().display().to_string();
        let Some(own) = layer_of(&module) else {
            out.push(format!(
                "{rel}: module `{module}` is not in the layer table"
            ));
            continue;
        };
        let text = code(&std::fs::read_to_string(&path).unwrap());
        let top_level_file = !rel.contains('/');
        let mut seen = Vec::new();
        for other in imported_modules(&text, top_level_file) {
            if other == module || seen.contains(&other) {
                continue;
            }
            seen.push(other.clone());
            match layer_of(&other) {
                Some(l) if l < own => {}
                Some(l) => out.push(format!(
                    "{rel}: `{module}` (layer {own}) imports `{other}` (layer {l})"
                )),
                None => out.push(format!("{rel}: imports `{other}`, not in the layer table")),
            }
        }
    }
    out
}

#[test]
fn each_module_imports_only_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = library_files(&src);
    // every top-level module of the crate is in the table, and the check sees them
    for (m, _) in LAYERS.iter().filter(|(_, l)| *l > 0) {
        assert!(
            files.values().any(|f| f == m),
            "`{m}` is in the layer table but has no file under src/"
        );
    }
    let bad = violations(&src);
    assert!(
        bad.is_empty(),
        "imports against the layers:\n{}",
        bad.join("\n")
    );
}

/// The check's negative test: an upward import, a same-layer import, a `super::` from
/// a top-level file and an unknown module are all reported; downward imports, a
/// module's own paths, comments and test code are not.
#[test]
fn the_check_reports_every_import_against_the_layers() {
    let src = std::env::temp_dir()
        .join(format!("layers_{}", std::process::id()))
        .join("src");
    let _ = std::fs::remove_dir_all(&src);
    let files = [
        // allowed: down to wire and the core, its own module, a comment, a test
        (
            "session/ok.rs",
            "use crate::wire::msgs::Time;\nuse crate::{geometry, session::input};\n\
             // crate::ros::node in a comment\n#[cfg(test)]\nmod tests { use crate::cli; }\n",
        ),
        ("record/up.rs", "fn f() { crate::ros::node::start(); }\n"),
        ("foxglove.rs", "use super::record::bag;\n"),
        ("wire/grouped.rs", "use crate::{geometry, session};\n"),
        ("stats.rs", "use crate::nowhere::X;\n"),
    ];
    for (path, text) in files {
        let p = src.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    let mut bad = violations(&src);
    bad.sort();
    assert_eq!(
        bad,
        vec![
            "foxglove.rs: `foxglove` (layer 4) imports `record` (layer 4)",
            "record/up.rs: `record` (layer 4) imports `ros` (layer 5)",
            "stats.rs: imports `nowhere`, not in the layer table",
            "wire/grouped.rs: `wire` (layer 2) imports `session` (layer 3)",
        ]
    );
}
