//! What `tests/docs.rs` checks in the repository's markdown (the README and the guide under
//! `docs/`), each problem reported with its file and line:
//!
//! - every `hnav` and `hnav-bench` command line in code (spans and fenced blocks; see
//!   [`command`] for what counts as one) names subcommands that exist and flags that the
//!   named subcommand's `--help` lists;
//! - every relative link and image resolves to a file or directory, and a `#anchor` into a
//!   markdown file to one of its headings;
//! - every code span that is a repository path (`operator/src/report/`, its first component a
//!   top-level directory of the repository, no component a placeholder in capitals like
//!   `TARGET`) names a path that exists.
//!
//! - every key of the scenario format ([`hnav_runtime::scenario::KEYS`]) is named by each
//!   text that describes the format ([`missing_keys`]);
//! - the blocks a page marks to be run ([`runnable`]) run as written, in a [`sandbox`].
//!
//! Fenced blocks tagged with a language other than `sh`, `bash`, `shell` or `console` (`text`
//! for output, `toml`) are not read for commands: what a program printed is not a command.

pub mod command;
pub mod markdown;
pub mod runnable;
pub mod sandbox;

use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};

use command::{commands, flags, CommandLine};
use markdown::{scan, Scan};

/// One markdown file of the repository, scanned.
pub struct Doc {
    /// The path relative to the repository root.
    pub path: PathBuf,
    /// What the file holds.
    pub scan: Scan,
}

/// One thing wrong in the docs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Problem {
    /// The file, relative to the repository root.
    pub file: PathBuf,
    /// 1-based line number.
    pub line: usize,
    /// What is wrong.
    pub what: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.file.display(), self.line, self.what)
    }
}

/// A binary's `--help` for one subcommand path: whether it exited 0, and what it printed.
#[derive(Debug, Clone)]
pub struct Help {
    /// The command exited 0.
    pub ok: bool,
    /// Its standard output.
    pub text: String,
}

/// Every markdown file under `root` (hidden directories and `target/` left out), scanned.
pub fn read_docs(root: &Path) -> std::io::Result<Vec<Doc>> {
    let mut files = Vec::new();
    walk(root, root, &mut files)?;
    files.sort();
    files
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(root.join(&path))?;
            Ok(Doc {
                path,
                scan: scan(&text),
            })
        })
        .collect()
}

fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let path = entry.path();
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if entry.file_type()?.is_dir() {
            if !name.starts_with('.') && name != "target" {
                walk(root, &path, out)?;
            }
        } else if name.ends_with(".md") {
            out.push(path.strip_prefix(root).unwrap_or(&path).to_path_buf());
        }
    }
    Ok(())
}

/// Every command line the docs name, with where.
pub fn command_lines(docs: &[Doc]) -> Vec<(PathBuf, usize, CommandLine)> {
    let mut out = Vec::new();
    for doc in docs {
        for span in &doc.scan.spans {
            for c in commands(&span.text, false) {
                out.push((doc.path.clone(), span.line, c));
            }
        }
        for line in &doc.scan.fences {
            if ["", "sh", "bash", "shell", "console"].contains(&line.lang.as_str()) {
                for c in commands(&line.text, true) {
                    out.push((doc.path.clone(), line.line, c));
                }
            }
        }
    }
    out
}

/// Checks every command line against the binaries' help; `help(bin, path)` runs
/// `bin PATH... --help`.
pub fn check_commands(docs: &[Doc], mut help: impl FnMut(&str, &[String]) -> Help) -> Vec<Problem> {
    let mut cache: HashMap<(String, Vec<String>), Help> = HashMap::new();
    let mut problems = Vec::new();
    for (file, line, c) in command_lines(docs) {
        let mut ask = |path: &[String]| {
            cache
                .entry((c.bin.to_string(), path.to_vec()))
                .or_insert_with(|| help(c.bin, path))
                .clone()
        };
        for what in check_one(&c, &mut ask) {
            problems.push(Problem {
                file: file.clone(),
                line,
                what,
            });
        }
    }
    problems
}

