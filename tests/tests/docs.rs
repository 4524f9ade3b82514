//! The docs name only what exists: every `hnav` / `hnav-bench` subcommand and flag in the
//! README and the guide under `docs/` is in that subcommand's `--help`, every relative link
//! resolves (anchors into markdown to a heading), and every repository path in a code span
//! exists. What is checked, and how commands are found, is in `hnav_tests::docs`.
//!
//! Needs the debug binaries `hnav` and `hnav-bench` (`cargo build -p hnav-operator -p
//! hnav-bench`, or any `cargo test --workspace`).

use std::process::Command;

use hnav_tests::docs::{self, Help};
use hnav_tests::swarm::{repo_root, workspace_bin};

fn help(bin: &str, path: &[String]) -> Help {
    let exe = workspace_bin(bin);
    let out = Command::new(&exe)
        .args(path)
        .arg("--help")
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", exe.display()));
    Help {
        ok: out.status.success(),
        text: String::from_utf8_lossy(&out.stdout).into_owned(),
    }
}

fn report(what: &str, problems: &[docs::Problem]) {
    if !problems.is_empty() {
        let lines: Vec<String> = problems.iter().map(ToString::to_string).collect();
        panic!("{} {what}:\n{}", problems.len(), lines.join("\n"));
    }
}

#[test]
fn every_command_the_docs_name_exists() {
    for bin in docs::command::BINARIES {
        let exe = workspace_bin(bin);
        assert!(
            exe.exists(),
            "{} is not built: cargo build -p hnav-operator -p hnav-bench",
            exe.display()
        );
    }
    let root = repo_root();
    let docs = docs::read_docs(&root).expect("the markdown files can be read");
    let lines = docs::command_lines(&docs);
    // The extraction finds the README's run command, and commands of both binaries.
    assert!(
        lines.iter().any(|(f, _, c)| f.as_os_str() == "README.md"
            && c.bin == "hnav"
            && c.words.first().is_some_and(|w| w == "run")),
        "no `hnav run` found in README.md"
    );
    assert!(lines.iter().any(|(_, _, c)| c.bin == "hnav-bench"));
    report(
        "commands name what does not exist",
        &docs::check_commands(&docs, help),
    );
}

#[test]
fn every_relative_link_resolves() {
    let root = repo_root();
    let docs = docs::read_docs(&root).expect("the markdown files can be read");
    assert!(docs.iter().any(|d| !d.scan.links.is_empty()));
    report("links point nowhere", &docs::check_links(&root, &docs));
}

#[test]
fn every_repository_path_in_code_exists() {
    let root = repo_root();
    let docs = docs::read_docs(&root).expect("the markdown files can be read");
    report("paths do not exist", &docs::check_paths(&root, &docs));
}
