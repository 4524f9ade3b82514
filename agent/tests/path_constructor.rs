//! The path constructor's rules: refused directions, Fig. 3-7 corners, eq. 3.7 heading,
//! visited cells, ties, and bad input.

mod common;

use hnav_agent::neural_map::{
    ActivationField, DiagonalRule, NeuralDynamics, NeuralMap, NeuralMapOptions, ReferenceMap,
    StopRule,
};
use hnav_agent::path_constructor::{
    DirectionMask, PathConstructor, PathOptions, PathOutcome, VisitedRule,
};
use hnav_agent::Error;
use hnav_runtime::grid::{Cell, Direction, Grid};

fn built(g: &Grid, target: Cell, opts: NeuralMapOptions) -> ReferenceMap {
    let mut m = ReferenceMap::new(g, opts).unwrap();
    m.build(target, StopRule::FullActivation).unwrap();
    m
}

#[test]
fn gradients_are_the_ascent_form_clockwise_from_north() {
    let g = Grid::new(9, 9).unwrap();
    let map = built(&g, Cell::new(4, 4), NeuralMapOptions::default());
    let pc = PathConstructor::default();
    let at = Cell::new(4, 6);
    let (dir, grads) = pc.next_step(&map, at, None, DirectionMask::NONE);
    assert_eq!(dir, Some(Direction::N));
    let e = |c: Cell| map.value(c);
    for d in Direction::ALL {
        let n = Cell::new(
            at.x.wrapping_add_signed(d.dx()),
            at.y.wrapping_add_signed(d.dy()),
        );
        let w = if d.is_diagonal() {
            std::f64::consts::FRAC_1_SQRT_2
        } else {
            1.0
        };
        let want = (e(n) - e(at)) * w;
        assert!((grads.values[d.index()] - want).abs() < 1e-15, "{d}");
    }
    // Off the grid and on obstacles: -1 and never taken.
    let (_, corner) = pc.next_step(&map, Cell::new(0, 0), None, DirectionMask::NONE);
    for d in [
        Direction::N,
        Direction::NE,
        Direction::W,
        Direction::SW,
        Direction::NW,
    ] {
        assert_eq!(corner.values[d.index()], -1.0);
        assert!(!corner.is_allowed(d));
    }
}

#[test]
fn refused_directions_and_fig_3_7_corners() {
    let g = Grid::new(9, 9).unwrap();
    let opts = NeuralMapOptions {
        diagonals: DiagonalRule::NoCornerCutting,
        ..NeuralMapOptions::default()
    };
    let map = built(&g, Cell::new(4, 0), opts);
    let pc = PathConstructor::default();
    let at = Cell::new(4, 4);
    assert_eq!(
        pc.next_step(&map, at, None, DirectionMask::NONE).0,
        Some(Direction::N)
    );
    // The coordinator refuses N: a virtual obstacle, so NE and NW go too (Fig. 3-7).
    let mask = DirectionMask::NONE.refuse(Direction::N);
    let (dir, g3) = pc.next_step(&map, at, None, mask);
    for d in [Direction::N, Direction::NE, Direction::NW] {
        assert_eq!(g3.values[d.index()], -1.0, "{d}");
        assert!(!g3.is_allowed(d));
    }
    assert!(matches!(dir, Some(Direction::E | Direction::W)), "{dir:?}");
    // With the dissertation's corner rule a refused N leaves the diagonals open.
    let loose = PathConstructor::new(PathOptions {
        corner_rule: Some(DiagonalRule::Always),
        ..PathOptions::default()
    })
    .unwrap();
    let (dir, _) = loose.next_step(&map, at, None, mask);
    assert!(
        matches!(dir, Some(Direction::NE | Direction::NW)),
        "{dir:?}"
    );
    // Everything refused: no move.
    let (dir, _) = pc.next_step(&map, at, None, DirectionMask(0xff));
    assert_eq!(dir, None);
}

#[test]
fn heading_bonus_is_sqrt_2_on_the_current_direction() {
    let g = Grid::new(9, 9).unwrap();
    let map = built(&g, Cell::new(8, 8), NeuralMapOptions::default());
    let bonus = PathConstructor::new(PathOptions {
        heading_bonus: true,
        ..PathOptions::default()
    })
    .unwrap();
    let at = Cell::new(2, 4);
    let plain = bonus.gradients(&map, at, None, DirectionMask::NONE, |_| false);
    let boosted = bonus.gradients(&map, at, Some(Direction::E), DirectionMask::NONE, |_| false);
    let ratio = boosted.values[Direction::E.index()] / plain.values[Direction::E.index()];
    assert!((ratio - std::f64::consts::SQRT_2).abs() < 1e-12);
    // Fewer or equal turns on an open map with the bonus than without.
    let a = PathConstructor::default()
        .trace(&map, Cell::new(0, 3))
        .unwrap();
    let b = bonus.trace(&map, Cell::new(0, 3)).unwrap();
    assert!(a.reached() && b.reached());
    assert!(b.turns <= a.turns, "{} vs {}", b.turns, a.turns);
}

#[test]
fn visited_cells_zeroed_or_negated() {
    let g = Grid::new(5, 5).unwrap();
    let map = built(&g, Cell::new(4, 2), NeuralMapOptions::default());
    let at = Cell::new(2, 2);
    let left = Cell::new(1, 2);
    let (c, l) = (map.value(at), map.value(left));
    for (rule, want) in [
        (VisitedRule::Keep, l - c),
        (VisitedRule::Zero, -c),
        (VisitedRule::Negate, -l - c),
    ] {
        let pc = PathConstructor::new(PathOptions {
            visited: rule,
            ..PathOptions::default()
        })
        .unwrap();
        let gr = pc.gradients(&map, at, None, DirectionMask::NONE, |x| x == left);
        assert!(
            (gr.values[Direction::W.index()] - want).abs() < 1e-15,
            "{rule:?}"
        );
    }
}

