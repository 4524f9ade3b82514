//! Random maps with 0-30 % obstacles: whenever a path exists, the ascent reaches the goal
//! without revisiting a cell, with legal moves only. Also reports how long the paths are
//! compared with the octile shortest path (run with `--nocapture` to see the distribution).

mod common;

use std::sync::Mutex;

use hnav_agent::plan::{plan_query, PlanOptions, PlanStop};
use hnav_agent::Activation;
use hnav_runtime::grid::{octile_shortest_path_len, Cell, CornerCutting, Direction, Grid};
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestRunner};

fn arb_case() -> impl Strategy<Value = (Grid, Cell, Cell, PlanOptions)> {
    (
        2u32..=40,
        2u32..=40,
        0u32..=30,
        any::<u64>(),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|(w, h, pct, seed, tanh, full, cut)| {
            let mut x = seed | 1;
            let mut next = move || {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x
            };
            let blocked: Vec<bool> = (0..w * h).map(|_| next() % 100 < u64::from(pct)).collect();
            let mut g = Grid::from_blocked(w, h, &blocked).unwrap();
            let start = Cell::new(
                (next() % u64::from(w)) as u32,
                (next() % u64::from(h)) as u32,
            );
            let goal = Cell::new(
                (next() % u64::from(w)) as u32,
                (next() % u64::from(h)) as u32,
            );
            g.set_blocked(start, false);
            g.set_blocked(goal, false);
            let options = PlanOptions {
                activation: if tanh {
                    Activation::Tanh
                } else {
                    Activation::Linear
                },
                stop: if full {
                    PlanStop::Full
                } else {
                    PlanStop::Partial
                },
                corner_cutting: if cut {
                    CornerCutting::Allowed
                } else {
                    CornerCutting::Forbidden
                },
            };
            (g, start, goal, options)
        })
}

/// One case: plan, check, and return the length ratio to the octile shortest path.
fn check_case(
    g: &Grid,
    start: Cell,
    goal: Cell,
    options: &PlanOptions,
) -> Result<Option<f64>, TestCaseError> {
    let shortest = octile_shortest_path_len(g, start, goal, options.corner_cutting);
    let r = plan_query(g, start, goal, options).unwrap();
    prop_assert_eq!(r.found, shortest.is_some(), "{}", common::render(g));
    let Some(shortest) = shortest else {
        return Ok(None);
    };
    prop_assert_eq!(r.path.first(), Some(&start));
    prop_assert_eq!(r.path.last(), Some(&goal));
    let mut seen = std::collections::HashSet::new();
    for c in &r.path {
        prop_assert!(seen.insert(*c), "revisits {}\n{}", c, common::render(g));
    }
    for w in r.path.windows(2) {
        let d = Direction::between(w[0], w[1]);
        prop_assert!(d.is_some_and(|d| g.can_move(w[0], d, options.corner_cutting)));
    }
    Ok((shortest > 0.0).then(|| r.length / shortest))
}

/// The property over 64 random cases; prints the length-ratio distribution at the end.
#[test]
fn ascent_reaches_goal_without_revisits() {
    let ratios = Mutex::new(Vec::new());
    let mut runner = TestRunner::new(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(hnav_runtime::hash::test_seed(0xa9e7)),
        ..ProptestConfig::default()
    });
    runner
        .run(&arb_case(), |(g, start, goal, options)| {
            if let Some(ratio) = check_case(&g, start, goal, &options)? {
                let label = format!("{}x{} {start} -> {goal} {options:?}", g.width(), g.height());
                ratios.lock().unwrap().push((ratio, label));
            }
            Ok(())
        })
        .unwrap();
    if let Some(s) = common::ratio_summary(ratios.into_inner().unwrap()) {
        println!("path length / octile shortest over the solvable cases: {s}");
    }
}
