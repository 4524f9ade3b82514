//! `hnav log verify|show`: exit codes and output on intact, torn, corrupt, unreadable and
//! garbage logs.

use std::fs;
use std::io::Write as _;
use std::path::Path;
use std::process::Command;

use hnav_runtime::consensus_log::segment_path;

use super::fixtures::{every_kind, write_log, ONE_SEGMENT};

fn hnav(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hnav"))
        .args(args)
        .output()
        .unwrap();
    let text = |b: Vec<u8>| String::from_utf8_lossy(&b).into_owned();
    (
        out.status.code().unwrap_or(-1),
        text(out.stdout),
        text(out.stderr),
    )
}

fn p(dir: &Path) -> &str {
    dir.to_str().unwrap()
}

#[test]
fn hnav_log_verify_and_show_exit_codes() {
    let tmp = tempfile::tempdir().unwrap();
    let good = tmp.path().join("good");
    let records = every_kind();
    let at = write_log(&good, &records, ONE_SEGMENT);

    let (code, out, _) = hnav(&["log", "verify", p(&good)]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("intact"), "{out}");

    let (code, out, _) = hnav(&["log", "show", p(&good)]);
    assert_eq!(code, 0);
    assert_eq!(out.lines().count(), records.len());
    assert!(
        out.contains("accept a0->[2, 2] block a1 crossing (N,NE)"),
        "{out}"
    );
    assert!(out.lines().last().unwrap().contains("all-at-goal"), "{out}");

    let (code, out, _) = hnav(&["log", "show", "--json", p(&good)]);
    assert_eq!(code, 0);
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), records.len());
    assert_eq!(lines[1]["kind"], "round");
    assert_eq!(lines[1]["round"], 1);
    assert_eq!(lines[1]["offset"], at[1].1);

    // Torn: verify 1, show 0 with a note.
    let torn = tmp.path().join("torn");
    write_log(&torn, &records, ONE_SEGMENT);
    let seg = segment_path(&torn, 0);
    let len = fs::metadata(&seg).unwrap().len();
    fs::OpenOptions::new()
        .write(true)
        .open(&seg)
        .unwrap()
        .set_len(len - 2)
        .unwrap();
    assert_eq!(hnav(&["log", "verify", p(&torn)]).0, 1);
    let (code, out, err) = hnav(&["log", "show", p(&torn)]);
    assert_eq!((code, out.lines().count()), (0, records.len() - 1));
    assert!(err.contains("torn tail"), "{err}");

    // Corrupt: both 1.
    let corrupt = tmp.path().join("corrupt");
    write_log(&corrupt, &records, ONE_SEGMENT);
    let seg = segment_path(&corrupt, 0);
    let mut bytes = fs::read(&seg).unwrap();
    bytes[at[2].1 + 9] ^= 0xFF;
    fs::write(&seg, bytes).unwrap();
    let (code, out, _) = hnav(&["log", "verify", p(&corrupt)]);
    assert_eq!(code, 1);
    assert!(out.contains(&format!("byte {}", at[2].1)), "{out}");
    let (code, out, err) = hnav(&["log", "show", p(&corrupt)]);
    assert_eq!((code, out.lines().count()), (1, 2));
    assert!(err.contains("corrupt"), "{err}");

    // Unreadable: 2.
    let missing = tmp.path().join("missing");
    assert_eq!(hnav(&["log", "verify", p(&missing)]).0, 2);
    assert_eq!(hnav(&["log", "show", p(&missing)]).0, 2);
    assert_eq!(hnav(&["log", "verify", p(tmp.path())]).0, 2);

    // Garbage after a new log's magic never panics.
    let garbage = tmp.path().join("garbage");
    write_log(&garbage, &[], ONE_SEGMENT);
    let junk: Vec<u8> = (0..4000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    fs::OpenOptions::new()
        .append(true)
        .open(segment_path(&garbage, 0))
        .unwrap()
        .write_all(&junk)
        .unwrap();
    for args in [
        &["log", "verify"][..],
        &["log", "show"],
        &["log", "show", "--json"],
    ] {
        let mut args = args.to_vec();
        args.push(p(&garbage));
        let (code, _, err) = hnav(&args);
        assert!(code == 1 || code == 0, "{args:?}: {code} {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}
