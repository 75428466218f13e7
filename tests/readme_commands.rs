//! Every `developable_sim` command quoted in README.md and docs/*.md parses: its
//! subcommand exists, every `--flag` it names is one of that subcommand's options, and
//! a concrete command (no `[optional]` or `A|B` placeholders) is accepted by the
//! binary's own argument parser (run with `--help` appended: clap parses every argument
//! before it, values included, then prints the help instead of running). So the front
//! page cannot drift from the binary.
//!
//! Commands are taken from fenced code blocks (and, in README.md, from inline code
//! spans that start with `developable_sim ` or `cargo run --release -- `), after the
//! program `developable_sim`, `./target/release/developable_sim` or `cargo run
//! --release --`; shell comments, `$(...)`, `;`, `&&`, `|` and redirections are
//! understood well enough for the commands we quote.

use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_developable_sim");

/// A command found in a document: where, and its arguments after the program.
#[derive(Debug)]
struct Quoted {
    place: String,
    args: Vec<String>,
}

/// Code quoted in a markdown text: the lines of fenced blocks, and (if `inline`) the
/// inline code spans of other lines, each with its line number.
fn code_lines(md: &str, inline: bool) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    let mut pending = String::new();
    for (i, line) in md.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            // a trailing backslash continues the command on the next line
            if let Some(head) = line.strip_suffix('\\') {
                pending.push_str(head);
                pending.push(' ');
                continue;
            }
            pending.push_str(line);
            out.push((i + 1, std::mem::take(&mut pending)));
        } else if inline {
            out.extend(
                line.split('`')
                    .skip(1)
                    .step_by(2)
                    .map(|s| (i + 1, s.to_string())),
            );
        }
    }
    out
}

/// Shell words of one line, split into simple commands at `;`, `&&`, `||`, `|` and the
/// loop keywords; `#` comments and redirections dropped; quotes and `$(...)` kept
/// within a word.
fn simple_commands(line: &str) -> Vec<Vec<String>> {
    let mut commands = vec![Vec::new()];
    let mut word = String::new();
    let mut in_word = false;
    let (mut quote, mut depth) = (None::<char>, 0usize);
    let mut chars = line.chars().peekable();
    let end_word = |word: &mut String, in_word: &mut bool, cmds: &mut Vec<Vec<String>>| {
        if *in_word {
            cmds.last_mut().unwrap().push(std::mem::take(word));
            *in_word = false;
        }
    };
    while let Some(c) = chars.next() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') if depth == 0 => {
                quote = Some(c);
                in_word = true;
            }
            (None, '$') if chars.peek() == Some(&'(') => {
                word.push(c);
                in_word = true;
            }
            (None, '(') => {
                depth += 1;
                word.push(c);
                in_word = true;
            }
            (None, ')') if depth > 0 => {
                depth -= 1;
                word.push(c);
            }
            (None, c) if depth > 0 => word.push(c),
            (None, '#') if !in_word => break,
            (None, ' ' | '\t') => end_word(&mut word, &mut in_word, &mut commands),
            (None, ';' | '|' | '&') => {
                end_word(&mut word, &mut in_word, &mut commands);
                while chars.peek() == Some(&c) {
                    chars.next();
                }
                commands.push(Vec::new());
            }
            (None, c) => {
                word.push(c);
                in_word = true;
            }
        }
    }
    end_word(&mut word, &mut in_word, &mut commands);
    commands
        .into_iter()
        .map(|mut cmd| {
            // a redirection ends the arguments; loop keywords start a command
            if let Some(i) = cmd
                .iter()
                .position(|w| w.contains('>') || w.starts_with('<'))
            {
                cmd.truncate(i);
            }
            while matches!(
                cmd.first().map(String::as_str),
                Some("do" | "then" | "else")
            ) {
                cmd.remove(0);
            }
            cmd
        })
        .collect()
}

/// The arguments after our program, if `cmd` runs it (a bare mention of the program's
/// name, or `cargo run --release -- ...`, is not a command).
fn our_args(cmd: &[String]) -> Option<Vec<String>> {
    let program = cmd.first()?;
    let args =
        if program == "developable_sim" || program.ends_with("target/release/developable_sim") {
            cmd[1..].to_vec()
        } else if program == "cargo" && cmd.get(1).map(String::as_str) == Some("run") {
            let dashes = cmd.iter().position(|w| w == "--")?;
            cmd[dashes + 1..].to_vec()
        } else {
            return None;
        };
    (!args.is_empty() && args[0] != "...").then_some(args)
}

