//! The dependency-tree check shared by `core_purity.rs` (the core crate) and
//! `wheel_purity.rs` (the Python wheel's crate): the package names of
//! `cargo tree -p <package> -e normal`, and which of a list of forbidden crates appear
//! in them. Each test file is a crate of its own that compiles this module with
//! `mod purity;`.

use std::process::Command;

/// The package names in `cargo tree --prefix none` output (one `name vX.Y.Z ...` a line).
pub fn packages(tree: &str) -> Vec<&str> {
    tree.lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect()
}

/// The crates of `forbidden` (name, why) found in a dependency tree listing, as
/// `name (why)`.
pub fn forbidden_in(tree: &str, forbidden: &[(&str, &str)]) -> Vec<String> {
    let found = packages(tree);
    forbidden
        .iter()
        .filter(|(name, _)| found.contains(name))
        .map(|(name, why)| format!("{name} ({why})"))
        .collect()
}

/// `cargo tree -p <package> -e normal --prefix none --offline` in the workspace: the
/// normal dependencies of `package` with the features a build of that package alone
/// enables.
pub fn cargo_tree(package: &str) -> String {
    let out = Command::new(env!("CARGO"))
        .args([
            "tree",
            "-p",
            package,
            "-e",
            "normal",
            "--prefix",
            "none",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "cargo tree failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}
