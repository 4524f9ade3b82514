//! The world's `[[events]]` in the sim: a closed cell is a wall a robot can hit, a mover is
//! an obstacle a robot can touch, both recorded once per contact; a restored world catches up
//! with the events by its time.

use hnav_runtime::grid::Cell;
use hnav_runtime::scenario::Scenario;
use hnav_sim::{Hit, World};

/// A 10x5 free room, one robot at (2, 2) facing +x (towards (9, 2)), and `events`.
fn world(events: &str) -> World {
    let text = format!(
        "name = \"ev\"\n[map]\nrows = [\"..........\", \"..........\", \"..........\", \
         \"..........\", \"..........\"]\n[[agents]]\nstart = [2, 2]\ngoal = [9, 2]\n{events}"
    );
    let s = Scenario::from_str(&text, "ev.toml", std::path::Path::new(".")).unwrap();
    World::from_scenario(&s).unwrap()
}

/// Drives robot 0 straight ahead for `steps` steps (commands renewed every 10).
fn drive(w: &mut World, steps: u64) {
    for _ in 0..steps {
        if w.steps().is_multiple_of(10) {
            let (now, period) = (w.time_ns(), w.steps() / 10);
            w.apply_command(0, period, 10.0, 10.0, now).unwrap();
        }
        w.step();
    }
}

#[test]
fn a_cell_closed_ahead_is_hit_and_one_opened_again_is_not() {
    let mut clear = world("");
    drive(&mut clear, 3000);
    assert!(clear
        .collisions()
        .iter()
        .all(|c| !matches!(c.hit, Hit::Cell(6, 2))));

    let mut closed = world("[[events]]\nat_s = 0.5\nclose = [[6, 2]]\n");
    assert!(
        !closed.grid().is_blocked(Cell::new(6, 2)),
        "not before its time"
    );
    drive(&mut closed, 3000);
    assert!(closed.grid().is_blocked(Cell::new(6, 2)));
    let first = closed.collisions().first().expect("the closed cell is hit");
    assert_eq!((first.robot, first.hit), (0, Hit::Cell(6, 2)));
    assert!(first.time_ns >= 500_000_000);

    // Closed, then open before the robot gets there: nothing to hit.
    let mut reopened = world(
        "[[events]]\nat_s = 0.1\nclose = [[6, 2]]\n[[events]]\nat_s = 0.2\nopen = [[6, 2]]\n",
    );
    drive(&mut reopened, 3000);
    assert!(!reopened.grid().is_blocked(Cell::new(6, 2)));
    assert!(reopened
        .collisions()
        .iter()
        .all(|c| !matches!(c.hit, Hit::Cell(6, 2))));
}

#[test]
fn a_mover_crossing_the_robots_way_is_touched_once() {
    // Down column 7 and back at 0.5 cells/s for ever: the robot, driving along row 2,
    // meets it there.
    // It walks on regardless (`yields = false`); one that yields would have walked on too,
    // having set off into (7, 2) before the robot came near.
    let mover = "[[events]]\nat_s = 0\nmover = \"person\"\npath = [[7, 0], [7, 4]]\nspeed = 0.5\nrepeat = true\nyields = false\n";
    let mut w = world(mover);
    drive(&mut w, 30_000);
    let hits: Vec<_> = (w.collisions().iter())
        .filter(|c| c.hit == Hit::Mover(0))
        .collect();
    assert_eq!(hits.len(), 1, "{:?}", w.collisions());
    let d = (hits[0].position - hits[0].other_position).norm();
    let r = hnav_runtime::scenario::params::RobotParams::default().body_radius_m;
    assert!(
        d < 2.0 * r && d > 2.0 * r - 0.01,
        "{d}: a contact begins at the discs' touch"
    );
    eprintln!("mover contact at {} ns", hits[0].time_ns);
    let (name, at) = w.movers().next().expect("the mover is under way");
    assert_eq!(name, "person");
    assert!(at.x > 0.0 && at.y > 0.0);
}

