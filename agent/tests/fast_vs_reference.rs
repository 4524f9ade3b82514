//! The fast path (f32 mantissa + exponent) against the f64 reference on maps where f64 does
//! not underflow: same sweep counts, values within f32 rounding, identical paths.

mod common;

use hnav_agent::neural_map::{
    Activation, ActivationField, Denominator, DiagonalRule, NeuralDynamics, NeuralMap,
    NeuralMapOptions, ReferenceMap, StopRule, Weights,
};
use hnav_agent::path_constructor::PathConstructor;
use hnav_runtime::grid::{Cell, Grid};

/// A deterministic spread of free cells (a tiny LCG, so the test needs no RNG crate).
fn free_cells(g: &Grid, count: usize, seed: u64) -> Vec<Cell> {
    let free: Vec<Cell> = g.passable_cells().collect();
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..count)
        .map(|_| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            free[(x >> 33) as usize % free.len()]
        })
        .collect()
}

fn variants() -> Vec<NeuralMapOptions> {
    let mut v = Vec::new();
    for activation in [Activation::Tanh, Activation::Linear] {
        for denominator in [
            Denominator::LinkedOnly,
            Denominator::InGrid,
            Denominator::OffGridAsZero,
        ] {
            for diagonals in [DiagonalRule::Always, DiagonalRule::NoCornerCutting] {
                v.push(NeuralMapOptions {
                    activation,
                    denominator,
                    diagonals,
                    ..NeuralMapOptions::default()
                });
            }
        }
    }
    v.push(NeuralMapOptions::seed_001());
    v.push(NeuralMapOptions {
        diagonals: DiagonalRule::NotBetweenTwoBlocked,
        denominator: Denominator::AllEight,
        weights: Weights {
            self_weight: 0.5,
            ..Weights::table_2_2()
        },
        // With a 1e-16 threshold far neurons may settle below it: cap the sweeps.
        max_sweeps: Some(300),
        ..NeuralMapOptions::dissertation()
    });
    v
}

/// Compares both implementations on `g` for `pairs` start/goal pairs; returns paths compared.
fn compare(g: &Grid, name: &str, pairs: usize, opts: &[NeuralMapOptions]) -> usize {
    let cells = free_cells(g, 2 * pairs, g.len() as u64);
    let mut compared = 0;
    for o in opts {
        let mut fast = NeuralMap::new(g, *o).unwrap();
        let mut reference = ReferenceMap::new(g, *o).unwrap();
        for pair in cells.chunks(2) {
            let (start, goal) = (pair[0], pair[1]);
            for stop in [
                StopRule::FullActivation,
                StopRule::PartialActivation { start },
            ] {
                let rf = fast.build(goal, stop).unwrap();
                let rr = reference.build(goal, stop).unwrap();
                assert_eq!(rf.outcome, rr.outcome, "{name} {o:?} {stop:?}");
                assert_eq!(rf.sweeps, rr.sweeps, "{name} {o:?} {stop:?} {goal}");
                assert_eq!(rf.cells_on, rr.cells_on, "{name} {o:?} {stop:?}");
                for c in g.passable_cells() {
                    let (a, b) = (fast.value(c), reference.value(c));
                    if b > 1e-280 {
                        assert!(
                            ((a - b) / b).abs() < 2e-4,
                            "{name} {o:?} {c}: fast {a:e} reference {b:e}"
                        );
                    }
                }
                let pc = PathConstructor::default();
                let pf = pc.trace(&fast, start).unwrap();
                let pr = pc.trace(&reference, start).unwrap();
                assert_eq!(pf, pr, "{name} {o:?} {stop:?} {start} -> {goal}");
                compared += 1;
            }
        }
    }
    compared
}

#[test]
fn dissertation_maze_and_open_10x10() {
    let n = compare(&common::maze(), "fig 2-16", 12, &variants());
    let n2 = compare(&Grid::new(10, 10).unwrap(), "open 10x10", 12, &variants());
    assert!(n + n2 > 0);
}

#[test]
fn movingai_32x32_maps() {
    let opts = variants();
    for name in [
        "empty-32-32.map",
        "random-32-32-10.map",
        "random-32-32-20.map",
        "maze-32-32-2.map",
        "room-32-32-4.map",
    ] {
        compare(&common::movingai(name), name, 4, &opts);
    }
}

#[test]
fn movingai_larger_maps_default_options() {
    for name in ["den312d.map", "warehouse-10-20-10-2-1.map"] {
        let g = common::movingai(name);
        let opts = [
            NeuralMapOptions::default(),
            NeuralMapOptions {
                activation: Activation::Linear,
                diagonals: DiagonalRule::NoCornerCutting,
                ..NeuralMapOptions::default()
            },
        ];
        compare(&g, name, 2, &opts);
    }
}
