//! Unit tests of `[[events]]`: closing, opening and movers, their errors (each naming its
//! line), and the hash.

use super::test_support::{parse, BASE};
use super::*;

/// `BASE` with `[[events]]` entries (each body after its header); the first entry's first
/// key is on line 17.
fn events(bodies: &[&str]) -> Result<Scenario, ScenarioError> {
    let mut text = BASE.to_string();
    for b in bodies {
        text.push_str("[[events]]\n");
        text.push_str(b);
    }
    parse(&text)
}

fn err(bodies: &[&str]) -> String {
    events(bodies).unwrap_err().to_string()
}

#[test]
fn closes_opens_and_movers_parse_in_time_order() {
    let s = events(&[
        "at_round = 100\nclose = [[4, 1]]\n",
        "at_s = 2.0\nclose_rect = [[4, 2], [5, 3]]\n",
        "at_s = 3.0\nopen = [[4, 1], [1, 1]]\n",
        "at_s = 3.0\nmover = \"forklift\"\npath = [[0, 2], [3, 2], [3, 1]]\nspeed = 0.5\nrepeat = true\n",
    ])
    .unwrap();
    let period = s.sim.control_period_s();
    assert_eq!(s.events.len(), 4);
    assert_eq!(s.events[0].at_s, 100.0 * period);
    assert_eq!(
        s.events[0].change,
        WorldChange::Close(vec![Cell::new(4, 1)])
    );
    let rect = [(4, 2), (5, 2), (4, 3), (5, 3)].map(|(x, y)| Cell::new(x, y));
    assert_eq!(s.events[1].change, WorldChange::Close(rect.to_vec()));
    // A wall of the map may open (a door drawn shut).
    assert_eq!(
        s.events[2].change,
        WorldChange::Open(vec![Cell::new(4, 1), Cell::new(1, 1)])
    );
    let WorldChange::Mover(m) = &s.events[3].change else {
        panic!("a mover: {:?}", s.events[3]);
    };
    let cells: Vec<(u32, u32)> = m.cells.iter().map(|c| (c.x, c.y)).collect();
    assert_eq!(cells, [(0, 2), (1, 2), (2, 2), (3, 2), (3, 1)]);
    assert_eq!((m.speed, m.repeat, m.yields), (0.5, true, true));
}

#[test]
fn a_mover_goes_along_its_cells_and_back_or_stays_at_the_end() {
    let mut m = MoverSpec {
        name: "p".into(),
        cells: [(0, 2), (1, 2), (2, 2), (2, 1)]
            .map(|(x, y)| Cell::new(x, y))
            .to_vec(),
        speed: 0.5,
        repeat: false,
        yields: true,
    };
    assert_eq!(m.position(0.0), (0.0, 2.0));
    assert_eq!(m.position(1.0), (0.5, 2.0));
    assert_eq!(m.position(4.0), (2.0, 2.0));
    assert_eq!(m.position(5.0), (2.0, 1.5));
    assert_eq!(m.position(60.0), (2.0, 1.0), "stays at its last cell");
    m.repeat = true;
    assert_eq!(m.position(6.0), (2.0, 1.0), "the far end after 3 cells");
    assert_eq!(m.position(8.0), (2.0, 2.0), "one cell back");
    assert_eq!(m.position(12.0), (0.0, 2.0), "home again");
    assert_eq!(m.position(13.0), (0.5, 2.0), "and out again");
    // The cells it passes, every return counted.
    let passed: Vec<(u32, u32)> = (0..8).map(|k| m.cell_at(k)).map(|c| (c.x, c.y)).collect();
    assert_eq!(
        passed,
        [
            (0, 2),
            (1, 2),
            (2, 2),
            (2, 1),
            (2, 2),
            (1, 2),
            (0, 2),
            (1, 2)
        ]
    );
    assert_eq!(m.end(), None);
    m.repeat = false;
    assert_eq!((m.cell_at(7), m.end()), (Cell::new(2, 1), Some(3.0)));
}

