//! The published numbers of Chapter 2: Table 2-2, the Fig. 2-16 maze, Table 2-1.

mod common;

use common::{id, maze};
use hnav_agent::neural_map::{
    Activation, ActivationField, Denominator, NeuralDynamics, NeuralMap, NeuralMapOptions, Outcome,
    ReferenceMap, StopRule,
};
use hnav_agent::path_constructor::{PathConstructor, PathOptions};

const FIG_2_16_PATH: [u32; 14] = [1, 2, 13, 23, 33, 44, 54, 64, 75, 76, 77, 68, 57, 56];

fn ids(g: &hnav_runtime::grid::Grid, cells: &[hnav_runtime::grid::Cell]) -> Vec<u32> {
    cells.iter().map(|&c| g.cell_id(c)).collect()
}

#[test]
fn fig_2_16_reference_counts_and_path() {
    let g = maze();
    for activation in [Activation::Tanh, Activation::Linear] {
        for denominator in [
            Denominator::LinkedOnly,
            Denominator::InGrid,
            Denominator::OffGridAsZero,
            Denominator::AllEight,
        ] {
            let opts = NeuralMapOptions {
                activation,
                denominator,
                ..NeuralMapOptions::dissertation()
            };
            let mut map = ReferenceMap::new(&g, opts).unwrap();
            let full = map.build(id(&g, 56), StopRule::FullActivation).unwrap();
            println!("{activation:?} {denominator:?}: full {full:?}");
            let path = PathConstructor::default().trace(&map, id(&g, 1)).unwrap();
            assert_eq!(path.steps, 13);
            if matches!(
                denominator,
                Denominator::LinkedOnly | Denominator::OffGridAsZero
            ) {
                assert_eq!(ids(&g, &path.cells), FIG_2_16_PATH, "{activation:?}");
            } else {
                // Obstacles as zeros lower 33 (three free neighbours, 44 diagonal) below 34
                // (44 straight below it): the same 13 moves and length through 34 instead.
                let mut alt = FIG_2_16_PATH;
                alt[4] = 34;
                assert_eq!(ids(&g, &path.cells), alt, "{activation:?} {denominator:?}");
            }
            let partial = map
                .build(id(&g, 56), StopRule::PartialActivation { start: id(&g, 1) })
                .unwrap();
            assert_eq!(partial.outcome, Outcome::StartReached);
            assert_eq!(partial.sweeps, 13, "{activation:?} {denominator:?}");
            if denominator != Denominator::AllEight {
                assert_eq!(full.outcome, Outcome::FullyActivated);
                assert_eq!(full.sweeps, 19, "{activation:?} {denominator:?}");
            } else {
                assert_eq!(full.sweeps, 21, "the notes' 1e-16 underflow case");
            }
        }
    }
}

#[test]
fn fig_2_16_fast_counts_and_path() {
    let g = maze();
    for activation in [Activation::Tanh, Activation::Linear] {
        let opts = NeuralMapOptions {
            activation,
            ..NeuralMapOptions::dissertation()
        };
        let mut map = NeuralMap::new(&g, opts).unwrap();
        let full = map.build(id(&g, 56), StopRule::FullActivation).unwrap();
        assert_eq!((full.outcome, full.sweeps), (Outcome::FullyActivated, 19));
        let path = PathConstructor::default().trace(&map, id(&g, 1)).unwrap();
        assert_eq!(ids(&g, &path.cells), FIG_2_16_PATH);
        assert_eq!(path.steps, 13);
        let partial = map
            .build(id(&g, 56), StopRule::PartialActivation { start: id(&g, 1) })
            .unwrap();
        assert_eq!(
            (partial.outcome, partial.sweeps),
            (Outcome::StartReached, 13)
        );
        let path = PathConstructor::new(PathOptions::default())
            .unwrap()
            .trace(&map, id(&g, 1))
            .unwrap();
        assert_eq!(ids(&g, &path.cells), FIG_2_16_PATH);
        assert!(map.is_on(id(&g, 1)));
    }
}