/// What is wrong with one command line.
fn check_one(c: &CommandLine, help: &mut dyn FnMut(&[String]) -> Help) -> Vec<String> {
    let mut path: Vec<String> = Vec::new();
    let mut leaf = false;
    let mut problems = Vec::new();
    let shown = |path: &[String]| {
        std::iter::once(c.bin.to_string())
            .chain(path.iter().cloned())
            .collect::<Vec<_>>()
            .join(" ")
    };
    for word in &c.words {
        if word.starts_with('-') {
            let h = help(&path);
            for flag in flags(word) {
                if !lists_flag(&h.text, &flag) {
                    problems.push(format!(
                        "`{}` has no flag `{flag}` (not in `{} --help`)",
                        shown(&path),
                        shown(&path)
                    ));
                }
            }
            continue;
        }
        if leaf {
            continue;
        }
        if !help(&path).text.contains("\nCommands:\n") {
            // A command without subcommands: the rest are its arguments.
            leaf = true;
            continue;
        }
        let mut sub = path.clone();
        sub.push(word.clone());
        let h = help(&sub);
        let usage = format!("Usage: {}", shown(&sub));
        let named = h.text.lines().any(|l| {
            l.strip_prefix(&usage)
                .is_some_and(|r| r.is_empty() || r.starts_with(' '))
        });
        if !(h.ok && named) {
            problems.push(format!("`{}` has no subcommand `{word}`", shown(&path)));
            break;
        }
        path = sub;
    }
    problems
}

/// Whether a help text lists `flag` (followed by a character that cannot continue its name).
fn lists_flag(help: &str, flag: &str) -> bool {
    help.match_indices(flag).any(|(i, _)| {
        let next = help[i + flag.len()..].chars().next();
        !next.is_some_and(|c| c.is_ascii_alphanumeric() || c == '-')
    })
}

/// Checks every relative link: its file exists, and its anchor (into markdown) is a heading.
pub fn check_links(root: &Path, docs: &[Doc]) -> Vec<Problem> {
    let anchors: HashMap<PathBuf, &Vec<String>> = docs
        .iter()
        .map(|d| (root.join(&d.path), &d.scan.anchors))
        .collect();
    let mut problems = Vec::new();
    for doc in docs {
        let here = root.join(&doc.path);
        for link in &doc.scan.links {
            let t = &link.target;
            if t.contains("://") || t.starts_with("mailto:") {
                continue;
            }
            let (file, anchor) = t.split_once('#').unwrap_or((t, ""));
            let target = if file.is_empty() {
                here.clone()
            } else {
                here.parent().unwrap_or(root).join(file)
            };
            let mut problem = |what: String| {
                problems.push(Problem {
                    file: doc.path.clone(),
                    line: link.line,
                    what,
                })
            };
            if !target.exists() {
                problem(format!("link `{t}`: no such file or directory"));
                continue;
            }
            if anchor.is_empty() || !file_is_markdown(&target) {
                continue;
            }
            let canonical = std::fs::canonicalize(&target).unwrap_or(target.clone());
            let known = anchors
                .iter()
                .find(|(p, _)| std::fs::canonicalize(p).ok().as_ref() == Some(&canonical));
            match known {
                Some((_, list)) if list.iter().any(|a| a == anchor) => {}
                Some(_) => problem(format!("link `{t}`: no heading with anchor `#{anchor}`")),
                None => problem(format!("link `{t}`: not a markdown file the test read")),
            }
        }
    }
    problems
}

fn file_is_markdown(path: &Path) -> bool {
    path.is_file() && path.extension().is_some_and(|e| e == "md")
}

/// Checks every code span that names a repository path (its first component one of the
/// repository's top-level directories): the path exists.
pub fn check_paths(root: &Path, docs: &[Doc]) -> Vec<Problem> {
    let top: Vec<String> = std::fs::read_dir(root)
        .map(|dir| {
            dir.filter_map(Result::ok)
                .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| !n.starts_with('.') && n != "target")
                .collect()
        })
        .unwrap_or_default();
    let mut problems = Vec::new();
    for doc in docs {
        for span in &doc.scan.spans {
            let t = span.text.as_str();
            let plain = t
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_.-/".contains(c));
            let first = t.split('/').next().unwrap_or("");
            // `fuzz/corpus/TARGET/`: a component in capitals is a placeholder.
            let placeholder = t.split('/').any(|c| {
                c.chars().any(|c| c.is_ascii_uppercase())
                    && c.chars().all(|c| c.is_ascii_uppercase() || c == '_')
            });
            if plain
                && !placeholder
                && t.contains('/')
                && top.iter().any(|d| d == first)
                && !root.join(t).exists()
            {
                problems.push(Problem {
                    file: doc.path.clone(),
                    line: span.line,
                    what: format!("`{t}`: no such file or directory in the repository"),
                });
            }
        }
    }
    problems
}

