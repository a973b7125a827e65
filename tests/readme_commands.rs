//! Every `mrsysid` command that the README's "Set-up" and "Commands" sections and the
//! `--help` examples show runs on the shipped data: exit code 0 and an expected line of
//! output. The commands are parsed from README.md and from the help text, so they cannot
//! rot. A command with a placeholder (`LOGS…`, `V.toml`, `a.csv`, `[--json R.json]`) is
//! skipped; a path into the repository (`data/…`, `examples/…`) must exist.

use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The text of the README section whose heading starts with `title`.
fn section<'a>(readme: &'a str, title: &str) -> &'a str {
    let start = readme
        .find(&format!("\n## {title}"))
        .unwrap_or_else(|| panic!("README has no section {title:?}"));
    let rest = &readme[start + 1..];
    let end = rest[3..].find("\n## ").map_or(rest.len(), |e| e + 3);
    &rest[..end]
}

/// Argument lists of the `mrsysid` commands in `text`: what follows `cargo run --release
/// --` or `mrsysid ` up to the end of the line, a closing backtick or a `#` comment.
fn commands(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for line in text.lines() {
        for marker in ["cargo run --release -- ", "mrsysid "] {
            let mut rest = line;
            while let Some(at) = rest.find(marker) {
                let tail = &rest[at + marker.len()..];
                let end = tail.find(['`', '#']).unwrap_or(tail.len());
                let args: Vec<String> = tail[..end].split_whitespace().map(String::from).collect();
                if args
                    .first()
                    .is_some_and(|a| a.chars().all(|c| c.is_ascii_lowercase()))
                {
                    out.push(args);
                }
                rest = &tail[end..];
            }
        }
    }
    out.dedup();
    out
}

/// True for an argument that stands for something the user supplies.
fn placeholder(arg: &str) -> bool {
    let file_like = [".csv", ".toml", ".json", ".mcap"]
        .iter()
        .any(|e| arg.ends_with(e))
        || arg.ends_with('/');
    arg.contains(['…', '[', ']', '|', '$'])
        || arg.chars().any(|c| c.is_ascii_uppercase()) && !arg.starts_with('-')
        || file_like && !arg.contains('/')
}

/// Runs `args`, unless they hold a placeholder; returns whether it ran. A repository
/// path must exist, the exit code must be 0, and the output must contain the line
/// expected of the subcommand.
fn run(source: &str, args: &[String]) -> bool {
    if args.iter().any(|a| placeholder(a)) {
        return false;
    }
    for a in args {
        if a.starts_with("data/") || a.starts_with("examples/") || a.starts_with("docs/") {
            assert!(
                root().join(a).exists(),
                "{source}: {a} does not exist: {args:?}"
            );
        }
    }
    let o = Command::new(env!("CARGO_BIN_EXE_mrsysid"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("binary runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{source}: {args:?}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let expected = if args.iter().any(|a| a == "--help") {
        "Usage: mrsysid"
    } else {
        match args[0].as_str() {
            "fit" => "MMR fit per axis (Table 4)",
            "diagnose" => "Diagnosis:",
            other => panic!("{source}: no expected output for `{other}`"),
        }
    };
    assert!(
        stdout.lines().any(|l| l.contains(expected)),
        "{source}: {args:?} printed no line with {expected:?}:\n{stdout}"
    );
    true
}

#[test]
fn readme_and_help_commands_run_on_the_shipped_data() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let mut ran = Vec::new();
    for title in ["Set-up", "Commands"] {
        let found = commands(section(&readme, title));
        assert!(!found.is_empty(), "no commands found in README {title:?}");
        let n = found.iter().filter(|c| run(title, c)).count();
        assert!(
            n > 0,
            "every command of README {title:?} was skipped: {found:?}"
        );
        ran.push(n);
    }
    // The help texts the README's commands lead to: their examples.
    let help = Command::new(env!("CARGO_BIN_EXE_mrsysid"))
        .args(["fit", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&help.stdout).into_owned();
    let examples = help
        .split("Examples:")
        .nth(1)
        .expect("fit --help has examples");
    let found = commands(examples);
    assert!(found.len() >= 3, "{found:?}");
    let n = found.iter().filter(|c| run("fit --help", c)).count();
    assert!(n > 0, "every --help example was skipped: {found:?}");
    // Set-up: the shipped flight fit; Commands: `fit --help`; help: the sweep fit.
    assert_eq!(ran, [1, 1]);
    assert_eq!(n, 1);
}
