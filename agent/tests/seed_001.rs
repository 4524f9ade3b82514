//! Seed 001's single-robot cases (Figs. 4 and 5 without the other robots) on an empty 10 x 10
//! map: every robot takes the shortest number of steps (the Chebyshev distance).

mod common;

use hnav_agent::neural_map::{
    Activation, NeuralDynamics, NeuralMap, NeuralMapOptions, Outcome, ReferenceMap, StopRule,
};
use hnav_agent::path_constructor::{PathConstructor, PathOptions, VisitedRule};
use hnav_runtime::grid::Grid;

/// (start, target, sweeps to full activation in the notes' proxy) per robot, 1-based ids.
const FIG_4: [(u32, u32, u32); 3] = [(1, 26, 7), (41, 49, 8), (96, 16, 8)];
const FIG_5: [(u32, u32, u32); 3] = [(12, 100, 9), (89, 1, 9), (96, 51, 9)];

#[test]
fn figs_4_and_5_single_robot_take_shortest_steps() {
    let g = Grid::new(10, 10).unwrap();
    let pc = PathConstructor::new(PathOptions {
        visited: VisitedRule::Negate,
        ..PathOptions::default()
    })
    .unwrap();
    for (fig, robots) in [("Fig. 4", FIG_4), ("Fig. 5", FIG_5)] {
        for (robot, &(start, target, sweeps)) in robots.iter().enumerate() {
            let (s, t) = (common::id(&g, start), common::id(&g, target));
            let shortest = s.x.abs_diff(t.x).max(s.y.abs_diff(t.y)) as usize;
            for activation in [Activation::Linear, Activation::Tanh] {
                let opts = NeuralMapOptions {
                    activation,
                    ..NeuralMapOptions::seed_001()
                };
                let mut fast = NeuralMap::new(&g, opts).unwrap();
                let mut reference = ReferenceMap::new(&g, opts).unwrap();
                let maps: [&mut dyn NeuralDynamics; 2] = [&mut fast, &mut reference];
                for map in maps {
                    let r = map.build(t, StopRule::FullActivation).unwrap();
                    assert_eq!((r.outcome, r.sweeps), (Outcome::FullyActivated, sweeps));
                    let p = pc.trace(&*map, s).unwrap();
                    assert!(p.reached());
                    println!(
                        "{fig} robot {}: {start} -> {target}: {} steps (shortest {shortest}), \
                         {activation:?}",
                        robot + 1,
                        p.steps
                    );
                    assert_eq!(p.steps, shortest, "{fig} robot {}", robot + 1);
                }
            }
        }
    }
}