#[test]
fn symmetric_ties_go_to_the_first_direction_clockwise() {
    // Target straight south of an open 5-wide strip: SW and SE from the start are equal.
    let g = Grid::new(5, 7).unwrap();
    let target = Cell::new(2, 6);
    let fast = {
        let mut m = NeuralMap::new(&g, NeuralMapOptions::default()).unwrap();
        m.build(target, StopRule::FullActivation).unwrap();
        m
    };
    let reference = built(&g, target, NeuralMapOptions::default());
    let pc = PathConstructor::default();
    // From (1, 0), S and the diagonals: the path must be the same in both implementations.
    for start in [
        Cell::new(0, 0),
        Cell::new(1, 0),
        Cell::new(3, 0),
        Cell::new(4, 0),
    ] {
        assert_eq!(
            pc.trace(&fast, start).unwrap(),
            pc.trace(&reference, start).unwrap()
        );
    }
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let g = common::grid_with_ids(4, 4, &[6]);
    let mut map = NeuralMap::new(&g, NeuralMapOptions::default()).unwrap();
    let pc = PathConstructor::default();
    assert!(matches!(
        pc.trace(&map, Cell::new(0, 0)),
        Err(Error::InvalidOption { .. })
    ));
    assert!(matches!(
        map.build(Cell::new(1, 1), StopRule::FullActivation),
        Err(Error::Blocked { .. })
    ));
    assert!(matches!(
        map.build(Cell::new(4, 0), StopRule::FullActivation),
        Err(Error::OutOfBounds { .. })
    ));
    assert!(map
        .build(
            Cell::new(0, 0),
            StopRule::PartialActivation {
                start: Cell::new(9, 9)
            }
        )
        .is_err());
    assert!(map
        .build(
            Cell::new(0, 0),
            StopRule::Converged {
                tolerance: f64::NAN
            }
        )
        .is_err());
    map.build(Cell::new(3, 3), StopRule::FullActivation)
        .unwrap();
    assert!(matches!(
        pc.trace(&map, Cell::new(1, 1)),
        Err(Error::Blocked { .. })
    ));
    assert!(matches!(
        pc.trace(&map, Cell::new(0, 7)),
        Err(Error::OutOfBounds { .. })
    ));
    let p = pc.trace(&map, Cell::new(3, 3)).unwrap();
    assert_eq!(
        (p.outcome, p.steps, p.cells.len()),
        (PathOutcome::Reached, 0, 1)
    );
    assert!(PathConstructor::new(PathOptions {
        diagonal_weight: 0.0,
        ..PathOptions::default()
    })
    .is_err());
    let bad = NeuralMapOptions {
        weights: hnav_agent::neural_map::Weights {
            straight: -1.0,
            ..Default::default()
        },
        ..NeuralMapOptions::default()
    };
    assert!(NeuralMap::new(&g, bad).is_err());
    assert!(ReferenceMap::new(&g, bad).is_err());
}

#[test]
fn convergence_stop_and_sweep_cap() {
    let g = Grid::new(10, 10).unwrap();
    let target = Cell::new(5, 5);
    for tol in [1e-3, 1e-6] {
        let mut f = NeuralMap::new(&g, NeuralMapOptions::default()).unwrap();
        let mut r = ReferenceMap::new(&g, NeuralMapOptions::default()).unwrap();
        let a = f
            .build(target, StopRule::Converged { tolerance: tol })
            .unwrap();
        let b = r
            .build(target, StopRule::Converged { tolerance: tol })
            .unwrap();
        println!(
            "tanh converged to {tol:e}: fast {} sweeps, reference {} sweeps",
            a.sweeps, b.sweeps
        );
        assert_eq!(a.outcome, hnav_agent::neural_map::Outcome::Converged);
        assert!(
            a.sweeps.abs_diff(b.sweeps) <= 2,
            "{} vs {}",
            a.sweeps,
            b.sweeps
        );
    }
    let capped = NeuralMapOptions {
        max_sweeps: Some(3),
        ..NeuralMapOptions::default()
    };
    let mut f = NeuralMap::new(&g, capped).unwrap();
    let r = f.build(target, StopRule::FullActivation).unwrap();
    assert_eq!(
        (r.outcome, r.sweeps),
        (hnav_agent::neural_map::Outcome::SweepLimit, 3)
    );
}

#[test]
fn walker_follows_the_coordinators_masks() {
    use hnav_agent::path_constructor::Walker;
    let g = Grid::new(9, 9).unwrap();
    let target = Cell::new(8, 4);
    let map = built(&g, target, NeuralMapOptions::default());
    let pc = PathConstructor::default();
    let mut w = Walker::new(9, 9, Cell::new(0, 4));
    // The coordinator refuses E at the first step (another robot is there).
    let (d, grads) = w.propose(&pc, &map, DirectionMask::NONE.refuse(Direction::E));
    assert_eq!(grads.values[Direction::E.index()], -1.0);
    let d = d.unwrap();
    assert!(matches!(d, Direction::NE | Direction::SE), "{d}");
    w.advance(d);
    assert!(w.has_left(Cell::new(0, 4)));
    let mut seen = vec![w.cell()];
    while w.cell() != target {
        let (d, _) = w.propose(&pc, &map, DirectionMask::NONE);
        w.advance(d.unwrap());
        assert!(!seen.contains(&w.cell()), "revisit {}", w.cell());
        seen.push(w.cell());
        assert!(seen.len() < 20);
    }
    assert_eq!(
        seen.len(),
        8,
        "one detour step costs nothing on an open map"
    );
}
