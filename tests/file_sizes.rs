//! No library file is longer than 900 lines, its tests excluded (ENGINEERING.md: a file
//! holds one job and is read in one sitting). Counted: every line of a `.rs` file under
//! src/, blank and comment lines included, except items marked `#[cfg(test)]` (a unit
//! test module and test-only helpers) and files that are test modules themselves
//! (`tests.rs`, or any file in a `tests/` folder).

use std::path::{Path, PathBuf};

/// The most lines a library file may have.
const MAX_LINES: usize = 900;

/// Lines of `text` outside `#[cfg(test)]` items. An item ends where its braces
/// balance again (or at its `;` when it has none); braces in `//` comments do not count.
fn library_lines(text: &str) -> usize {
    let mut count = 0;
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        if line.trim() != "#[cfg(test)]" {
            count += 1;
            continue;
        }
        let mut depth: i64 = 0;
        let mut opened = false;
        for item_line in lines.by_ref() {
            let code = item_line.split("//").next().unwrap_or("");
            for c in code.chars() {
                match c {
                    '{' => {
                        depth += 1;
                        opened = true;
                    }
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            if (opened && depth <= 0) || (!opened && code.trim_end().ends_with(';')) {
                break;
            }
        }
    }
    count
}

fn is_test_file(path: &Path) -> bool {
    path.file_name().is_some_and(|n| n == "tests.rs")
        || path.components().any(|c| c.as_os_str() == "tests")
}

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

/// (path relative to `root`, library lines) of every library file over [`MAX_LINES`].
fn too_long(root: &Path) -> Vec<(String, usize)> {
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    files.sort();
    let mut long = Vec::new();
    for path in files {
        let rel = path.strip_prefix(root).unwrap().to_path_buf();
        if is_test_file(&rel) {
            continue;
        }
        let n = library_lines(&std::fs::read_to_string(&path).unwrap());
        if n > MAX_LINES {
            long.push((rel.display().to_string(), n));
        }
    }
    long
}

#[test]
fn no_library_file_is_over_900_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let long = too_long(root);
    assert!(
        long.is_empty(),
        "library files over {MAX_LINES} lines (tests excluded), split them: {long:?}"
    );
}

/// The check's negative test: a synthetic tree with a 901-line file is reported; a file
/// of 900 library lines and a long test module, a `tests.rs` and a file in a `tests/`
/// folder are not.
#[test]
fn the_check_reports_a_long_file_and_ignores_tests() {
    let root = std::env::temp_dir().join(format!("file_sizes_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(root.join("src/a/tests")).unwrap();
    let code = |n: usize| "let x = 1;\n".repeat(n);
    let with_tests = format!(
        "{}#[cfg(test)]\nuse std::fmt;\n#[cfg(test)]\nmod tests {{\n    // }} in a comment\n    fn f() {{\n{}    }}\n}}\n",
        code(898),
        code(500)
    );
    assert_eq!(library_lines(&with_tests), 898);
    std::fs::write(root.join("src/long.rs"), code(901)).unwrap();
    std::fs::write(root.join("src/ok.rs"), &with_tests).unwrap();
    std::fs::write(root.join("src/exactly.rs"), code(900)).unwrap();
    std::fs::write(root.join("src/a/tests.rs"), code(2000)).unwrap();
    std::fs::write(root.join("src/a/tests/big.rs"), code(2000)).unwrap();
    let long = too_long(&root);
    std::fs::remove_dir_all(&root).unwrap();
    assert_eq!(long, vec![("src/long.rs".to_string(), 901)]);
}