/// The keys of the scenario format ([`hnav_runtime::scenario::KEYS`], as `table.key`) that
/// `text` does not name: a table as `[table]` or `[[table]]`, any other key as `key =` or
/// in a code span.
pub fn missing_keys(text: &str) -> Vec<String> {
    let mut missing = Vec::new();
    for (table, keys) in hnav_runtime::scenario::KEYS {
        for key in *keys {
            let named = if table.is_empty() && !["name", "allow_unreachable"].contains(key) {
                text.contains(&format!("[{key}]")) || text.contains(&format!("[[{key}]]"))
            } else {
                text.contains(&format!("{key} =")) || text.contains(&format!("`{key}`"))
            };
            if !named {
                missing.push(format!("{table}.{key}"));
            }
        }
    }
    missing
}

/// The ```toml block of a Rust file's module docs (`//!` lines), without the `//! `.
pub fn module_doc_toml(rust: &str) -> String {
    let mut out = String::new();
    let mut inside = false;
    for line in rust.lines() {
        let Some(doc) = line.strip_prefix("//!") else {
            continue;
        };
        let doc = doc.strip_prefix(' ').unwrap_or(doc);
        match (inside, doc.trim()) {
            (false, "```toml") => inside = true,
            (true, "```") => break,
            (true, _) => {
                out.push_str(doc);
                out.push('\n');
            }
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_named_as_tables_assignments_or_spans() {
        let all: String = hnav_runtime::scenario::KEYS
            .iter()
            .flat_map(|(t, keys)| keys.iter().map(move |k| (t, k)))
            .map(|(t, k)| {
                if t.is_empty() && !["name", "allow_unreachable"].contains(k) {
                    format!("[{k}]\n")
                } else {
                    format!("{k} = 1\n")
                }
            })
            .collect();
        assert!(missing_keys(&all).is_empty());
        let without = all.replace("election_ms = 1", "election = 1");
        assert_eq!(missing_keys(&without), ["coordinator.election_ms"]);
        assert_eq!(
            module_doc_toml("//! a\n//! ```toml\n//! x = 1\n//!\n//! ```\nfn f() {}\n"),
            "x = 1\n\n"
        );
    }

    /// A fake `hnav`: `run` (flags `--force`, `--replicas`) and `log` with `verify`.
    fn fake(_bin: &str, path: &[String]) -> Help {
        let text = match path.iter().map(String::as_str).collect::<Vec<_>>()[..] {
            [] => "Usage: hnav <COMMAND>\n\nCommands:\n  run\n  log\n",
            ["run"] => {
                "Usage: hnav run [OPTIONS] <SCENARIO>\n      --force\n      --replicas <N>\n"
            }
            ["log"] => "Usage: hnav log <COMMAND>\n\nCommands:\n  verify\n",
            ["log", "verify"] => "Usage: hnav log verify <DIR>\n",
            _ => "",
        };
        Help {
            ok: !text.is_empty(),
            text: text.into(),
        }
    }

    fn problems(md: &str) -> Vec<String> {
        let docs = [Doc {
            path: "x.md".into(),
            scan: scan(md),
        }];
        check_commands(&docs, fake)
            .into_iter()
            .map(|p| p.to_string())
            .collect()
    }

    #[test]
    fn unknown_subcommands_and_flags_are_named_with_their_line() {
        assert!(problems("`hnav run a.toml --replicas 3 --force`\n").is_empty());
        assert!(problems("```sh\nhnav log verify DIR\n```\n").is_empty());
        assert_eq!(
            problems("\n`hnav run a.toml --replica 3`\n"),
            ["x.md:2: `hnav run` has no flag `--replica` (not in `hnav run --help`)"]
        );
        assert_eq!(
            problems("`hnav replay DIR`"),
            ["x.md:1: `hnav` has no subcommand `replay`"]
        );
        assert_eq!(
            problems("```sh\ncargo run -p hnav-operator --bin hnav -- log show DIR\n```"),
            ["x.md:2: `hnav log` has no subcommand `show`"]
        );
        assert!(problems("```text\nhnav replay\n```\n`cargo test --release`").is_empty());
    }

    #[test]
    fn flags_are_matched_whole() {
        assert!(lists_flag("  --force\n", "--force"));
        assert!(!lists_flag("  --forced\n", "--force"));
        assert!(!lists_flag("  --force-all\n", "--force"));
    }
}
