//! No library file is longer than 900 lines and no library function longer than 120,
//! tests excluded (ARCHITECTURE.md, "What the compiler enforces": a file holds one job
//! and is read in one sitting, a function fits on a screen or two). Counted: every line of a `.rs` file under
//! src/, blank and comment lines included, except items marked `#[cfg(test)]` (a unit
//! test module and test-only helpers) and files that are test modules themselves
//! (`tests.rs`, or any file in a `tests/` folder).

use std::path::{Path, PathBuf};

/// The most lines a library file may have.
const MAX_LINES: usize = 900;

/// The most lines a library function may have, its signature and closing brace
/// included.
const MAX_FUNCTION_LINES: usize = 120;

/// Lines of `text` outside `#[cfg(test)]` items.
fn library_lines(text: &str) -> usize {
    library_text(text).len()
}

/// The lines of `text` outside `#[cfg(test)]` items (see [`item_end`]).
fn library_text(text: &str) -> Vec<&str> {
    let lines: Vec<&str> = text.lines().collect();
    let mut kept = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        if lines[i].trim() == "#[cfg(test)]" {
            i = item_end(&lines, i + 1).0 + 1;
        } else {
            kept.push(lines[i]);
            i += 1;
        }
    }
    kept
}

/// The last line of the item starting at `lines[start]` (where its braces balance
/// again, or its `;` when it has no braces) and whether it has braces. Braces in
/// comments and literals do not count ([`code_of`]).
fn item_end(lines: &[&str], start: usize) -> (usize, bool) {
    let (mut depth, mut opened) = (0i64, false);
    for (j, line) in lines.iter().enumerate().skip(start) {
        let code = code_of(line);
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
            return (j, opened);
        }
    }
    (lines.len().saturating_sub(1), opened)
}

/// `line` without its `//` comment and with the contents of string and character
/// literals blanked (so that `"{}"` or `'{'` do not count as braces). Lifetimes (`'a`)
/// are left alone: a character literal is a quote, one (escaped) character, a quote.
fn code_of(line: &str) -> String {
    let chars: Vec<char> = line.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        match chars[i] {
            '/' if chars.get(i + 1) == Some(&'/') => break,
            '"' => {
                i += 1;
                while i < chars.len() && chars[i] != '"' {
                    i += if chars[i] == '\\' { 2 } else { 1 };
                }
                out.push_str("\"\"");
            }
            '\'' if chars.get(i + 1) == Some(&'\\') && chars.get(i + 3) == Some(&'\'') => {
                i += 3;
                out.push_str("' '");
            }
            '\'' if chars.get(i + 2) == Some(&'\'') => {
                i += 2;
                out.push_str("' '");
            }
            c => out.push(c),
        }
        i += 1;
    }
    out
}

/// The name of the function `code` starts, if it starts one (`fn`, `pub fn`,
/// `pub(crate) const fn`, ...).
fn function_name(code: &str) -> Option<&str> {
    let mut words = code.split_whitespace();
    loop {
        let w = words.next()?;
        if w == "fn" {
            let name = words.next()?;
            return Some(name.split(['(', '<']).next().unwrap_or(name));
        }
        let qualifier =
            w.starts_with("pub") || matches!(w, "const" | "async" | "unsafe" | "extern");
        if !qualifier {
            return None;
        }
    }
}

/// (name, first line (1-based in `lines`), length) of every function in `lines` over
/// [`MAX_FUNCTION_LINES`]. A function runs from its `fn` line to where its braces
/// balance again; one without a body (a trait method's signature) ends at its `;`.
fn long_functions(lines: &[&str]) -> Vec<(String, usize, usize)> {
    let mut long = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let Some(name) = function_name(&code_of(lines[i])).map(str::to_string) else {
            i += 1;
            continue;
        };
        let (end, opened) = item_end(lines, i);
        let n = end - i + 1;
        if opened && n > MAX_FUNCTION_LINES {
            long.push((name, i + 1, n));
        }
        // a nested function is counted inside its parent only
        i = if opened { end + 1 } else { i + 1 };
    }
    long
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

/// (path relative to `root`, text) of every library file under `root`/src, sorted.
fn library_files(root: &Path) -> Vec<(String, String)> {
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    files.sort();
    files
        .into_iter()
        .filter_map(|path| {
            let rel = path.strip_prefix(root).unwrap().to_path_buf();
            (!is_test_file(&rel)).then(|| {
                (
                    rel.display().to_string(),
                    std::fs::read_to_string(&path).unwrap(),
                )
            })
        })
        .collect()
}

/// (path relative to `root`, library lines) of every library file over [`MAX_LINES`].
fn too_long(root: &Path) -> Vec<(String, usize)> {
    library_files(root)
        .into_iter()
        .map(|(rel, text)| (rel, library_lines(&text)))
        .filter(|&(_, n)| n > MAX_LINES)
        .collect()
}

/// (path:line, name, lines) of every library function over [`MAX_FUNCTION_LINES`].
fn too_long_functions(root: &Path) -> Vec<(String, String, usize)> {
    let mut long = Vec::new();
    for (rel, text) in library_files(root) {
        for (name, line, n) in long_functions(&library_text(&text)) {
            long.push((format!("{rel}:{line}"), name, n));
        }
    }
    long
}

/// The crates of the workspace: the edges (this one), the core (core/) and the Python
/// bindings (python/).
fn crate_roots() -> [PathBuf; 3] {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    [root.to_path_buf(), root.join("core"), root.join("python")]
}

#[test]
fn no_library_function_is_over_120_lines() {
    let long: Vec<_> = crate_roots()
        .iter()
        .flat_map(|r| too_long_functions(r))
        .collect();
    assert!(
        long.is_empty(),
        "library functions over {MAX_FUNCTION_LINES} lines (tests excluded), split them \
         along their jobs: {long:?}"
    );
}

/// The function check's negative test: a 121-line function is reported with its name
/// and line, a 120-line one is not, braces in strings, character literals and
/// comments do not count, and a long function in a `#[cfg(test)]` module is ignored.
#[test]
fn the_check_reports_a_long_function_and_ignores_braces_in_literals() {
    let body = |n: usize| "    let x = 1;\n".repeat(n);
    let text = format!(
        "use std::fmt;\n\
         pub(crate) fn short<'a>(s: &'a str) -> usize {{\n{}    let _ = \"{{ {{\"; let _ = '{{'; // {{\n}}\n\
         fn long() {{\n{}}}\n\
         trait T {{\n    fn signature_only(&self);\n}}\n\
         #[cfg(test)]\nmod tests {{\n    fn long_test() {{\n{}    }}\n}}\n",
        body(117),
        body(119),
        body(300)
    );
    let lines = library_text(&text);
    let long = long_functions(&lines);
    // `short` has 1 + 117 + 1 + 1 = 120 lines; `long` 1 + 119 + 1 = 121, from line 122
    assert_eq!(long, vec![("long".to_string(), 122, 121)]);
    assert_eq!(
        code_of(r#"let s = "}"; let c = '}'; let e = '\''; // }"#),
        r#"let s = ""; let c = ' '; let e = ' '; "#
    );
    assert_eq!(function_name("pub(crate) const fn f<T>(x: T)"), Some("f"));
    assert_eq!(function_name("let f = 1;"), None);
}

#[test]
fn no_library_file_is_over_900_lines() {
    let long: Vec<_> = crate_roots().iter().flat_map(|r| too_long(r)).collect();
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
