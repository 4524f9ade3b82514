//! The workspace's import rules, checked over its sources (`tests/house.rs`):
//!
//! - no two files import each other, directly or around a ring of imports;
//! - in a library, a top-level module imports only modules listed below it in the table of
//!   contents of its `lib.rs` (the table whose first column is headed `module`, highest
//!   first), the table lists exactly the modules `lib.rs` declares, and `lib.rs` says what
//!   the crate must not depend on.
//!
//! An import is a `use` of an item of the file's own crate (`crate::`, `super::`, `self::` or
//! a path relative to the module) and any such path written in code; it is resolved through
//! re-exports to the file that defines the item. A parent's `mod child;` is containment, not
//! an import; neither is a file's use of what its own enclosing modules define
//! (`super::Error` in `state.rs` beside its `mod.rs`): a child is a part of its parent.
//!
//! Test code (`#[cfg(test)]` modules, uses and files) is left out: it is not compiled into the
//! product, and a unit test of a low module may well drive it through a higher one that uses
//! it (the waiter's tests build a `Transport`, which hands out waiters). Integration tests,
//! examples and benches are crates of their own, checked for rings among their own files. Other crates (`hnav_runtime::...` from `hnav-agent`) are
//! outside this check: Cargo already refuses a cycle between crates.

mod graph;
mod lex;
mod parse;
mod tree;

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

pub use graph::Ring;
use tree::{Crate, Edge};

/// A top-level module that imports one listed above it in its crate's table of contents.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BackUp {
    /// The importing file.
    pub from: PathBuf,
    /// Its top-level module.
    pub from_module: String,
    /// The imported file.
    pub to: PathBuf,
    /// Its top-level module, listed above `from_module`.
    pub to_module: String,
    /// The names imported.
    pub names: Vec<String>,
}

/// Everything the check found.
#[derive(Debug, Default)]
pub struct Findings {
    /// Rings of files.
    pub rings: Vec<Ring>,
    /// Imports that run back up a table of contents.
    pub back_ups: Vec<BackUp>,
    /// A `lib.rs` without a table of contents that matches its modules, or without the crate's
    /// forbidden dependencies; a file that could not be read.
    pub other: Vec<String>,
}

/// Checks every crate (every target: library, binaries, tests, examples, benches) of the
/// workspace members listed in `ws/Cargo.toml`.
pub fn check(ws: &Path) -> Findings {
    let mut f = Findings::default();
    let mut edges = Vec::new();
    let members = match members(ws) {
        Ok(m) => m,
        Err(e) => {
            f.other.push(e);
            return f;
        }
    };
    for member in members {
        for root in targets(ws, &member) {
            match Crate::read(ws, &root) {
                Ok(c) => {
                    let e = c.edges();
                    if root.ends_with("src/lib.rs") {
                        layering(ws, &c, &root, &e, &mut f);
                    }
                    edges.extend(e);
                }
                Err(e) => f.other.push(e),
            }
        }
    }
    edges.sort();
    edges.dedup();
    f.rings = graph::rings(&edges);
    f
}

/// The root files of a package's targets, by Cargo's conventional layout.
fn targets(ws: &Path, member: &Path) -> Vec<PathBuf> {
    let mut roots = Vec::new();
    for single in ["src/lib.rs", "src/main.rs"] {
        roots.push(member.join(single));
    }
    for dir in ["src/bin", "tests", "examples", "benches"] {
        let Ok(entries) = std::fs::read_dir(ws.join(member).join(dir)) else {
            continue;
        };
        for e in entries.flatten() {
            let name = PathBuf::from(e.file_name());
            if name.extension().is_some_and(|x| x == "rs") {
                roots.push(member.join(dir).join(&name));
            } else {
                roots.push(member.join(dir).join(&name).join("main.rs"));
            }
        }
    }
    roots.retain(|r| ws.join(r).is_file());
    roots.sort();
    roots
}

