//! The search on its own ([`standalone`](super::standalone)): its plans are MAPF solutions,
//! LaCAM*'s refinement never makes them worse, and without refinement the search is plain
//! LaCAM, first plan for first plan.

use std::path::PathBuf;

use hnav_runtime::grid::{read_map_file, read_scen_file, Cell, Grid};

use super::search::{Budget, SearchError};
use super::standalone::{Instance, PlanError};
use crate::conflict::pibt::tests::props;
use crate::conflict::Options;

fn c(x: u32, y: u32) -> Cell {
    Cell::new(x, y)
}

/// The first `n` entries of a `.scen` of `maps/`.
fn movingai(stem: &str, n: usize, options: Options) -> Instance {
    let maps = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../maps");
    let grid = read_map_file(maps.join(format!("{stem}.map"))).unwrap();
    let scen = read_scen_file(maps.join(format!("{stem}-random-1.scen"))).unwrap();
    let (starts, goals): (Vec<Cell>, Vec<Cell>) =
        scen.entries[..n].iter().map(|e| (e.start, e.goal)).unzip();
    Instance::new(&grid, &starts, &goals, options).unwrap()
}

fn refining(iterations: usize) -> Budget {
    Budget {
        refine: iterations,
        ..Budget::default()
    }
}

#[test]
fn plans_are_solutions_and_refinement_never_makes_them_worse() {
    for options in [
        Options::default(),
        Options {
            sweep: false,
            ..Options::default()
        },
    ] {
        let inst = movingai("random-32-32-10", 50, options);
        let plain = inst.solve(Budget::default(), None).unwrap();
        inst.check(&plain.configs).unwrap();
        let lb = inst.lower_bound();
        let soc = inst.sum_of_costs(&plain.configs);
        assert_eq!(plain.first_cost, soc);
        assert!(soc >= lb, "{soc} < {lb}");
        let star = inst.solve(refining(20_000), None).unwrap();
        inst.check(&star.configs).unwrap();
        let refined = inst.sum_of_costs(&star.configs);
        assert!(refined <= star.first_cost && refined >= lb, "{refined}");
        // Before its first solution LaCAM* searches as LaCAM does: the same configurations
        // (its first plan may be rewired to another way through them).
        assert_eq!(star.first_visited, plain.visited);
        eprintln!(
            "{options:?}: LB {lb}, LaCAM {soc}, LaCAM* first {} then {refined} ({} configurations)",
            star.first_cost, star.visited
        );
    }
}

#[test]
fn random_instances_are_solved_validly_with_and_without_refinement() {
    let mut solved = 0;
    for seed in 0..40u64 {
        let Some(props::Instance {
            grid,
            starts,
            goals,
            ..
        }) = props::instance(seed)
        else {
            continue;
        };
        let Ok(inst) = Instance::new(&grid, &starts, &goals, Options::default()) else {
            continue;
        };
        let Ok(plain) = inst.solve(Budget::default(), None) else {
            continue;
        };
        inst.check(&plain.configs)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let star = inst.solve(refining(5_000), None).unwrap();
        inst.check(&star.configs)
            .unwrap_or_else(|e| panic!("seed {seed}, refined: {e}"));
        let b = inst.sum_of_costs(&star.configs);
        assert_eq!(star.first_visited, plain.visited, "seed {seed}");
        assert!(b <= star.first_cost, "seed {seed}");
        assert!(b >= inst.lower_bound(), "seed {seed}");
        solved += 1;
    }
    assert!(solved >= 20, "only {solved} instances solved");
}

#[test]
fn a_small_instance_is_refined_to_a_proven_optimum() {
    // Two agents exchanging the ends of a 3 x 2 room: with nothing left to search LaCAM* has
    // proven its plan optimal.
    let g = Grid::new(3, 2).unwrap();
    let inst = Instance::new(
        &g,
        &[c(0, 0), c(2, 0)],
        &[c(2, 0), c(0, 0)],
        Options::default(),
    )
    .unwrap();
    let plan = inst.solve(refining(1_000_000), None).unwrap();
    inst.check(&plan.configs).unwrap();
    assert!(
        plan.optimal,
        "the search ran out before it proved the optimum"
    );
    assert!(inst.sum_of_costs(&plan.configs) >= inst.lower_bound());
}

#[test]
fn a_past_deadline_ends_the_search_without_a_plan() {
    let inst = movingai("random-32-32-10", 50, Options::default());
    let err = inst
        .solve(Budget::default(), Some(std::time::Instant::now()))
        .err()
        .unwrap();
    assert_eq!(err, SearchError::Deadline { configurations: 1 });
}

#[test]
fn the_check_refuses_jumps_swaps_and_shared_cells() {
    let g = Grid::new(3, 1).unwrap();
    let inst = Instance::new(
        &g,
        &[c(0, 0), c(1, 0)],
        &[c(1, 0), c(0, 0)],
        Options::default(),
    )
    .unwrap();
    let plan = |steps: &[[u32; 2]]| -> Vec<Box<[u32]>> {
        steps
            .iter()
            .map(|s| s.to_vec().into_boxed_slice())
            .collect()
    };
    assert_eq!(
        inst.check(&plan(&[[0, 1], [1, 0]])),
        Err(PlanError::Swap {
            step: 0,
            a: 0,
            b: 1
        })
    );
    assert_eq!(
        inst.check(&plan(&[[0, 1], [1, 1], [1, 0]])),
        Err(PlanError::Vertex {
            step: 1,
            a: 0,
            b: 1
        })
    );
    assert_eq!(
        inst.check(&plan(&[[0, 1], [0, 2], [2, 2], [1, 0]])),
        Err(PlanError::Jump { step: 1, agent: 0 })
    );
    assert_eq!(inst.check(&plan(&[[0, 1]])), Err(PlanError::Ends));
    // No plan exists on a 3-cell line with the agents exchanging their cells.
    assert_eq!(
        inst.solve(refining(10), None).err(),
        Some(SearchError::NoPlan)
    );
}

#[test]
fn a_diagonal_never_cuts_a_blocked_corner() {
    // Corner cutting forbidden: (0, 0) -> (1, 1) past the wall at (1, 0) is no move.
    let g = Grid::from_rows(&[".@", ".."]).unwrap();
    let inst = Instance::new(&g, &[c(0, 0)], &[c(1, 1)], Options::default()).unwrap();
    assert_eq!(
        inst.check(&[vec![0].into(), vec![3].into()]),
        Err(PlanError::Jump { step: 0, agent: 0 })
    );
    let plan = inst.solve(refining(100), None).unwrap();
    inst.check(&plan.configs).unwrap();
    assert_eq!(inst.sum_of_costs(&plan.configs), 2);
}