#[test]
fn a_restored_world_catches_up_with_the_events() {
    let events = "[[events]]\nat_s = 0\nmover = \"p\"\npath = [[7, 0], [7, 4]]\nspeed = 0.5\n\
                  repeat = true\n[[events]]\nat_s = 0.5\nclose = [[6, 2]]\n";
    let mut w = world(events);
    drive(&mut w, 1000);
    let mut bytes = Vec::new();
    w.write_snapshot(&mut bytes);
    let mut back = world(events);
    assert!(!back.grid().is_blocked(Cell::new(6, 2)));
    back.restore_snapshot(&bytes).unwrap();
    assert!(
        back.grid().is_blocked(Cell::new(6, 2)),
        "closed by its time"
    );
    drive(&mut w, 20_000);
    drive(&mut back, 20_000);
    assert_eq!(w.collisions(), back.collisions());
    assert_eq!(w.pose(0), back.pose(0));
}

/// The cells robot 0 sees within `range`, as (x, y, blocked).
fn seen(w: &World, range: u32) -> Vec<(u32, u32, bool)> {
    let mut v = hnav_runtime::msg::View::default();
    w.fill_view(0, 0, range, &mut v);
    v.cells().collect()
}

#[test]
fn a_view_sees_what_is_in_range_and_in_sight_and_a_wall_hides_what_is_behind() {
    // The robot at (2, 2); (4, 2) closed at once: seen blocked, (5, 2) behind it hidden.
    let w = world("[[events]]\nat_s = 0\nclose = [[4, 2]]\n");
    let cells = seen(&w, 3);
    assert!(cells.contains(&(4, 2, true)), "{cells:?}");
    assert!(cells.contains(&(3, 2, false)));
    assert!(
        !cells.iter().any(|&(x, y, _)| (x, y) == (5, 2)),
        "hidden: {cells:?}"
    );
    // In range (a disc of 3 cells) and in the map only.
    assert!(cells.iter().all(|&(x, y, _)| {
        let (dx, dy) = (i64::from(x) - 2, i64::from(y) - 2);
        dx * dx + dy * dy <= 9 && x < 10 && y < 5
    }));
    assert!(cells.contains(&(2, 2, false)), "its own cell");
    assert!(
        !cells.iter().any(|&(x, y, _)| (x, y) == (5, 3)),
        "out of range"
    );
    // Nothing closed: (5, 2) is seen, free.
    assert!(seen(&world(""), 3).contains(&(5, 2, false)));
}

#[test]
fn a_mover_in_range_is_seen_as_blocked_cells() {
    // Walks on: one that yields would wait at (4, 1) for the robot driving along row 2.
    let w = world(
        "[[events]]\nat_s = 0\nmover = \"p\"\npath = [[4, 0], [4, 4]]\nspeed = 1\nyields = false\n",
    );
    let mut w = w;
    drive(&mut w, 2000); // 2 s: the mover near (4, 2)
    let blocked: Vec<_> = seen(&w, 5)
        .into_iter()
        .filter(|c| c.2)
        .map(|c| (c.0, c.1))
        .collect();
    assert!(blocked.iter().all(|&(x, _)| x == 4), "{blocked:?}");
    assert!(blocked.contains(&(4, 2)), "{blocked:?}");
}

/// Steps the world `steps` times with no command (the robot stands).
fn stand(w: &mut World, steps: u64) {
    for _ in 0..steps {
        w.step();
    }
}

/// Turns robot 0 on the spot for `steps` steps (commands renewed every 10): in motion,
/// about to set off into a neighbour.
fn turn(w: &mut World, steps: u64) {
    for _ in 0..steps {
        if w.steps().is_multiple_of(10) {
            let (now, period) = (w.time_ns(), w.steps() / 10);
            w.apply_command(0, period, -5.0, 5.0, now).unwrap();
        }
        w.step();
    }
}

