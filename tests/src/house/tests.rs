use std::path::{Path, PathBuf};

use super::*;

fn workspace(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temporary directory");
    for (path, text) in files {
        let p = dir.path().join(path);
        std::fs::create_dir_all(p.parent().expect("a parent")).expect("mkdir");
        std::fs::write(p, text).expect("write");
    }
    dir
}

const LIB: &str = "//! **Must not depend on**: anything.\n//!\n//! | module | what |\n//! |---|---|\n\
                   //! | [`top`] | above |\n//! | [`low`] | below |\n\npub mod low;\npub mod top;\npub use low::Low;\n";

#[test]
fn a_clean_crate_has_no_findings_and_re_exports_are_followed_to_their_file() {
    let ws = workspace(&[
        ("Cargo.toml", "[workspace]\nmembers = [\"a\"]\n"),
        ("a/src/lib.rs", LIB),
        // `crate::Low` is `low.rs`'s item re-exported by `lib.rs`: no ring through `lib.rs`.
        (
            "a/src/top.rs",
            "use crate::Low;\npub fn f() -> Low { crate::low::make() }\n",
        ),
        (
            "a/src/low.rs",
            "pub struct Low;\npub fn make() -> Low { Low }\n#[cfg(test)]\nmod tests;\n",
        ),
        (
            "a/src/low/tests.rs",
            "use super::*;\n#[test]\nfn t() { make(); }\n",
        ),
    ]);
    let f = check(ws.path());
    assert!(
        f.rings.is_empty() && f.back_ups.is_empty() && f.other.is_empty(),
        "{f:?}"
    );
}

#[test]
fn a_ring_and_an_import_back_up_the_table_are_both_named() {
    let ws = workspace(&[
        ("Cargo.toml", "[workspace]\nmembers = [\"a\"]\n"),
        ("a/src/lib.rs", LIB),
        (
            "a/src/top.rs",
            "pub const LIMIT: u32 = 3;\npub fn f() -> u32 { crate::low::g() }\n",
        ),
        (
            "a/src/low.rs",
            "use crate::{top::{LIMIT}};\npub struct Low;\npub fn g() -> u32 { LIMIT }\n",
        ),
    ]);
    let f = check(ws.path());
    let files: Vec<PathBuf> = vec!["a/src/low.rs".into(), "a/src/top.rs".into()];
    assert_eq!(f.rings.len(), 1, "{f:?}");
    assert_eq!(f.rings[0].files, files);
    assert_eq!(f.back_ups.len(), 1, "{f:?}");
    let b = &f.back_ups[0];
    assert_eq!(
        (
            b.from_module.as_str(),
            b.to_module.as_str(),
            b.names.clone()
        ),
        ("low", "top", vec!["LIMIT".to_string()])
    );
    assert!(
        f.rings[0]
            .to_string()
            .contains("a/src/low.rs -> a/src/top.rs: LIMIT"),
        "{}",
        f.rings[0]
    );
}

#[test]
fn a_child_using_its_parent_and_test_code_make_no_ring_but_siblings_in_a_binary_do() {
    let ws = workspace(&[
        ("Cargo.toml", "[workspace]\nmembers = [\"a\"]\n"),
        ("a/src/main.rs", "mod run;\nfn main() { run::go(); }\n"),
        (
            "a/src/run/mod.rs",
            "mod host;\nmod slots;\npub struct Part;\npub fn go() { host::start(); }\n",
        ),
        // `super::Part` is the parent's: containment. The test module's import is left out.
        (
            "a/src/run/host.rs",
            "pub fn start() { let _ = super::Part; crate::run::slots::n(); }\n\
             #[cfg(test)]\nmod tests { use crate::run::slots::Spy; }\n",
        ),
        (
            "a/src/run/slots.rs",
            "pub fn n() {}\npub struct Spy;\n#[cfg(test)]\nuse super::host::start;\n",
        ),
    ]);
    let f = check(ws.path());
    assert!(f.rings.is_empty(), "{f:?}");
    std::fs::write(
        ws.path().join("a/src/run/slots.rs"),
        "pub fn n() { super::host::start() }\n",
    )
    .expect("write");
    let f = check(ws.path());
    assert_eq!(f.rings.len(), 1, "{f:?}");
    assert_eq!(
        f.rings[0].files,
        vec![
            Path::new("a/src/run/host.rs"),
            Path::new("a/src/run/slots.rs")
        ]
    );
}

#[test]
fn a_table_that_misses_a_module_or_a_crate_that_names_no_forbidden_dependency_is_reported() {
    let ws = workspace(&[
        ("Cargo.toml", "[workspace]\nmembers = [\"a\"]\n"),
        ("a/src/lib.rs", "//! | module | what |\n//! |---|---|\n//! | [`low`] | below |\npub mod low;\npub mod extra;\n"),
        ("a/src/low.rs", ""),
        ("a/src/extra.rs", ""),
    ]);
    let f = check(ws.path());
    assert_eq!(f.other.len(), 2, "{f:?}");
    assert!(
        f.other.iter().any(|o| o.contains("must not depend on")),
        "{f:?}"
    );
    assert!(f.other.iter().any(|o| o.contains("\"extra\"")), "{f:?}");
}