#[test]
fn every_mistake_names_its_line() {
    let cases: &[(&[&str], &str)] = &[
        (&["close = [[4, 1]]\n"], "t.toml:16: events event 0 needs `at_round` or `at_s`"),
        (
            &["at_round = 1\nat_s = 2\nclose = [[4, 1]]\n"],
            "t.toml:18: events.at_s event 0: give one of `at_round` and `at_s`, not both",
        ),
        (
            &["at_s = -1\nclose = [[4, 1]]\n"],
            "t.toml:17: events.at_s must be a finite number of seconds >= 0, got -1",
        ),
        (
            &["at_s = 1\n"],
            "t.toml:16: events event 0 must be exactly one of close, close_rect, open, open_rect and mover; it gives none",
        ),
        (
            &["at_s = 1\nclose = [[4, 1]]\nopen = [[1, 1]]\n"],
            "it gives close and open",
        ),
        (
            &["at_s = 1\nclose = [[4, 1]]\nspeed = 1\n"],
            "t.toml:16: events event 0: `path`, `speed`, `repeat` and `yields` are for a `mover`",
        ),
        (
            &["at_s = 1\nclose = [[4, 1]]\nyields = false\n"],
            "t.toml:16: events event 0: `path`, `speed`, `repeat` and `yields` are for a `mover`",
        ),
        (
            &["at_s = 2\nclose = [[4, 1]]\n", "at_s = 1\nclose = [[4, 2]]\n"],
            "t.toml:19: events happens at 1 s, before the event at line 16 (2 s); list the events in time order",
        ),
        (
            &["at_s = 1\nclose = [[6, 1]]\n"],
            "t.toml:18: events.close (6, 1) is outside the 6x4 map",
        ),
        (
            &["at_s = 1\nclose = [[1, 1]]\n"],
            "t.toml:18: events.close (1, 1) is a wall or closed already",
        ),
        (
            &["at_s = 1\nclose = [[5, 0]]\n"],
            "t.toml:18: events.close (5, 0) is agent 1's start: the robot would begin inside it",
        ),
        (
            &["at_s = 1\nclose = []\n"],
            "t.toml:18: events.close is empty; give at least one [x, y]",
        ),
        (
            &["at_s = 1\nclose_rect = [[5, 3], [4, 2]]\n"],
            "t.toml:18: events.close_rect the corners (5, 3) and (4, 2) are not top-left then bottom-right",
        ),
        (
            &["at_s = 1\nopen = [[4, 1]]\n"],
            "t.toml:18: events.open (4, 1) is free already: nothing to open",
        ),
        (
            &["at_s = 1\nmover = \"p\"\npath = [[0, 2], [2, 3]]\nspeed = 1\n"],
            "t.toml:19: events.path the leg from (0, 2) to (2, 3) is not along a row or a column",
        ),
        (
            &["at_s = 1\nmover = \"p\"\npath = [[1, 0], [1, 2]]\nspeed = 1\n"],
            "t.toml:19: events.path passes (1, 1), a wall or a closed cell",
        ),
        (
            &["at_s = 1\nmover = \"p\"\npath = [[2, 0], [0, 0]]\nspeed = 1\n"],
            "t.toml:19: events.path (0, 0) is agent 0's start: the robot would begin inside it",
        ),
        (
            &["at_s = 1\nmover = \"p\"\npath = [[0, 2]]\nspeed = 1\n"],
            "t.toml:19: events.path needs at least two corners, [[x0, y0], [x1, y1]]",
        ),
        (
            &["at_s = 1\nmover = \"p\"\npath = [[0, 2], [2, 2]]\nspeed = 0\n"],
            "t.toml:20: events.speed must be a positive number of cells per second, got 0",
        ),
        (
            &["at_s = 1\nmover = \"p\"\npath = [[0, 2], [2, 2]]\n"],
            "t.toml:16: events mover `p` (event 0) needs `path` and `speed`",
        ),
        (
            &[
                "at_s = 1\nmover = \"p\"\npath = [[0, 2], [2, 2]]\nspeed = 1\n",
                "at_s = 1\nmover = \"p\"\npath = [[0, 2], [2, 2]]\nspeed = 1\n",
            ],
            "t.toml:23: events.mover a mover is named `p` already",
        ),
        (
            &["at_s = 1\nclose = [[4, 2]]\n", "at_s = 2\nmover = \"p\"\npath = [[3, 2], [5, 2]]\nspeed = 1\n"],
            "t.toml:22: events.path passes (4, 2), a wall or a closed cell",
        ),
        (&["at_s = 1\nclos = [[4, 1]]\n"], "t.toml:18: unknown key `clos` (expected one of `at_round`, `at_s`, `close`"),
    ];
    for (bodies, want) in cases {
        let got = err(bodies);
        assert!(got.contains(want), "{bodies:?}:\n got  {got}\n want {want}");
    }
}

#[test]
fn events_change_the_hash_and_none_keep_it() {
    let base = parse(BASE).unwrap().scenario_hash();
    let none = events(&[]).unwrap().scenario_hash();
    assert_eq!(base, none);
    let close = events(&["at_s = 1\nclose = [[4, 1]]\n"]).unwrap();
    let later = events(&["at_s = 2\nclose = [[4, 1]]\n"]).unwrap();
    let open = events(&["at_s = 1\nopen = [[1, 1]]\n"]).unwrap();
    let mover = "at_s = 1\nmover = \"p\"\npath = [[0, 2], [2, 2]]\nspeed = 1\n";
    let yields = events(&[mover]).unwrap().scenario_hash();
    let said = events(&[&format!("{mover}yields = true\n")]).unwrap();
    assert_eq!(yields, said.scenario_hash(), "yielding is the default");
    let walks_on = events(&[&format!("{mover}yields = false\n")]).unwrap();
    let hashes = [
        base,
        close.scenario_hash(),
        later.scenario_hash(),
        open.scenario_hash(),
        yields,
        walks_on.scenario_hash(),
    ];
    for i in 0..hashes.len() {
        for j in i + 1..hashes.len() {
            assert_ne!(hashes[i], hashes[j], "{i} and {j}");
        }
    }
}

#[test]
fn hnav_check_lists_the_events() {
    let s = events(&[
        "at_round = 100\nclose = [[4, 1]]\n",
        "at_s = 3\nmover = \"forklift\"\npath = [[0, 2], [3, 2]]\nspeed = 0.5\n",
        "at_s = 4\nmover = \"cart\"\npath = [[0, 3], [1, 3]]\nspeed = 1\nyields = false\n",
    ])
    .unwrap();
    let text = ScenarioReport::new(&s).render();
    assert!(text.contains("event     at 1.00 s: close (4, 1)"), "{text}");
    assert!(
        text.contains(
            "event     at 3.00 s: mover `forklift` at 0.5 cells/s from (0, 2) over 4 cells\n"
        ),
        "{text}"
    );
    assert!(
        text.contains(
            "event     at 4.00 s: mover `cart` at 1 cells/s from (0, 3) over 2 cells, yielding \
             to no robot"
        ),
        "{text}"
    );
}
