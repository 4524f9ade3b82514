//! `hnav-bench experiment ga-fuzzy --quick --json` through the binary: every map and the
//! seed's setting with all three planners, rates inside [0, 1], A* solving every `.scen`
//! task, no route shorter than the optimal, and the same figures twice for one seed (the
//! wall times apart, never compared).

use serde_json::Value;

mod common;
use common::bench;

const SETTINGS: [&str; 4] = [
    "random-32-32-10",
    "random-32-32-20",
    "warehouse-10-20-10-2-1",
    "seed 004 setting (moving robots)",
];
const PLANNERS: [&str; 3] = ["ga-fuzzy", "astar", "hnav"];

fn json(seed: &str) -> Value {
    let out = bench(&[
        "experiment",
        "ga-fuzzy",
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

fn rate(v: &Value, k: &str, n: &str, ci: &str) {
    let (k, n) = (v[k].as_u64().unwrap(), v[n].as_u64().unwrap());
    let (lo, hi) = (v[ci]["lo"].as_f64().unwrap(), v[ci]["hi"].as_f64().unwrap());
    let p = k as f64 / n as f64;
    assert!(n > 0 && k <= n, "{v}");
    assert!(0.0 <= lo && lo <= p && p <= hi && hi <= 1.0, "{v}");
}

#[test]
fn quick_json_covers_every_map_and_planner_and_is_deterministic() {
    let a = json("3");
    assert_eq!(a["name"], "ga-fuzzy");
    assert_eq!(
        (a["quick"].as_bool(), a["seed"].as_u64()),
        (Some(true), Some(3))
    );
    let figures = &a["data"]["figures"];
    let summaries = figures["summaries"].as_array().unwrap();
    assert_eq!(summaries.len(), SETTINGS.len() * PLANNERS.len());
    for (i, m) in summaries.iter().enumerate() {
        let (setting, planner) = (SETTINGS[i / 3], PLANNERS[i % 3]);
        assert_eq!(
            (m["setting"].as_str(), m["planner"].as_str()),
            (Some(setting), Some(planner))
        );
        rate(m, "found", "tasks", "found_ci");
        rate(m, "collision_free", "tasks", "collision_free_ci");
        if planner == "astar" && !setting.starts_with("seed") {
            assert_eq!(m["found"], m["tasks"], "A* solves every scen task: {m}");
        }
        if let Some(r) = m["length_ratio"].as_f64() {
            let ci = &m["length_ratio_ci"];
            let (lo, hi) = (ci["lo"].as_f64().unwrap(), ci["hi"].as_f64().unwrap());
            assert!(r >= 1.0 - 1e-6 && lo <= r + 1e-12 && r <= hi + 1e-12, "{m}");
        }
    }
    // Every answer on every task: nothing shorter than the optimal; a static map has no
    // collisions; the GA never collides on the seed's setting here (its fitness forbids it).
    let settings = figures["settings"].as_array().unwrap();
    assert_eq!(settings.len(), SETTINGS.len());
    for s in settings {
        let tasks = s["tasks"].as_array().unwrap();
        assert!(!tasks.is_empty(), "{s}");
        let moving = s["setting"].as_str().unwrap().starts_with("seed");
        for t in tasks {
            let optimal = t["optimal"].as_f64().unwrap();
            for (k, ans) in t["answers"].as_array().unwrap().iter().enumerate() {
                if ans["found"].as_bool().unwrap() {
                    let len = ans["length"].as_f64().unwrap();
                    assert!(len >= optimal - 1e-6, "{} {t}", PLANNERS[k]);
                    assert!(
                        ans["ticks"].as_f64().unwrap() + 1e-9 >= len / 2f64.sqrt(),
                        "{t}"
                    );
                }
                if !moving {
                    assert_eq!(ans["conflicts"].as_u64(), Some(0), "{t}");
                }
            }
        }
    }
    let md = a["markdown"].as_str().unwrap();
    assert!(md.contains("publishes no result table"), "{md}");
    assert_eq!(
        a["data"]["figures"],
        json("3")["data"]["figures"],
        "one seed, one set of figures"
    );
    assert_ne!(
        figures,
        &json("4")["data"]["figures"],
        "another seed, other tasks"
    );
}
