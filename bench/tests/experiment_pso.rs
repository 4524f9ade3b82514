//! `hnav-bench experiment pso --quick` through the binary: the report's shape (the nine
//! settings of both tables and of Table 2 with the corner analysis, beside the paper's
//! figures, both step counts, intervals that bracket their estimates) and the
//! same JSON twice for one seed, another for another seed; the ablation's tables and their
//! invariants (not the paper's direction). Nothing here is a timing.

use serde_json::Value;

mod common;
use common::bench;

fn json(seed: &str) -> Value {
    let out = bench(&["experiment", "pso", "--quick", "--json", "--seed", seed]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON document")
}

#[test]
fn quick_json_has_both_tables_and_is_deterministic() {
    let a = json("3");
    assert_eq!(a["name"], "pso");
    assert_eq!(
        (a["quick"].as_bool(), a["seed"].as_u64()),
        (Some(true), Some(3))
    );
    let data = &a["data"];
    let runs = data["runs_per_setting"].as_u64().unwrap();
    assert!(runs > 0);
    let rows = data["rows"].as_array().unwrap();
    let settings: Vec<(String, u64, f64)> = rows
        .iter()
        .map(|r| {
            (
                r["algorithm"].as_str().unwrap().to_string(),
                r["parameter"].as_u64().unwrap(),
                r["paper_steps"].as_f64().unwrap(),
            )
        })
        .collect();
    let expected = [
        ("original", 1, 183.0),
        ("original", 2, 210.0),
        ("original", 4, 155.0),
        ("modified-corners", 5, 159.0),
        ("modified-corners", 7, 100.0),
        ("modified-corners", 10, 93.0),
        ("modified", 5, 159.0),
        ("modified", 7, 100.0),
        ("modified", 10, 93.0),
    ];
    assert_eq!(settings.len(), expected.len(), "{settings:?}");
    for ((alg, p, steps), (ea, ep, es)) in settings.iter().zip(expected) {
        assert_eq!((alg.as_str(), *p, *steps), (ea, ep, es));
    }
    for r in rows {
        assert_eq!(r["runs"].as_u64(), Some(runs));
        let lo = r["success_ci"]["lo"].as_f64().unwrap();
        let hi = r["success_ci"]["hi"].as_f64().unwrap();
        assert!(0.0 <= lo && lo <= hi && hi <= 1.0, "{r}");
        if let (Some(m), Some(slo), Some(shi)) = (
            r["mean_steps"].as_f64(),
            r["steps_ci"]["lo"].as_f64(),
            r["steps_ci"]["hi"].as_f64(),
        ) {
            assert!(slo <= m && m <= shi, "{r}");
        }
        // The other count: every run, a never-reached one at 1200, so never below the mean
        // over successes.
        let all = r["all_runs_steps"].as_f64().unwrap();
        let (alo, ahi) = (
            r["all_runs_ci"]["lo"].as_f64().unwrap(),
            r["all_runs_ci"]["hi"].as_f64().unwrap(),
        );
        assert!(alo <= all && all <= ahi && ahi <= 1200.0, "{r}");
    }
    // The paired steps: nine setting pairs and the pooled row per corner rule, each on at
    // most the tasks there are, its mean difference the difference of its means.
    let pairs = data["paired_steps"].as_array().unwrap();
    assert_eq!(pairs.len(), 2 * (9 + 1), "{pairs:?}");
    for (i, p) in pairs.iter().enumerate() {
        let rule = if i < 10 {
            "modified"
        } else {
            "modified-corners"
        };
        assert_eq!(p["modified"], rule, "{p}");
        assert_eq!(p["r_max"].is_null(), i % 10 == 9, "{p}");
        assert_eq!(p["all_runs"]["n"].as_u64(), Some(runs), "every task: {p}");
        let s = &p["steps"];
        assert!(s["n"].as_u64().unwrap() <= runs, "{p}");
        if let (Some(a), Some(b), Some(d)) = (
            s["mean_a"].as_f64(),
            s["mean_b"].as_f64(),
            s["mean_diff"].as_f64(),
        ) {
            assert!((b - a - d).abs() < 1e-9, "{p}");
            let (lo, hi) = (
                s["diff_ci"]["lo"].as_f64().unwrap(),
                s["diff_ci"]["hi"].as_f64().unwrap(),
            );
            assert!(lo <= d + 1e-9 && d <= hi + 1e-9, "{p}");
        }
    }
    ablation_has_its_shape(&data["ablation"], runs);
    let md = a["markdown"].as_str().unwrap();
    assert!(md.contains("Paired steps"), "{md}");
    assert!(md.contains("Ablation") && md.contains("How steps are counted"));
    assert!(
        md.contains("Table 1: original algorithm") && md.contains("Table 2: modified algorithm")
    );
    assert_eq!(a, json("3"), "one seed, one report");
    assert_ne!(a["data"], json("4")["data"], "another seed, other maps");
}

/// The ablation: eight variants (the original first), each pooled over three settings; the
/// task splits cover every task once per corner rule; the counting table has the nine
/// settings of the tables. Checks shapes and invariants only, never which way a result goes.
fn ablation_has_its_shape(ab: &Value, runs: u64) {
    let rows = ab["rows"].as_array().unwrap();
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["algorithm"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "original",
            "modified-corners",
            "modified",
            "no-virtual-obstacles",
            "fixed-weights-corners",
            "fixed-weights",
            "original-blocked-move-corners",
            "original-blocked-move"
        ]
    );
    for r in rows {
        assert_eq!(r["runs"].as_u64(), Some(3 * runs), "{r}");
        assert!(r["successes"].as_u64().unwrap() <= 3 * runs, "{r}");
        let (lo, hi) = (
            r["success_ci"]["lo"].as_f64().unwrap(),
            r["success_ci"]["hi"].as_f64().unwrap(),
        );
        assert!(0.0 <= lo && lo <= hi && hi <= 1.0, "{r}");
        let obstacles = r["obstacles_per_run"].as_f64().unwrap();
        assert!(r["detections_per_run"].as_f64().unwrap() >= 0.0 && obstacles >= 0.0);
        let places = !r["corner_rule"].is_null();
        assert!(
            places || obstacles == 0.0,
            "no obstacle without a corner rule: {r}"
        );
        let reference = r["algorithm"] == "original";
        for key in ["steps", "vs_r_max_1", "common", "all_runs", "route"] {
            let p = &r[key];
            assert_eq!(p.is_null(), reference, "{key}: {r}");
            if reference {
                continue;
            }
            let n = p["n"].as_u64().unwrap();
            assert!(n <= runs, "{key}: {r}");
            if let (Some(a), Some(b), Some(d)) = (
                p["mean_a"].as_f64(),
                p["mean_b"].as_f64(),
                p["mean_diff"].as_f64(),
            ) {
                assert!((b - a - d).abs() < 1e-9, "{key}: {r}");
                let (lo, hi) = (
                    p["diff_ci"]["lo"].as_f64().unwrap(),
                    p["diff_ci"]["hi"].as_f64().unwrap(),
                );
                assert!(lo <= d + 1e-9 && d <= hi + 1e-9, "{key}: {r}");
            }
        }
        if !reference {
            // Every run has an iteration count, so the all-runs comparison keeps every task.
            assert_eq!(r["all_runs"]["n"].as_u64(), Some(runs), "{r}");
            assert_eq!(r["route"]["n"], r["steps"]["n"], "{r}");
        }
    }
    let splits = ab["splits"].as_array().unwrap();
    assert_eq!(splits.len(), 8);
    for rule in ["modified", "modified-corners"] {
        let mine: Vec<&Value> = splits.iter().filter(|x| x["modified"] == rule).collect();
        let total: u64 = mine.iter().map(|x| x["tasks"].as_u64().unwrap()).sum();
        assert_eq!(total, runs, "{rule}: every task in one group");
        let both = mine.iter().find(|x| x["group"] == "both solve").unwrap();
        let by_stall: u64 = ab["stall_splits"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|x| x["variant"] == rule)
            .map(|x| x["steps"]["n"].as_u64().unwrap())
            .sum();
        assert_eq!(by_stall, both["tasks"].as_u64().unwrap(), "{rule}");
    }
    assert_eq!(ab["stall_splits"].as_array().unwrap().len(), 6);
    let counting = ab["counting"].as_array().unwrap();
    assert_eq!(counting.len(), 9);
    for c in counting {
        let all = c["all_runs_mean"].as_f64().unwrap();
        assert!((0.0..=1200.0).contains(&all), "{c}");
        // A run that never reaches counts 1200, at least any reached run's count.
        if let Some(reached) = c["reached_mean"].as_f64() {
            assert!(reached <= all + 1e-9, "{c}");
        }
        assert!(c["paper_implied_reached"].as_f64().unwrap() > 0.0, "{c}");
    }
}