fn quoted_commands(name: &str, md: &str, inline: bool) -> Vec<Quoted> {
    let mut out = Vec::new();
    for (line_no, line) in code_lines(md, inline) {
        for cmd in simple_commands(&line) {
            if let Some(args) = our_args(&cmd) {
                out.push(Quoted {
                    place: format!("{name}:{line_no}: `{}`", line.trim()),
                    args,
                });
            }
        }
    }
    out
}

fn run(args: &[String]) -> (bool, String) {
    let out = Command::new(BIN)
        .args(args)
        .output()
        .expect("run developable_sim");
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

/// The long options an option listing of `--help` names (lines starting with `-`).
fn long_options(help: &str) -> Vec<String> {
    help.lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with('-'))
        .flat_map(|l| l.split([' ', ',']))
        .filter(|w| w.starts_with("--"))
        .map(|w| w.split(['=', '<', '[']).next().unwrap().to_string())
        .collect()
}

/// A flag named by a quoted word: `[--set` -> `--set`, `--view=-1,2,3` -> `--view`.
fn flag_of(word: &str) -> Option<String> {
    let w = word.trim_start_matches(['[', '(']);
    if !w.starts_with("--") || w == "--" {
        return None;
    }
    let name: String = w
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
        .collect();
    Some(name)
}

/// Check one quoted command against the binary: None when it parses, else why not.
fn check(q: &Quoted) -> Option<String> {
    // `--ros-args ...` is ROS's own syntax, parsed before clap: not checked here
    let end = q
        .args
        .iter()
        .position(|a| a == "--ros-args")
        .unwrap_or(q.args.len());
    let args = &q.args[..end];
    let Some(first) = args.first() else {
        return Some(format!("{}: no subcommand", q.place));
    };
    // the subcommand path: `bag info`, `run`, ...
    let mut path = vec![first.clone()];
    let mut help = loop {
        let mut a = path.clone();
        a.push("--help".into());
        let (ok, text) = run(&a);
        if !ok {
            return Some(format!(
                "{}: no subcommand `{}`:\n{text}",
                q.place,
                path.join(" ")
            ));
        }
        match args.get(path.len()) {
            Some(next) if text.contains("\nCommands:\n") && !next.starts_with('-') => {
                path.push(next.clone())
            }
            _ => break text,
        }
    };
    help.push('\n');
    let options = long_options(&help);
    for word in &args[path.len()..] {
        if let Some(flag) = flag_of(word) {
            if !options.contains(&flag) {
                return Some(format!(
                    "{}: `{}` has no option `{flag}` (it has {})",
                    q.place,
                    path.join(" "),
                    options.join(" ")
                ));
            }
        }
    }
    // a concrete command goes through the whole parser (values, positionals)
    let placeholder = |w: &String| w.contains(['[', ']', '|']) || w.contains("...");
    if !args.iter().any(placeholder) {
        let mut a = args.to_vec();
        a.push("--help".into());
        let (ok, text) = run(&a);
        if !ok {
            return Some(format!("{}: the parser refuses it:\n{text}", q.place));
        }
    }
    None
}

fn documents() -> Vec<(String, String, bool)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut docs = vec![(
        "README.md".to_string(),
        std::fs::read_to_string(root.join("README.md")).unwrap(),
        true,
    )];
    let mut pages: Vec<_> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    for p in pages {
        let name = format!("docs/{}", p.file_name().unwrap().to_string_lossy());
        docs.push((name, std::fs::read_to_string(&p).unwrap(), false));
    }
    docs
}

