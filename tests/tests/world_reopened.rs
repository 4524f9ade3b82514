//! A door that closes and opens again while the only robot to see it shut is gone (issue 35;
//! robot 14 of `hnav-bench experiment dynamic --robots 50`, rebuild variant). Robot 0 sees
//! the door close and reports it; the coordinator closes it on its map. The door opens again
//! out of everyone's sight. Robot 1 comes along the corridor later: its map has the door open
//! (it never saw it shut), so seeing it open was no news to it, and the coordinator kept it
//! closed. Under PIBT robot 1 was redirected back along the coordinator's way beside the
//! door and came forward again on its own map's, until the time limit. Now the coordinator
//! holds its step as invalid, robot 1 takes that as the coordinator's word on the cell and
//! reports the door open when it sees it so; both arrive, and the run repeats byte for byte.

use hnav_runtime::consensus_log::{read_decided, MapChangeRecord, Record};
use hnav_tests::swarm::lockstep_all_home;

/// The door: (10, 0) of a 30-cell-wide map.
const DOOR: u32 = 10;

const SCENARIO: &str = r#"
name = "door-reopened"

[map]
rows = [
  "..............................",
  ".@@@@@@@@@@@@@@@@@@@@@@@@@@@@.",
  "..............................",
]

[sim]
clock = "lockstep"
seed = 1

[coordinator]
rules = "pibt"
time_limit_s = 60

[sensing]
range = 3

# Robot 0 stands next to the door when it closes and drives away from it (75 rounds a cell).
[[events]]
at_round = 50
close = [[10, 0]]

# Robot 0 is out of range by now, and robot 1 (19 cells away at the start) still is.
[[events]]
at_round = 700
open = [[10, 0]]

[[agents]]
start = [9, 0]
goal = [0, 2]

[[agents]]
start = [29, 0]
goal = [1, 0]
"#;

#[test]
fn a_door_that_reopened_unseen_is_reported_open_by_the_robot_held_at_it() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = tmp.path().join("door-reopened.toml");
    std::fs::write(&scenario, SCENARIO).unwrap();
    let registry = tmp.path().join("runs");
    let mut logs = Vec::new();
    for k in 0..2 {
        let dir = tmp.path().join(format!("run{k}"));
        // Exit 0 and every robot home: before, robot 1 paced beside the door to the limit.
        let (_, log) = lockstep_all_home(&format!("reopened{k}"), &scenario, &dir, &registry, 2);
        logs.push(log);
        let changes: Vec<(u32, Vec<u32>, Vec<u32>)> = read_decided(dir.join("log"))
            .unwrap()
            .records
            .into_iter()
            .filter_map(|r| match r {
                Record::MapChange(MapChangeRecord {
                    agent,
                    closed,
                    opened,
                    ..
                }) => Some((agent, closed, opened)),
                _ => None,
            })
            .collect();
        assert_eq!(
            changes,
            [(0, vec![DOOR], vec![]), (1, vec![], vec![DOOR])],
            "closed as robot 0 saw it, opened as robot 1 saw it"
        );
    }
    assert!(logs[0] == logs[1], "the two lockstep logs differ");
}
