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

/// The default options and their linear, no-corner-cutting counterpart.
fn default_and_linear() -> [NeuralMapOptions; 2] {
    [
        NeuralMapOptions::default(),
        NeuralMapOptions {
            activation: Activation::Linear,
            diagonals: DiagonalRule::NoCornerCutting,
            ..NeuralMapOptions::default()
        },
    ]
}

#[test]
fn movingai_larger_maps_default_options() {
    for name in ["den312d.map", "warehouse-10-20-10-2-1.map"] {
        let g = common::movingai(name);
        compare(&g, name, 2, &default_and_linear());
    }
}

/// A map much larger than one tile of the fast path: walls with gaps every 16 cells plus
/// scattered blocks, so the wave crosses many tiles, tiles hold obstacles, and a tile can
/// hold cells on both sides of a wall (values far apart) or cells the wave never reaches
/// (a walled-off pocket).
fn tiled_obstacles(n: u32) -> Grid {
    let mut g = Grid::new(n, n).unwrap();
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = |m: u32| {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 33) as u32 % m
    };
    for w in (16..n).step_by(21) {
        for y in 0..n {
            // A vertical wall with a gap near one end, so the wave winds around it.
            if (w / 21) % 2 == 0 && y < n - 3 || (w / 21) % 2 == 1 && y > 2 {
                g.set_blocked(Cell::new(w, y), true);
            }
        }
    }
    for _ in 0..n * 2 {
        g.set_blocked(Cell::new(rnd(n), rnd(n)), true);
    }
    // A walled-off pocket: a closed ring of obstacles.
    for i in 0..9 {
        for c in [
            Cell::new(5 + i, 5),
            Cell::new(5 + i, 13),
            Cell::new(5, 5 + i),
            Cell::new(13, 5 + i),
        ] {
            g.set_blocked(c, true);
        }
    }
    g
}

#[test]
fn many_tiles_with_walls_and_pockets() {
    let g = tiled_obstacles(100);
    let opts = default_and_linear();
    assert!(compare(&g, "tiled obstacles 100x100", 3, &opts) > 0);
    // A target inside the pocket: the rest of the map stays 0.
    let mut fast = NeuralMap::new(&g, opts[0]).unwrap();
    let mut reference = ReferenceMap::new(&g, opts[0]).unwrap();
    let (goal, start) = (Cell::new(8, 8), Cell::new(60, 60));
    let rf = fast
        .build(goal, StopRule::PartialActivation { start })
        .unwrap();
    let rr = reference
        .build(goal, StopRule::PartialActivation { start })
        .unwrap();
    assert_eq!((rf.outcome, rf.sweeps), (rr.outcome, rr.sweeps));
    assert!(!fast.is_on(start));
}
