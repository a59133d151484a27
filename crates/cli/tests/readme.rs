//! The documentation against the binary: `.ci/run` runs exactly the README's test command, and
//! every `--option` the README and the user guide write after an `htngtp COMMAND` is one that
//! the command's `--help` lists, so that the docs name no option the binary lacks.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The one line of `text` that starts with `cargo fmt` (the test command).
fn test_command(text: &str, what: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.trim_start().starts_with("cargo fmt"))
        .collect();
    assert_eq!(
        lines.len(),
        1,
        "{what}: expected one `cargo fmt ...` line, found {lines:?}"
    );
    lines[0].trim().to_string()
}

#[test]
fn ci_runs_exactly_the_readme_test_command() {
    let readme = test_command(&read("README.md"), "README.md");
    let ci = test_command(&read(".ci/run"), ".ci/run");
    assert_eq!(readme, ci, "README.md's test command and .ci/run differ");
    assert!(
        readme.contains("cargo doc --workspace --no-deps"),
        "{readme}"
    );
    assert!(readme.contains("cargo test --workspace"), "{readme}");
}

/// The subcommands (with `bench`'s targets) that take options.
const COMMANDS: &[&str] = &[
    "demo",
    "plan",
    "validate",
    "bench-hddl",
    "render",
    "facts",
    "gtp",
    "check",
    "export",
    "view",
    "bench library",
    "bench domain",
    "bench scale",
];

/// Per command, the options written after it in `text`: each `--name` is given to the nearest
/// `htngtp COMMAND` before it on the same line (lines ending in `\` are joined).
fn options_in(text: &str, found: &mut BTreeMap<String, Vec<(String, String)>>, file: &str) {
    let joined = text.replace("\\\n", " ");
    for line in joined.lines() {
        let mut command: Option<&str> = None;
        let mut i = 0;
        let bytes = line.as_bytes();
        while i < line.len() {
            let rest = &line[i..];
            if let Some(after) = rest.strip_prefix("htngtp ") {
                // The longest command name that follows (`bench library` before `bench`);
                // any other word (`htngtp binary`) ends the previous command's options.
                command = COMMANDS
                    .iter()
                    .filter(|c| {
                        after.starts_with(**c)
                            && !after[c.len()..]
                                .starts_with(|ch: char| ch.is_ascii_alphanumeric() || ch == '-')
                    })
                    .max_by_key(|c| c.len())
                    .copied();
                i += "htngtp ".len();
                continue;
            }
            if rest.starts_with("--")
                && (i == 0 || !bytes[i - 1].is_ascii_alphanumeric())
                && rest[2..].starts_with(|c: char| c.is_ascii_lowercase())
            {
                let name: String = rest[2..]
                    .chars()
                    .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '-')
                    .collect();
                if let Some(c) = command {
                    found.entry(c.to_string()).or_default().push((
                        format!("--{}", name.trim_end_matches('-')),
                        file.to_string(),
                    ));
                }
                i += 2 + name.len();
                continue;
            }
            i += rest.chars().next().map_or(1, char::len_utf8);
        }
    }
}

#[test]
fn the_docs_name_only_options_the_binary_has() {
    let mut found = BTreeMap::new();
    for file in ["README.md", "docs/guide.md"] {
        options_in(&read(file), &mut found, file);
    }
    assert!(
        found.contains_key("plan"),
        "no `htngtp plan --...` found in the docs"
    );
    let mut missing = Vec::new();
    for (command, options) in &found {
        let out = Command::new(env!("CARGO_BIN_EXE_htngtp"))
            .args(command.split(' '))
            .arg("--help")
            .output()
            .expect("htngtp runs");
        assert!(out.status.success(), "htngtp {command} --help failed");
        let help = String::from_utf8_lossy(&out.stdout);
        for (option, file) in options {
            let listed = help
                .split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
                .any(|word| word == option);
            if !listed {
                missing.push(format!("{file}: htngtp {command} {option}"));
            }
        }
    }
    missing.sort();
    missing.dedup();
    assert!(
        missing.is_empty(),
        "options the binary does not have:\n{}",
        missing.join("\n")
    );
}