/// Table 2-1: the activation matrix of an empty 10 x 10 network with I_56 = 1.
const TABLE_2_1: [[f64; 10]; 10] = [
    [
        0.0034, 0.0071, 0.0113, 0.0155, 0.0187, 0.0198, 0.0185, 0.0151, 0.0104, 0.0052,
    ],
    [
        0.0071, 0.0153, 0.0249, 0.0349, 0.0429, 0.0459, 0.0426, 0.0341, 0.0229, 0.0113,
    ],
    [
        0.0113, 0.0249, 0.0423, 0.0625, 0.0799, 0.0868, 0.0794, 0.0612, 0.0393, 0.0187,
    ],
    [
        0.0155, 0.0349, 0.0625, 0.1017, 0.1417, 0.1598, 0.1412, 0.1001, 0.0585, 0.0267,
    ],
    [
        0.0187, 0.0429, 0.0799, 0.1417, 0.2591, 0.3103, 0.2585, 0.1398, 0.0752, 0.0330,
    ],
    [
        0.0198, 0.0459, 0.0868, 0.1598, 0.3103, 1.0000, 0.3097, 0.1578, 0.0819, 0.0355,
    ],
    [
        0.0185, 0.0426, 0.0794, 0.1412, 0.2585, 0.3097, 0.2579, 0.1393, 0.0748, 0.0328,
    ],
    [
        0.0151, 0.0341, 0.0612, 0.1001, 0.1398, 0.1578, 0.1393, 0.0985, 0.0573, 0.0261,
    ],
    [
        0.0104, 0.0229, 0.0393, 0.0585, 0.0752, 0.0819, 0.0748, 0.0573, 0.0366, 0.0173,
    ],
    [
        0.0052, 0.0113, 0.0187, 0.0267, 0.0330, 0.0355, 0.0328, 0.0261, 0.0173, 0.0085,
    ],
];

/// Single peak at the target, and strictly decreasing along every ray out of it.
fn assert_single_peak(values: &[f64], w: usize, t: (usize, usize)) {
    let at = |x: usize, y: usize| values[y * w + x];
    let h = values.len() / w;
    for y in 0..h {
        for x in 0..w {
            if (x, y) == t {
                continue;
            }
            let larger = (-1i64..=1)
                .flat_map(|dy| (-1i64..=1).map(move |dx| (dx, dy)))
                .any(|(dx, dy)| {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    (0..w as i64).contains(&nx)
                        && (0..h as i64).contains(&ny)
                        && at(nx as usize, ny as usize) > at(x, y)
                });
            assert!(larger, "({x}, {y}) is a local maximum");
        }
    }
    for (dx, dy) in [
        (0i64, -1i64),
        (1, -1),
        (1, 0),
        (1, 1),
        (0, 1),
        (-1, 1),
        (-1, 0),
        (-1, -1),
    ] {
        let (mut x, mut y) = (t.0 as i64, t.1 as i64);
        let mut last = at(t.0, t.1);
        loop {
            x += dx;
            y += dy;
            if !(0..w as i64).contains(&x) || !(0..h as i64).contains(&y) {
                break;
            }
            let v = at(x as usize, y as usize);
            assert!(v < last, "ray ({dx}, {dy}) not decreasing at ({x}, {y})");
            last = v;
        }
    }
}

fn print_table(name: &str, v: &[f64]) {
    println!("{name}:");
    for row in v.chunks(10) {
        let cells: Vec<String> = row.iter().map(|x| format!("{x:.4}")).collect();
        println!("  {}", cells.join(" "));
    }
}

#[test]
fn table_2_1_shape_and_closest_variant() {
    let g = hnav_runtime::grid::Grid::new(10, 10).unwrap();
    let target = id(&g, 56);
    let published: Vec<f64> = TABLE_2_1.iter().flatten().copied().collect();
    print_table("Table 2-1 (published)", &published);
    assert_single_peak(&published, 10, (5, 5));

    // The notes' closest variant: synchronous tanh, off-grid neighbours as zeros, 9 sweeps.
    let mut map = ReferenceMap::new(&g, NeuralMapOptions::table_2_1()).unwrap();
    let r = map.build(target, StopRule::Sweeps(9)).unwrap();
    assert_eq!((r.outcome, r.sweeps), (Outcome::SweepsDone, 9));
    print_table(
        "ours (tanh, all eight in the denominator, 9 sweeps)",
        map.values(),
    );
    let err = map
        .values()
        .iter()
        .zip(&published)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("max abs error vs Table 2-1: {err:.4}");
    assert!(err <= 0.0165, "max abs error {err}");
    assert_single_peak(map.values(), 10, (5, 5));

    // Our default maps have the same qualitative shape.
    for opts in [
        NeuralMapOptions::default(),
        NeuralMapOptions::dissertation(),
    ] {
        let mut map = ReferenceMap::new(&g, opts).unwrap();
        let r = map.build(target, StopRule::FullActivation).unwrap();
        assert_eq!(r.sweeps, 5, "eccentricity of 56 on 10 x 10");
        assert_single_peak(map.values(), 10, (5, 5));
    }
}

