//! The docs name only what exists: every `hnav` / `hnav-bench` subcommand and flag in the
//! README and the guide under `docs/` is in that subcommand's `--help`, every relative link
//! resolves (anchors into markdown to a heading), and every repository path in a code span
//! exists; the blocks a page marks run as written; the scenario format's descriptions name
//! every key. What is checked, and how, is in `hnav_tests::docs`.
//!
//! Needs the debug binaries `hnav` and `hnav-bench` (`cargo build -p hnav-operator -p
//! hnav-bench`, or any `cargo test --workspace`).

use std::process::Command;
use std::time::Instant;

use hnav_tests::docs::runnable::Action;
use hnav_tests::docs::sandbox::Sandbox;
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

/// Every page's marked blocks ([`docs::runnable`]) run as written, in a sandbox per page:
/// the files the page tells the reader to save are written, then its commands run in order
/// with the test build's binaries as `target/release/...`.
#[test]
fn every_marked_block_runs_as_written() {
    let root = repo_root();
    let bin_dir = workspace_bin("hnav")
        .parent()
        .expect("binaries live in a directory")
        .to_path_buf();
    let docs = docs::read_docs(&root).expect("the markdown files can be read");
    let mut problems = Vec::new();
    let mut ran = 0;
    for doc in &docs {
        let text = std::fs::read_to_string(root.join(&doc.path)).expect("readable");
        let steps = match docs::runnable::steps(&text) {
            Ok(s) if s.is_empty() => continue,
            Ok(s) => s,
            Err((line, what)) => {
                problems.push(format!("{}:{line}: {what}", doc.path.display()));
                continue;
            }
        };
        let tmp = tempfile::tempdir().expect("a temporary directory");
        let tag = doc.path.file_stem().unwrap_or_default().to_string_lossy();
        let sandbox = Sandbox::new(tmp.path(), &root, &bin_dir, &tag).expect("sandbox made");
        let started = Instant::now();
        for step in &steps {
            let at = format!("{}:{}", doc.path.display(), step.line);
            match (sandbox.apply(step), &step.action) {
                (Err(e), _) => problems.push(format!("{at}: {e}")),
                (Ok(Some(r)), Action::Run(want)) if r.code != Some(*want) => {
                    problems.push(format!(
                        "{at}: exit {:?}, not {want}:\n{}\n--- output:\n{}",
                        r.code, step.text, r.output
                    ));
                    break;
                }
                (Ok(Some(_)), _) => ran += 1,
                (Ok(None), _) => {}
            }
        }
        println!(
            "{}: {} blocks in {:.1} s",
            doc.path.display(),
            steps.len(),
            started.elapsed().as_secs_f64()
        );
    }
    assert!(ran > 0, "no block ran: the tutorials mark none");
    if !problems.is_empty() {
        panic!(
            "{} blocks failed:\n{}",
            problems.len(),
            problems.join("\n\n")
        );
    }
}

/// The scenario format's three descriptions (the module docs, the reference page and the
/// tutorial) name every key the parser takes, and the reference's block is a valid scenario.
#[test]
fn every_description_of_the_scenario_format_names_every_key() {
    let root = repo_root();
    let read = |p: &str| std::fs::read_to_string(root.join(p)).expect(p);
    let module = docs::module_doc_toml(&read("runtime/src/scenario/mod.rs"));
    let reference = read("docs/reference/scenario.md");
    let tutorial = read("docs/tutorials/write-a-scenario.md");
    for (name, text) in [
        ("runtime/src/scenario/mod.rs (module docs)", &module),
        ("docs/reference/scenario.md", &reference),
        ("docs/tutorials/write-a-scenario.md", &tutorial),
    ] {
        let missing = docs::missing_keys(text);
        assert!(missing.is_empty(), "{name} does not name {missing:?}");
    }
    // As written (maps relative to `scenarios/`), the block of every key loads.
    let block = reference
        .split("```toml\n")
        .nth(1)
        .and_then(|b| b.split("\n```").next())
        .expect("a toml block in the reference");
    for (name, text) in [("reference", block), ("module docs", module.as_str())] {
        let loaded =
            hnav_runtime::scenario::Scenario::from_str(text, name, &root.join("scenarios"));
        assert!(loaded.is_ok(), "{name}: {}", loaded.unwrap_err());
    }
}
