//! `hnav-bench experiment dynamic --quick --json` through the binary: the three variants run
//! the same world to the end, each repairs the way it is told to, and the coordinator logs
//! the changes the agents saw.

use serde_json::Value;

mod common;
use common::bench_within;

#[test]
fn the_quick_dynamic_experiment_runs_every_variant_on_the_same_world() {
    // Three lockstep runs of six robots: about 15 s on two idle cores.
    let limit = std::time::Duration::from_secs(240);
    let v = quick_json(&[], limit);
    let rows = v["data"].as_array().expect("rows");
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["variant"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["partial", "rebuild", "all-knowing"], "{v}");
    let optimal = rows[0]["optimal_sum"].as_f64().unwrap();
    for r in rows {
        let o = &r["outcome"];
        assert_eq!(
            r["optimal_sum"].as_f64(),
            Some(optimal),
            "one world for all: {r}"
        );
        assert!(
            o["at_goal"].as_u64().unwrap() <= r["robots"].as_u64().unwrap(),
            "{r}"
        );
        assert!(o["rounds"].as_u64().unwrap() > 0, "{r}");
        assert!(o["length_sum"].as_f64().unwrap() >= optimal * 0.5, "{r}");
        assert!(
            o["map_changes"].as_u64().unwrap() > 0,
            "a door was seen: {r}"
        );
    }
    let repairs = |i: usize, kind: &str| rows[i]["outcome"]["repairs"][kind].as_u64().unwrap();
    assert!(
        repairs(0, "partial") > 0,
        "the partial variant corrects partially"
    );
    assert_eq!(
        repairs(1, "partial"),
        0,
        "the rebuild variant only rebuilds"
    );
    assert!(repairs(1, "rebuild") > 0);
    let md = v["markdown"].as_str().unwrap();
    assert!(md.contains("| 6 | all-knowing | "), "{md}");
    assert!(
        md.contains("Lockstep, `pibt` rules"),
        "the default rules: {md}"
    );
}

#[test]
fn unknown_rules_or_variants_are_refused_with_the_known_ones_before_anything_runs() {
    let limit = std::time::Duration::from_secs(30);
    for (flag, value, refusal) in [
        (
            "--rules",
            "pibtt",
            "no rules called \"pibtt\"; the rules are dissertation, pibt, lacam",
        ),
        (
            "--variant",
            "both",
            "no variant called \"both\"; the variants are partial, rebuild, all-knowing",
        ),
    ] {
        let out = bench_within(&["experiment", "dynamic", "--quick", flag, value], limit);
        assert_eq!(out.status.code(), Some(2), "{flag} {value}: a usage error");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(refusal), "{err}");
        assert!(out.stdout.is_empty(), "nothing ran");
    }
}

#[test]
fn one_variant_runs_alone_when_asked() {
    // One lockstep run of six robots: about 6 s on two idle cores.
    let limit = std::time::Duration::from_secs(120);
    let v = quick_json(&["--variant", "rebuild"], limit);
    let rows = v["data"].as_array().expect("rows");
    assert_eq!(rows.len(), 1, "{v}");
    assert_eq!(rows[0]["variant"], "rebuild", "{v}");
    assert_eq!(rows[0]["outcome"]["repairs"]["partial"], 0, "{v}");
}

/// `hnav-bench experiment dynamic --quick --json` with `extra` arguments: its one JSON
/// document, after a successful exit.
fn quick_json(extra: &[&str], limit: std::time::Duration) -> Value {
    let mut args = vec!["experiment", "dynamic", "--quick", "--json"];
    args.extend_from_slice(extra);
    let out = bench_within(&args, limit);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON document")
}