#[test]
fn table_2_2_weight_matrix() {
    use hnav_agent::neural_map::{WeightMatrix, Weights};
    #[rustfmt::skip]
    let table: [[f64; 12]; 12] = [
        [0.0, 1.0, 0.0, 0.0, 1.0, 0.7, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, 1.0, 0.0, 0.7, 1.0, 0.7, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 1.0, 0.0, 0.7, 1.0, 0.7, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.7, 1.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, 0.7, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.7, 0.0, 0.0],
        [0.7, 1.0, 0.7, 0.0, 1.0, 0.0, 1.0, 0.0, 0.7, 1.0, 0.7, 0.0],
        [0.0, 0.7, 1.0, 0.7, 0.0, 1.0, 0.0, 1.0, 0.0, 0.7, 1.0, 0.7],
        [0.0, 0.0, 0.7, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.7, 1.0],
        [0.0, 0.0, 0.0, 0.0, 1.0, 0.7, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, 0.7, 1.0, 0.7, 0.0, 1.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.7, 1.0, 0.7, 0.0, 1.0, 0.0, 1.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.7, 1.0, 0.0, 0.0, 1.0, 0.0],
    ];
    let m = WeightMatrix::lattice(3, 4, &Weights::table_2_2()).unwrap();
    assert_eq!(m.len(), 12);
    for (i, row) in table.iter().enumerate() {
        assert_eq!(m.row(i).unwrap(), row.as_slice(), "neuron {i}");
    }
    assert!(m.is_symmetric() && m.has_zero_diagonal() && m.is_stable_by_hopfield_rule());
    // Seed 001's self-connection breaks the zero-diagonal rule, as it should.
    let s = Weights {
        self_weight: 1.0,
        ..Weights::table_2_2()
    };
    let m = WeightMatrix::lattice(3, 4, &s).unwrap();
    assert!(m.is_symmetric() && !m.has_zero_diagonal());
    assert!(WeightMatrix::lattice(100, 100, &Weights::default()).is_err());
}

#[test]
fn unreachable_goal_is_reported_not_looped_on() {
    // The start (0, 0) is walled in by (1, 0), (0, 1), (1, 1).
    let g = common::grid_with_ids(6, 6, &[2, 7, 8]);
    let start = id(&g, 1);
    let target = id(&g, 36);
    let mut fast = NeuralMap::new(&g, NeuralMapOptions::default()).unwrap();
    let mut reference = ReferenceMap::new(&g, NeuralMapOptions::dissertation()).unwrap();
    let maps: [&mut dyn NeuralDynamics; 2] = [&mut fast, &mut reference];
    for map in maps {
        let r = map
            .build(target, StopRule::PartialActivation { start })
            .unwrap();
        assert_eq!(r.outcome, Outcome::Unreachable);
        // 5 sweeps cover the reachable cells; the 6th turns nothing on, and that is the proof.
        assert_eq!(r.sweeps, 6, "stops once the wave stops growing");
        assert!(!map.is_on(start));
        let full = map.build(target, StopRule::FullActivation).unwrap();
        assert_eq!(full.outcome, Outcome::FullyActivated);
        assert_eq!(full.cells_on, 36 - 4);
        let path = PathConstructor::default().trace(&*map, start).unwrap();
        assert_eq!(
            path.outcome,
            hnav_agent::path_constructor::PathOutcome::Unreachable
        );
        assert_eq!(path.steps, 0);
    }
    let r = hnav_agent::plan_query(&g, start, target, &Default::default()).unwrap();
    assert!(!r.found);
    assert!(r.path.is_empty());
}
