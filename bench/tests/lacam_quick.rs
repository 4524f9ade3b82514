//! `hnav-bench lacam --quick --json` through the binary: the search-only benchmark runs its
//! instance (random-32-32-10, 50 agents, 1 s) in a child and prints a row that holds
//! together: a plan found and checked, no sum of costs below the lower bound, the refined
//! plan no worse than the first, peak memory measured. No timing is asserted.

use hnav_bench::mapf::search_only::SearchRow;

mod common;
use common::bench;

#[test]
fn the_quick_search_finds_a_valid_plan_and_refinement_never_worsens_it() {
    let run = bench(&["lacam", "--quick", "--json"]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let rows: Vec<SearchRow> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l:?}: {e}")))
        .collect();
    assert_eq!(rows.len(), 1, "{stdout}");
    let r = &rows[0];
    assert_eq!((r.map.as_str(), r.agents), ("random-32-32-10", 50));
    assert_eq!(r.error, None, "{r:?}");
    assert!(r.valid, "the plan is no solution: {r:?}");
    let (first, soc) = (r.first_soc.unwrap(), r.soc.unwrap());
    assert!(r.lower_bound > 0 && first >= r.lower_bound, "{r:?}");
    assert!(soc >= r.lower_bound && soc <= first, "{r:?}");
    assert!(
        r.first_s.is_some() && r.visited >= r.first_visited.unwrap(),
        "{r:?}"
    );
    assert!(
        r.peak_rss_kib >= r.rss_before_kib && r.peak_rss_kib > 0,
        "{r:?}"
    );
}

#[test]
fn the_table_has_a_row_per_instance_with_the_published_figures() {
    let run = bench(&["lacam", "--quick"]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 3, "{stdout}");
    assert!(lines[0].starts_with("| map | agents |"), "{stdout}");
    assert!(
        lines[2].starts_with("| random-32-32-10 | 50 | 1 |"),
        "{stdout}"
    );
    assert_eq!(
        hnav_bench::mapf::search_only::published("random-32-32-20", 400),
        "LaCAM2 first: SOC 31 373 / LB 9 217 = 3.41 in 31 ms (4-neighbour)"
    );
}