/// The workspace's `members = [...]`.
fn members(ws: &Path) -> Result<Vec<PathBuf>, String> {
    let toml =
        std::fs::read_to_string(ws.join("Cargo.toml")).map_err(|e| format!("Cargo.toml: {e}"))?;
    let line = toml
        .lines()
        .find(|l| l.trim_start().starts_with("members"))
        .ok_or("Cargo.toml: no `members = [...]` line")?;
    let list = line
        .split_once('[')
        .and_then(|(_, r)| r.split_once(']'))
        .map(|(l, _)| l)
        .ok_or("Cargo.toml: `members` is not a one-line list")?;
    Ok(list
        .split(',')
        .map(|s| s.trim().trim_matches('"'))
        .filter(|s| !s.is_empty())
        .map(PathBuf::from)
        .collect())
}

/// The library's table of contents: its top-level modules, highest first.
fn table_of_contents(lib_rs: &str) -> Vec<String> {
    let rows: Vec<&str> = lib_rs
        .lines()
        .map_while(|l| l.strip_prefix("//!"))
        .map(str::trim)
        .collect();
    let Some(head) = rows.iter().position(|r| r.starts_with("| module |")) else {
        return Vec::new();
    };
    rows[head + 1..]
        .iter()
        .skip_while(|r| r.starts_with("|-") || r.starts_with("| -"))
        .take_while(|r| r.starts_with('|'))
        .filter_map(|r| r.split('`').nth(1))
        // A rustdoc disambiguator (`mod@line_of_sight`, where a function shares the name).
        .map(|m| m.strip_prefix("mod@").unwrap_or(m).to_string())
        .collect()
}

fn layering(ws: &Path, c: &Crate, root: &Path, edges: &[Edge], f: &mut Findings) {
    let shown = root.display();
    let src = std::fs::read_to_string(ws.join(root)).unwrap_or_default();
    if !src
        .lines()
        .any(|l| l.starts_with("//!") && l.contains("Must not depend on"))
    {
        f.other.push(format!("{shown}: does not say what the crate must not depend on (`**Must not depend on**: ...`)"));
    }
    let table = table_of_contents(&src);
    let declared: Vec<String> = c
        .files
        .iter()
        .enumerate()
        .filter(|(i, _)| c.module_path(*i).len() == 1)
        .map(|(i, _)| c.module_path(i)[0].clone())
        .collect();
    let mut listed = table.clone();
    listed.sort();
    let mut sorted = declared.clone();
    sorted.sort();
    if listed != sorted {
        f.other.push(format!("{shown}: the table of contents (`| module |`, highest first) lists {table:?}, the file declares {sorted:?}"));
        return;
    }
    let rank: BTreeMap<&str, usize> = table
        .iter()
        .enumerate()
        .map(|(i, m)| (m.as_str(), i))
        .collect();
    let top: BTreeMap<&PathBuf, &str> = c
        .files
        .iter()
        .enumerate()
        .filter_map(|(i, file)| c.module_path(i).first().map(|m| (&file.path, m.as_str())))
        .collect();
    let mut found: BTreeMap<(PathBuf, PathBuf), BackUp> = BTreeMap::new();
    for e in edges {
        let (Some(&from), Some(&to)) = (top.get(&e.from), top.get(&e.to)) else {
            continue;
        };
        if rank[to] < rank[from] {
            found
                .entry((e.from.clone(), e.to.clone()))
                .or_insert_with(|| BackUp {
                    from: e.from.clone(),
                    from_module: from.into(),
                    to: e.to.clone(),
                    to_module: to.into(),
                    names: Vec::new(),
                })
                .names
                .push(e.name.clone());
        }
    }
    f.back_ups.extend(found.into_values());
}

impl fmt::Display for Ring {
    fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
        let files: Vec<_> = self.files.iter().map(|p| p.display().to_string()).collect();
        writeln!(out, "ring of {} files: {}", files.len(), files.join(", "))?;
        for (from, to, names) in &self.imports {
            writeln!(
                out,
                "    {} -> {}: {}",
                from.display(),
                to.display(),
                names.join(", ")
            )?;
        }
        Ok(())
    }
}

impl fmt::Display for BackUp {
    fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            out,
            "{} ({}) imports {} from {} ({}, listed above it)",
            self.from.display(),
            self.from_module,
            self.names.join(", "),
            self.to.display(),
            self.to_module
        )
    }
}

#[cfg(test)]
mod tests;