#[test]
fn a_mover_that_yields_waits_at_a_cell_centre_while_a_robot_may_enter_its_next_cell() {
    // Along row 1 past (1, 1), (2, 1) and (3, 1), above the robot at (2, 2), at 1 cell/s.
    let path = "[[events]]\nat_s = 0\nmover = \"p\"\npath = [[0, 1], [5, 1]]\nspeed = 1\n";
    let cell = hnav_runtime::scenario::params::RobotParams::default().cell_size_m;
    let mut w = world(path);
    turn(&mut w, 5_000);
    let (_, at) = w.movers().next().unwrap();
    // (1, 1) is one diagonal move from the robot: claimed.
    assert_eq!((at.x / cell, at.y / cell), (0.5, 1.5), "waits at (0, 1)");
    // Its view: the cell it holds.
    let mut v = hnav_runtime::msg::View::default();
    w.fill_view(0, 0, 3, &mut v);
    assert_eq!(v.moving_cells().collect::<Vec<_>>(), [(0, 1)]);

    // A checkpoint restores the wait: restored, it still waits.
    let mut bytes = Vec::new();
    w.write_snapshot(&mut bytes);
    let mut back = world(path);
    back.restore_snapshot(&bytes).unwrap();
    turn(&mut back, 1000);
    assert_eq!(back.movers().next().unwrap().1, at);

    // The robot stands: the mover walks by (a cell apart, no contact) to its end.
    stand(&mut back, 7_000);
    let (_, end) = back.movers().next().unwrap();
    assert_eq!((end.x / cell, end.y / cell), (5.5, 1.5));
    assert!(back.collisions().is_empty(), "{:?}", back.collisions());

    // One that does not yield walks by while the robot turns.
    let mut on = world(&format!("{path}yields = false\n"));
    turn(&mut on, 7_000);
    let (_, end) = on.movers().next().unwrap();
    assert_eq!((end.x / cell, end.y / cell), (5.5, 1.5));
}

#[test]
fn a_mover_that_has_waited_long_turns_back() {
    // West along row 1 from (5, 1); the turning robot at (2, 2) claims (3, 1), one diagonal
    // move away: the mover waits at (4, 1) from 1 s, turns back at 4 s.
    let path =
        "[[events]]\nat_s = 0\nmover = \"p\"\npath = [[5, 1], [0, 1]]\nspeed = 1\nrepeat = true\n";
    let cell = hnav_runtime::scenario::params::RobotParams::default().cell_size_m;
    let mut w = world(path);
    turn(&mut w, 3_900);
    let (_, at) = w.movers().next().unwrap();
    assert_eq!((at.x / cell, at.y / cell), (4.5, 1.5), "waits at (4, 1)");
    turn(&mut w, 500);
    let (_, at) = w.movers().next().unwrap();
    assert!(at.x / cell > 4.8, "back towards (5, 1): {}", at.x / cell);
    assert!(w.collisions().is_empty(), "{:?}", w.collisions());
}

#[test]
fn a_view_marks_the_cells_of_the_leg_a_mover_walks() {
    let mut w = world("[[events]]\nat_s = 0\nmover = \"p\"\npath = [[4, 0], [4, 4]]\nspeed = 1\n");
    stand(&mut w, 1500); // 1.5 cells walked: between (4, 1) and (4, 2)
    let mut v = hnav_runtime::msg::View::default();
    w.fill_view(0, 0, 5, &mut v);
    assert_eq!(v.moving_cells().collect::<Vec<_>>(), [(4, 1), (4, 2)]);
    // Blocked: the cells its disc covers, here the same.
    let blocked: Vec<_> = v.cells().filter(|c| c.2).map(|c| (c.0, c.1)).collect();
    assert_eq!(blocked, [(4, 1), (4, 2)]);
}

