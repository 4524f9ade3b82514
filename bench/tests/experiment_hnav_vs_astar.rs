//! `hnav-bench experiment hnav-vs-astar --quick` through the binary: the report's shape, and
//! the machine-independent figures (`data.figures`) identical on two runs with one seed.
//! Wall times are never asserted.

use serde_json::Value;

mod common;
use common::bench;

fn json(seed: &str) -> Value {
    let out = bench(&[
        "experiment",
        "hnav-vs-astar",
        "--quick",
        "--json",
        "--seed",
        seed,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON document")
}

#[test]
fn quick_json_has_the_tables_figures_and_is_deterministic() {
    let a = json("7");
    assert_eq!(a["name"], "hnav-vs-astar");
    assert_eq!(
        (a["quick"].as_bool(), a["seed"].as_u64()),
        (Some(true), Some(7))
    );
    let data = &a["data"];
    let planners = data["planners"].as_array().unwrap();
    assert_eq!(planners.len(), 5);
    assert_eq!(planners[0], "astar");
    let tasks = data["figures"]["tasks"].as_array().unwrap();
    assert_eq!(tasks.len(), 4);
    let paper_hnav_ms: Vec<f64> = tasks
        .iter()
        .map(|t| t["paper"]["hnav_ms"].as_f64().unwrap())
        .collect();
    assert_eq!(paper_hnav_ms, [7.22, 6.95, 7.81, 8.23]);
    for t in tasks {
        let ps = t["planners"].as_array().unwrap();
        assert_eq!(ps.len(), 5);
        assert!(ps
            .iter()
            .all(|p| p["found"] == true && p["steps"].as_u64() > Some(0)));
        // Figures only: a timing in them would make the determinism check below flaky.
        assert!(ps.iter().all(|p| p.get("median_us").is_none()));
    }
    let scen = data["figures"]["movingai"].as_array().unwrap();
    assert_eq!(scen.len(), 3);
    for s in scen {
        assert_eq!(s["entries"].as_array().unwrap().len(), 4);
        assert_eq!(s["summaries"].as_array().unwrap().len(), 5);
        // A* is the oracle's algorithm: every entry optimal.
        assert_eq!(s["summaries"][0]["optimal"], s["summaries"][0]["queries"]);
    }
    let timings = data["timings"]["tasks"].as_array().unwrap();
    assert_eq!(timings.len(), 4);
    assert!(timings[0]["planners"][0]["median_us"].as_f64().is_some());

    let b = json("7");
    assert_eq!(
        a["data"]["figures"], b["data"]["figures"],
        "same seed, same figures"
    );
    let c = json("8");
    let lines = |v: &Value| v["data"]["figures"]["movingai"][0]["entries"].clone();
    assert_ne!(lines(&a), lines(&c), "another seed samples other entries");
    assert_eq!(a["data"]["figures"]["tasks"], c["data"]["figures"]["tasks"]);
}

#[test]
fn quick_markdown_prints_ours_beside_the_papers() {
    let out = bench(&["experiment", "hnav-vs-astar", "--quick"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for want in [
        "## Table 3-8",
        "| 26.37 (33) | 7.22 (33) | 0.274 |",
        "## Table 3-9",
        "| paper | | | 1.3-3 | 1.3-3 | up to 2.5 | 1.5-2.5 |",
        "`random-32-32-20-random-1.scen` | hnav tanh full |",
    ] {
        assert!(text.contains(want), "missing {want:?} in\n{text}");
    }
    let listed = bench(&["experiment", "list"]);
    assert!(String::from_utf8_lossy(&listed.stdout).contains("hnav-vs-astar"));
    let unknown = bench(&["experiment", "no-such-experiment"]);
    assert!(!unknown.status.success());
    assert!(String::from_utf8_lossy(&unknown.stderr).contains("hnav-vs-astar"));
}