#[test]
fn every_command_quoted_in_the_readme_and_docs_parses() {
    let mut quoted = Vec::new();
    for (name, text, inline) in documents() {
        quoted.extend(quoted_commands(&name, &text, inline));
    }
    let readme = quoted
        .iter()
        .filter(|q| q.place.starts_with("README.md"))
        .count();
    // the front page quotes 9 commands (2026-12-07): 4 in fenced blocks, 5 inline, so
    // an extraction that loses either kind finds fewer than 8; docs/cli.md quotes every
    // subcommand (below). Finding fewer means the extraction broke, not that all is well
    assert!(
        readme >= 8,
        "only {readme} commands found in README.md: {quoted:#?}"
    );
    for sub in ["node", "run", "replay"] {
        assert!(
            quoted
                .iter()
                .any(|q| q.place.starts_with("README.md") && q.args[0] == sub),
            "README.md quotes no `{sub}` command"
        );
    }
    for sub in ["node", "run", "render", "replay", "bag", "report", "stress"] {
        assert!(
            quoted
                .iter()
                .any(|q| q.place.starts_with("docs/cli.md") && q.args[0] == sub),
            "docs/cli.md quotes no `{sub}` command"
        );
    }
    let failures: Vec<String> = quoted.iter().filter_map(check).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn the_check_refuses_unknown_subcommands_flags_and_values() {
    let md = "```sh\n\
        developable_sim run config/scenes/mobius_band.yaml --bogus-flag 1\n\
        cargo run --release -- fly config/scenes/mobius_band.yaml\n\
        developable_sim render SCENE.yaml --out OUT.png [--no-such-option S]\n\
        for n in 1 2; do ./target/release/developable_sim stress --max-steps lots; done\n\
        developable_sim bag look BAG_DIR\n\
        ```\n";
    let quoted = quoted_commands("test.md", md, false);
    assert_eq!(quoted.len(), 5, "{quoted:#?}");
    for q in &quoted {
        let why = check(q);
        assert!(why.is_some(), "{} should fail the check", q.place);
    }
    let why: Vec<String> = quoted.iter().filter_map(check).collect();
    assert!(why[0].contains("no option `--bogus-flag`"), "{}", why[0]);
    assert!(why[1].contains("no subcommand `fly`"), "{}", why[1]);
    assert!(
        why[2].contains("no option `--no-such-option`"),
        "{}",
        why[2]
    );
    assert!(why[3].contains("the parser refuses it"), "{}", why[3]);
    assert!(why[4].contains("no subcommand `bag look`"), "{}", why[4]);
}

#[test]
fn the_check_accepts_the_forms_the_readme_uses() {
    let md = "```sh\n\
        # a comment line\n\
        cargo run --release -- node config/scenes/ribbon_gripper.yaml --record bags/run-$(date +%Y%m%d-%H%M%S)\n\
        developable_sim node SCENE.yaml [--domain-id N] [--lockstep service|HANDLE] [--set k=v]...\n\
        developable_sim render S.yaml --out o.png --view=-0.4,-1,-0.8   # trailing comment\n\
        for s in a b; do\n  ./target/release/developable_sim run config/scenes/$s.yaml --stats target/$s.json; done\n\
        developable_sim node S.yaml --ros-args --params-file p.yaml -r __ns:=/x\n\
        developable_sim bag info BAG_DIR > out.txt 2>&1\n\
        ```\n\
        Inline: `developable_sim stress --quick --out target/stress`, not `developable_sim`.\n";
    let quoted = quoted_commands("test.md", md, true);
    assert_eq!(quoted.len(), 7, "{quoted:#?}");
    assert_eq!(
        quoted[0].args.last().unwrap(),
        "bags/run-$(date +%Y%m%d-%H%M%S)"
    );
    let failures: Vec<String> = quoted.iter().filter_map(check).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn ci_runs_exactly_the_readmes_test_command() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let section = readme
        .split("\n## The two commands")
        .nth(1)
        .expect("README.md has a section `## The two commands`");
    let block = section.split("```").nth(1).expect("a code block in it");
    // the block's last command is the test command
    let test_command = block
        .lines()
        .map(str::trim)
        .rfind(|l| !l.is_empty() && !l.starts_with('#'))
        .expect("a command in the block");
    let ci = std::fs::read_to_string(root.join(".ci/run")).unwrap();
    let runs_it = ci
        .lines()
        .map(|l| l.split(" #").next().unwrap().trim())
        .any(|l| l == test_command);
    assert!(
        runs_it,
        ".ci/run does not run the README's test command `{test_command}`:\n{ci}"
    );
}