#[test]
fn a_mover_that_yields_comes_on_only_when_no_robot_claims_its_first_cell() {
    // The robot drives east along row 2; when is it in (5, 2)?
    let cell = hnav_runtime::scenario::params::RobotParams::default().cell_size_m;
    let in_cell = |w: &World, x: f64| (w.position(0).unwrap().x / cell).floor() == x;
    let mut probe = world("");
    let mut steps = 0;
    while !in_cell(&probe, 5.0) {
        drive(&mut probe, 1);
        steps += 1;
        assert!(steps < 20_000, "the robot never reached (5, 2)");
    }
    // A person due at that very time on (5, 2), walking up column 5: it waits to come on.
    let t_s = probe.time_ns() as f64 / 1e9;
    let person =
        format!("[[events]]\nat_s = {t_s}\nmover = \"p\"\npath = [[5, 2], [5, 0]]\nspeed = 1\n");
    let mut w = world(&person);
    drive(&mut w, steps + 1);
    assert!(in_cell(&w, 5.0));
    assert_eq!(w.movers().count(), 0, "it came on over the robot");
    assert_eq!(w.movers_on_floor(), 0);
    // A checkpoint keeps it off the floor.
    let mut bytes = Vec::new();
    w.write_snapshot(&mut bytes);
    let mut back = world(&person);
    back.restore_snapshot(&bytes).unwrap();
    assert_eq!(back.movers().count(), 0);
    // The robot drives on, out of (5, 2) and past its neighbours, and stops: the person
    // comes on and walks its way. Nobody touched anybody.
    for w in [&mut w, &mut back] {
        while (w.position(0).unwrap().x / cell) < 7.5 {
            drive(w, 1);
        }
        stand(w, 3_000);
        assert_eq!(w.movers().count(), 1);
        assert_eq!(w.mover_place(0).mover, 0);
        assert!(w.collisions().is_empty(), "{:?}", w.collisions());
    }
}

#[test]
fn a_mover_held_at_an_end_of_its_path_steps_off_and_comes_back_when_the_way_is_free() {
    // Back and forth along row 1 between (0, 1) and (3, 1); the turning robot at (2, 2)
    // claims (1, 1), one diagonal move away, so from the start the mover waits at (0, 1),
    // an end of its path, where turning back is the same way.
    let path =
        "[[events]]\nat_s = 0\nmover = \"p\"\npath = [[0, 1], [3, 1]]\nspeed = 1\nrepeat = true\n";
    let cell = hnav_runtime::scenario::params::RobotParams::default().cell_size_m;
    let mut w = world(path);
    turn(&mut w, 2_900);
    let (_, at) = w.movers().next().expect("on the floor, waiting");
    assert_eq!((at.x / cell, at.y / cell), (0.5, 1.5), "waits at (0, 1)");
    // Past the turn-back wait it steps off the floor, and stays off while the robot turns.
    turn(&mut w, 300);
    assert_eq!(w.movers().count(), 0, "it stepped off");
    turn(&mut w, 2_000);
    assert_eq!(
        w.movers().count(),
        0,
        "off while the robot may enter its way"
    );
    // A checkpoint keeps it off, at its end.
    let mut bytes = Vec::new();
    w.write_snapshot(&mut bytes);
    let mut back = world(path);
    back.restore_snapshot(&bytes).unwrap();
    assert_eq!(back.movers().count(), 0);
    // The robot stands: the mover comes back on at (0, 1) and walks its way, a cell from
    // the robot; nobody touched anybody.
    for w in [&mut w, &mut back] {
        // The robot's wheels come to rest first (motor lag): until then it may still enter.
        let mut steps = 0;
        while w.movers().count() == 0 {
            stand(w, 1);
            steps += 1;
            assert!(steps < 2_000, "never came back on");
        }
        let (_, at) = w.movers().next().unwrap();
        assert_eq!(
            (at.x / cell, at.y / cell),
            (0.5, 1.5),
            "back where it stepped off"
        );
        stand(w, 2_000);
        let (_, at) = w.movers().next().unwrap();
        assert!(at.x / cell > 2.0, "walked on: {}", at.x / cell);
        assert!(w.collisions().is_empty(), "{:?}", w.collisions());
    }
}
