//! §2.10: partial correction of the map and rebuilding with partial activation.

mod common;

use hnav_agent::neural_map::repair::{partial_correction, path_hits, rebuild_partial};
use hnav_agent::neural_map::{
    NeuralDynamics, NeuralMap, NeuralMapOptions, Outcome, ReferenceMap, StopRule,
};
use hnav_agent::path_constructor::PathConstructor;
use hnav_runtime::grid::{Cell, Grid};

#[test]
fn rebuild_with_partial_activation_needs_13_sweeps_on_the_maze() {
    let g = common::maze();
    let (start, target) = (common::id(&g, 1), common::id(&g, 56));
    let mut map = NeuralMap::new(&g, NeuralMapOptions::dissertation()).unwrap();
    let full = map.build(target, StopRule::FullActivation).unwrap();
    let full_path = PathConstructor::default().trace(&map, start).unwrap();
    let r = rebuild_partial(&mut map, &[], start).unwrap();
    assert_eq!((full.sweeps, r.sweeps), (19, 13));
    assert!(r.cells_on < full.cells_on, "fewer neurons activated");
    println!(
        "maze: full {} sweeps / {} neurons on, partial {} sweeps / {} neurons on ({:.1} % fewer \
         sweeps)",
        full.sweeps,
        full.cells_on,
        r.sweeps,
        r.cells_on,
        100.0 * (1.0 - f64::from(r.sweeps) / f64::from(full.sweeps))
    );
    let partial_path = PathConstructor::default().trace(&map, start).unwrap();
    assert_eq!(
        partial_path.cells, full_path.cells,
        "same trajectory (§2.10 Б)"
    );
}

/// A 20 x 20 room: the robot heads east along row 10 when a wall appears across its way.
fn room() -> (Grid, Cell, Cell, Vec<Cell>) {
    let g = Grid::new(20, 20).unwrap();
    let wall: Vec<Cell> = (4..=15).map(|y| Cell::new(10, y)).collect();
    (g, Cell::new(0, 10), Cell::new(19, 10), wall)
}

#[test]
fn partial_correction_bends_the_path_around_a_new_wall() {
    let (g, start, goal, wall) = room();
    let pc = PathConstructor::default();
    let mut lengths = Vec::new();
    for n in [1, 5] {
        let mut fast = NeuralMap::new(&g, NeuralMapOptions::default()).unwrap();
        let mut reference = ReferenceMap::new(&g, NeuralMapOptions::default()).unwrap();
        let maps: [&mut dyn NeuralDynamics; 2] = [&mut fast, &mut reference];
        let mut paths = Vec::new();
        for map in maps {
            map.build(goal, StopRule::FullActivation).unwrap();
            let before = pc.trace(&*map, start).unwrap();
            assert!(
                path_hits(&before.cells, &wall),
                "the old path crosses the new wall"
            );
            let r = partial_correction(map, &wall, n).unwrap();
            assert_eq!((r.outcome, r.sweeps), (Outcome::SweepsDone, n));
            for &c in &wall {
                assert!(map.is_blocked(c) && !map.is_on(c), "{c} zeroed and blocked");
            }
            let after = pc.trace(&*map, start).unwrap();
            assert!(after.reached(), "n = {n}: {:?}", after.outcome);
            assert!(!path_hits(&after.cells, &wall));
            paths.push(after);
        }
        assert_eq!(
            paths[0].cells, paths[1].cells,
            "fast and reference agree (n = {n})"
        );
        println!(
            "partial correction n = {n}: {} steps, {} turns, length (encoder) {:.2}",
            paths[0].steps, paths[0].turns, paths[0].length
        );
        lengths.push(paths[0].length);
    }
    // Rebuilding from zero with partial activation, for comparison.
    let mut map = NeuralMap::new(&g, NeuralMapOptions::default()).unwrap();
    map.build(goal, StopRule::FullActivation).unwrap();
    let r = rebuild_partial(&mut map, &wall, start).unwrap();
    assert_eq!(r.outcome, Outcome::StartReached);
    let p = pc.trace(&map, start).unwrap();
    assert!(p.reached() && !path_hits(&p.cells, &wall));
    println!(
        "rebuild (partial activation, {} sweeps): {} steps, {} turns, length {:.2}",
        r.sweeps, p.steps, p.turns, p.length
    );
    assert!(lengths.iter().all(|&l| l >= p.length - 1e-9));
}

#[test]
fn repair_rejects_bad_cells() {
    let (g, _, goal, _) = room();
    let mut map = NeuralMap::new(&g, NeuralMapOptions::default()).unwrap();
    assert!(
        partial_correction(&mut map, &[Cell::new(1, 1)], 1).is_err(),
        "not built yet"
    );
    map.build(goal, StopRule::FullActivation).unwrap();
    assert!(partial_correction(&mut map, &[Cell::new(20, 0)], 1).is_err());
    assert!(
        partial_correction(&mut map, &[goal], 1).is_err(),
        "the target cannot be blocked"
    );
    assert!(rebuild_partial(&mut map, &[], Cell::new(0, 20)).is_err());
}
