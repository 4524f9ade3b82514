//! Paths across maps far beyond f64's range: the wave front's values fall below 1e-308
//! (and f32's 1e-38) long before it arrives, yet the scaled fast path finds the path.

mod common;

use std::time::Instant;

use hnav_agent::neural_map::{ActivationField, NeuralMap};
use hnav_agent::path_constructor::PathConstructor;
use hnav_agent::plan::{PlanOptions, PlanStop, Planner};
use hnav_agent::Activation;
use hnav_runtime::grid::{octile_shortest_path_len, Cell, CornerCutting, Direction, Grid};
use hnav_runtime::plan::PlanResult;

/// Plans and checks the path: legal moves, no revisits, strictly rising activation.
fn plan_and_check(g: &Grid, start: Cell, goal: Cell, options: &PlanOptions) -> PlanResult {
    let t0 = Instant::now();
    let mut planner = Planner::new(g, options).unwrap();
    let r = planner.query(start, goal).unwrap();
    assert!(r.found, "no path {start} -> {goal}");
    assert_eq!(r.path.first(), Some(&start));
    assert_eq!(r.path.last(), Some(&goal));
    let map: &NeuralMap = planner.map();
    let mut seen = std::collections::HashSet::new();
    let mut last = f64::NEG_INFINITY;
    for w in r.path.windows(2) {
        let d = Direction::between(w[0], w[1]).expect("a single move");
        assert!(
            g.can_move(w[0], d, options.corner_cutting),
            "{} -> {}",
            w[0],
            w[1]
        );
        assert!(seen.insert(w[0]), "revisits {}", w[0]);
        let l = map.log2_value(w[1]);
        assert!(l > last, "activation does not rise at {}", w[1]);
        last = l;
    }
    let shortest = octile_shortest_path_len(g, start, goal, options.corner_cutting).unwrap();
    println!(
        "{}x{} {start} -> {goal}: {} sweeps, {} steps, length {:.2} (octile shortest {:.2}, \
         ratio {:.4}), log2 E(start) = {:.0}, {:.2} s (debug build)",
        g.width(),
        g.height(),
        r.iterations,
        r.steps,
        r.length,
        shortest,
        r.length / shortest,
        map.log2_value(start),
        t0.elapsed().as_secs_f64()
    );
    assert!(r.length <= shortest * 1.5);
    r
}

/// The goal in the centre, the robot in each corner: 512 sweeps cover the whole map (about
/// 1.8e8 neuron updates, ~5 s in a debug build; corner to corner would take twice as long, so
/// that case runs in `hnav-bench neural-map` instead). The start's activation is about
/// `2^-1700`, far below f64's `2^-1074`.
#[test]
fn open_1024_corners_to_centre() {
    let g = Grid::new(1024, 1024).unwrap();
    let goal = Cell::new(512, 512);
    let options = PlanOptions {
        activation: Activation::Linear,
        stop: PlanStop::Full,
        ..PlanOptions::default()
    };
    let t0 = Instant::now();
    let mut planner = Planner::new(&g, &options).unwrap();
    let r = planner.query(Cell::new(0, 0), goal).unwrap();
    assert!(r.found);
    assert_eq!(
        r.iterations, 512,
        "full activation = eccentricity of the centre"
    );
    assert_eq!(r.steps, 512, "the diagonal");
    let map = planner.map();
    assert!(map.log2_value(Cell::new(0, 0)) < -1074.0, "beyond f64");
    let pc = PathConstructor::default();
    for corner in [
        Cell::new(1023, 0),
        Cell::new(0, 1023),
        Cell::new(1023, 1023),
    ] {
        let p = pc.trace(map, corner).unwrap();
        assert!(p.reached(), "{corner}");
        let chebyshev = corner.x.abs_diff(goal.x).max(corner.y.abs_diff(goal.y)) as usize;
        assert_eq!(p.steps, chebyshev, "{corner}");
        let shortest =
            octile_shortest_path_len(&g, corner, goal, CornerCutting::Forbidden).unwrap();
        assert!(
            (p.length - shortest).abs() < 1e-9,
            "{corner}: {} vs {shortest}",
            p.length
        );
    }
    println!(
        "1024x1024: 512 sweeps, log2 E(corner) = {:.0}, {:.2} s (debug build)",
        map.log2_value(Cell::new(0, 0)),
        t0.elapsed().as_secs_f64()
    );
}

#[test]
fn movingai_den520d() {
    let g = common::movingai("den520d.map");
    let (a, b) = common::far_pair(&g, CornerCutting::Forbidden);
    plan_and_check(&g, a, b, &PlanOptions::default());
}

#[test]
fn movingai_lak303d() {
    let g = common::movingai("lak303d.map");
    let (a, b) = common::far_pair(&g, CornerCutting::Forbidden);
    plan_and_check(&g, a, b, &PlanOptions::default());
}

#[test]
fn movingai_maze_128() {
    let g = common::movingai("maze-128-128-10.map");
    let (a, b) = common::far_pair(&g, CornerCutting::Forbidden);
    for activation in [Activation::Tanh, Activation::Linear] {
        for corner_cutting in [CornerCutting::Forbidden, CornerCutting::Allowed] {
            let options = PlanOptions {
                activation,
                stop: PlanStop::Partial,
                corner_cutting,
            };
            plan_and_check(&g, a, b, &options);
        }
    }
}
