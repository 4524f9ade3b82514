//! The workspace's import rules (issue 33): no two files import each other, directly or around
//! a ring, and no module imports one listed above it in its crate's `lib.rs` table of contents.
//! The rules and what counts as an import: `hnav_tests::house`.

use std::path::Path;

use hnav_tests::house::{check, BackUp, Ring};
use hnav_tests::swarm::repo_root;

/// Rings and imports back up known and accepted, with who owns breaking them. Each entry must
/// still be found (a stale entry fails the test). Empty: issue 33 broke every one of them.
const KNOWN_RINGS: &[(&str, &[&str])] = &[];
/// (owner, importing file, imported file)
const KNOWN_BACK_UPS: &[(&str, &str, &str)] = &[];

fn ring_is_known(r: &Ring) -> bool {
    KNOWN_RINGS.iter().any(|(_, files)| {
        r.files
            .iter()
            .map(|p| p.as_path())
            .eq(files.iter().map(Path::new))
    })
}

fn back_up_is_known(b: &BackUp) -> bool {
    KNOWN_BACK_UPS
        .iter()
        .any(|(_, from, to)| b.from == Path::new(from) && b.to == Path::new(to))
}

#[test]
fn no_file_imports_another_that_imports_it_back_and_no_import_runs_up_a_table() {
    let f = check(&repo_root());
    let mut report = String::new();
    for r in f.rings.iter().filter(|r| !ring_is_known(r)) {
        report += &r.to_string();
    }
    for b in f.back_ups.iter().filter(|b| !back_up_is_known(b)) {
        report += &b.to_string();
    }
    for o in &f.other {
        report += &format!("{o}\n");
    }
    for (owner, files) in KNOWN_RINGS {
        if !f.rings.iter().any(|r| {
            r.files
                .iter()
                .map(|p| p.as_path())
                .eq(files.iter().map(Path::new))
        }) {
            report +=
                &format!("KNOWN_RINGS: {files:?} ({owner}) is gone: remove it from the list\n");
        }
    }
    for (owner, from, to) in KNOWN_BACK_UPS {
        if !f
            .back_ups
            .iter()
            .any(|b| b.from == Path::new(from) && b.to == Path::new(to))
        {
            report += &format!(
                "KNOWN_BACK_UPS: {from} -> {to} ({owner}) is gone: remove it from the list\n"
            );
        }
    }
    assert!(report.is_empty(), "\n{report}");
}
