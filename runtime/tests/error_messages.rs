//! Every class of malformed input to the readers the fuzz targets cover (`fuzz/`), with the
//! exact message a user sees: MovingAI `.map` and `.scen`, scenario TOML, and consensus logs
//! (reader errors, torn tails and the verifier's problems). Each table ends with a check that
//! it names every class, so a class added without a message test fails here.

use std::collections::BTreeSet;
use std::fs;
use std::path::Path;

use hnav_runtime::consensus_log::{
    encode_frame, read_log, segment_path, verify, AgentEntry, EndReason, EndRecord,
    LifecycleRecord, LoggedDecision, Record, ReplanRecord, RoundRecord, RunHeader, FORMAT_VERSION,
    MAGIC, REPLICATED_VERSION,
};
use hnav_runtime::grid::{read_map, read_map_file, read_scen, read_scen_file, validate_scen};
use hnav_runtime::msg::{Lifecycle, Role};
use hnav_runtime::scenario::Scenario;

/// The variant name at the start of an error's `Debug` form.
fn class(error: &impl std::fmt::Debug) -> String {
    format!("{error:?}")
        .chars()
        .take_while(|c| c.is_alphanumeric())
        .collect()
}

/// Collects (class, got, expected) and reports every mismatch at once.
#[derive(Default)]
struct Table {
    covered: BTreeSet<String>,
    mismatches: Vec<String>,
}

impl Table {
    fn check(&mut self, class: String, got: String, expected: &str) {
        if got != expected {
            self.mismatches
                .push(format!("{class}:\n   got: {got}\n  want: {expected}"));
        }
        self.covered.insert(class);
    }

    fn finish(self, classes: &[&str]) {
        assert!(
            self.mismatches.is_empty(),
            "wrong messages:\n{}",
            self.mismatches.join("\n")
        );
        let want: BTreeSet<String> = classes.iter().map(|c| c.to_string()).collect();
        assert_eq!(self.covered, want, "classes without a message test");
    }
}

const MAP: &str = "type octile\nheight 3\nwidth 4\nmap\n....\n.@@.\n....\n";

#[test]
fn every_map_and_scen_error_class_has_its_exact_message() {
    let mut t = Table::default();
    let mut map = |text: &str, expected: &str| {
        let e = read_map(text, "bad.map").expect_err(text);
        t.check(class(&e), e.to_string(), expected);
    };
    map(
        "type octile\nheight 3\nwidth 4\n",
        "bad.map:4: header ended before the `map` line (truncated header)",
    );
    map(
        "type octile\nheigth 3\nwidth 4\nmap\n",
        "bad.map:2: unrecognised header line \"heigth 3\" (expected `type octile`, `height N`, \
         `width N` or `map`)",
    );
    map(
        "type hex\nheight 3\nwidth 4\nmap\n",
        "bad.map:1: unsupported map type \"hex\", expected `octile`",
    );
    map(
        "type octile\nheight three\nwidth 4\nmap\n",
        "bad.map:2: bad height \"three\": not a positive integer",
    );
    map(
        "type octile\nheight 3\nmap\n....\n",
        "bad.map:3: `map` line reached but no `width` line was given",
    );
    map(
        "type octile\nheight 100000\nwidth 100000\nmap\n",
        "bad.map:4: a 100000x100000 grid is not supported (more than 67108864 cells)",
    );
    map(
        &MAP.replace(".@@.", ".@@"),
        "bad.map:6: row has 3 characters, expected 4",
    );
    map(
        "type octile\nheight 3\nwidth 4\nmap\n....\n.@@.\n",
        "bad.map:7: map ends after 2 rows, expected 3",
    );
    map(
        &format!("{MAP}....\n"),
        "bad.map:8: extra row after the 3 rows the header declares",
    );
    map(
        &MAP.replace(".@@.", ".@?."),
        "bad.map:6:3: unknown map character '?' (known: . G S W T @ O)",
    );
    let e = read_map_file("/nonexistent/bad.map").unwrap_err();
    t.check(
        class(&e),
        e.to_string(),
        "/nonexistent/bad.map: cannot read map file: No such file or directory (os error 2)",
    );

    let grid = read_map(MAP, "ok.map").unwrap();
    let entry = |fields: &str| format!("version 1\n{fields}\n");
    let mut scen = |text: &str, expected: &str| {
        let e = match read_scen(text, "bad.scen") {
            Err(e) => e,
            Ok(s) => validate_scen(&grid, &s).remove(0),
        };
        t.check(class(&e), e.to_string(), expected);
    };
    scen(
        "version 2\n",
        "bad.scen:1: expected `version 1` or `version 1.0`, found \"version 2\"",
    );
    scen(
        &entry("0\tok.map\t4\t3\t0\t0\t3"),
        "bad.scen:2: expected 9 tab-separated fields, found 7",
    );
    scen(
        &entry("0\tok.map\t4\t3\tx\t0\t3\t2\t3.0"),
        "bad.scen:2: field 5 (start_x) is not a non-negative integer: \"x\"",
    );
    scen(
        &entry("0\tok.map\t4\t3\t0\t0\t4\t2\t4.0"),
        "bad.scen:2: goal [4, 2] is outside the 4x3 map",
    );
    scen(
        &entry("0\tok.map\t4\t3\t1\t1\t3\t2\t2.4"),
        "bad.scen:2: start [1, 1] is on an obstacle ('@')",
    );
    scen(
        &entry("0\tok.map\t5\t3\t0\t0\t3\t2\t3.8"),
        "bad.scen:2: entry is for a 5x3 map but the map is 4x3",
    );
    let e = read_scen_file("/nonexistent/bad.scen").unwrap_err();
    let class_io = class(&e);
    t.covered.insert(class_io);
    assert_eq!(
        e.to_string(),
        "/nonexistent/bad.scen: cannot read scenario file: No such file or directory (os error 2)"
    );
    t.finish(&[
        "BadDimension",
        "BadField",
        "BadHeaderLine",
        "BadShape",
        "BadVersion",
        "FieldCount",
        "Io",
        "MissingDimension",
        "OnObstacle",
        "OutsideMap",
        "RowWidth",
        "SizeMismatch",
        "TooFewRows",
        "TooManyRows",
        "TruncatedHeader",
        "UnknownChar",
        "UnsupportedType",
    ]);
}

/// A scenario on a 4x3 map with one agent, `extra` appended, and `agent` as its agent table.
fn scenario(extra: &str, agent: &str) -> String {
    format!(
        "name = \"bad\"\n\n[map]\nrows = [\"....\", \".@@.\", \"....\"]\n\n[[agents]]\n{agent}\n{extra}"
    )
}

#[test]
fn every_scenario_error_class_has_its_exact_message() {
    let dir = tempfile::tempdir().unwrap();
    let mut t = Table::default();
    let ok_agent = "start = [0, 0]\ngoal = [3, 2]";
    let mut check = |text: &str, expected: &str| {
        let e = Scenario::from_str(text, "bad.toml", dir.path()).expect_err(text);
        t.check(class(&e), e.to_string(), expected);
    };
    check(
        "name = \"bad\"\n[map\n",
        "bad.toml:2: invalid table header\nexpected `.`, `]`",
    );
    check(
        &scenario("", &format!("{ok_agent}\ncolour = \"red\"")),
        "bad.toml:9: unknown key `colour` (expected one of `start`, `goal`, `speed`, \
         `priority`, `start_heading_deg`, `planner`)",
    );
    check(
        "[map]\nrows = [\"....\"]\n\n[[agents]]\nstart = [0, 0]\ngoal = [3, 0]\n",
        "bad.toml:1: missing key `name`",
    );
    check(
        &scenario("", ok_agent).replace("\"....\", \".@@.\"", "\"....\", \".@?.\""),
        "bad.toml:4:3: unknown map character '?' (known: . G S W T @ O)",
    );
    check(
        &scenario("", ok_agent).replace("rows =", "file = \"x.map\"\nrows ="),
        "bad.toml:3: [map] has both `file` and `rows`; give exactly one",
    );
    check(
        "name = \"bad\"\n\n[map]\ncorner_cutting = true\n\n[[agents]]\nstart = [0, 0]\ngoal = [3, 2]\n",
        "bad.toml:3: [map] needs `file = \"...\"` or `rows = [...]`",
    );
    check(
        &scenario("\n[sim]\nstep_ms = 0\n", ok_agent),
        "bad.toml:11: sim.step_ms must be at least 1",
    );
    check(
        "name = \"bad\"\n\n[map]\nrows = [\"....\"]\n",
        "bad.toml:1: the scenario has no [[agents]]",
    );
    check(
        &scenario("", "start = [0]\ngoal = [3, 2]"),
        "bad.toml:7: agent 0 start must be [x, y], got 1 numbers",
    );
    check(
        &scenario("", "start = [4, 0]\ngoal = [3, 2]"),
        "bad.toml:7: agent 0 start [4, 0] is outside the 4x3 map",
    );
    check(
        &scenario("", "start = [0, 0]\ngoal = [3, 3]"),
        "bad.toml:8: agent 0 goal [3, 3] is outside the 4x3 map",
    );
    check(
        &scenario("", "start = [1, 1]\ngoal = [3, 2]"),
        "bad.toml:7: agent 0 start [1, 1] is on an obstacle ('@')",
    );
    check(
        &scenario("", "start = [0, 0]\ngoal = [2, 1]"),
        "bad.toml:8: agent 0 goal [2, 1] is on an obstacle ('@')",
    );
    check(
        &scenario("[[agents]]\nstart = [0, 0]\ngoal = [0, 2]\n", ok_agent),
        "bad.toml:10: agent 1 starts at [0, 0], where agent 0 starts too",
    );
    check(
        &scenario("[[agents]]\nstart = [0, 2]\ngoal = [3, 2]\n", ok_agent),
        "bad.toml:11: agent 1 has goal [3, 2], which is agent 0's goal too",
    );
    check(
        &scenario("", &format!("{ok_agent}\nspeed = -1")),
        "bad.toml:9: agent 0 speed must be a positive number of cells/s, got -1",
    );
    check(
        &scenario("", &format!("{ok_agent}\nspeed = 1e9")),
        "bad.toml:9: agent 0 speed 1000000000 cells/s exceeds the robot's 2.625 cells/s \
         (max_wheel_speed_rad_s * wheel_radius_m / cell_size_m)",
    );
    check(
        &scenario("", &format!("{ok_agent}\npriority = 0")),
        "bad.toml:9: agent 0 priority must be a positive number, got 0",
    );
    check(
        &scenario(
            "\n[[faults]]\nat_round = 5\naction = \"kill\"\nrole = \"agent\"\nindex = 3\n",
            ok_agent,
        ),
        "bad.toml:14: fault 0 targets agent 3, but agents are numbered 0..1",
    );
    check(
        &scenario(
            "\n[[faults]]\nat_round = 5\naction = \"kill\"\nrole = \"agent\"\n",
            ok_agent,
        ),
        "bad.toml:10: fault 0: role = \"agent\" needs an `index`",
    );
    check(
        &scenario("", "start = [0, 0]\ngoal = [3, 2]").replace("\".@@.\"", "\"@@@@\""),
        "bad.toml:8: agent 0: goal [3, 2] is unreachable from start [0, 0] (write \
         allow_unreachable = true at the top of the scenario to run it anyway)",
    );
    let many: String = (0..4097)
        .map(|i| format!("[[agents]]\nstart = [{i}, 0]\ngoal = [{i}, 1]\n"))
        .collect();
    check(
        &format!(
            "name = \"bad\"\n\n[map]\nrows = [\"{0}\", \"{0}\"]\n\n{many}",
            ".".repeat(4097)
        ),
        "bad.toml:12294: 4097 agents, but a run holds at most 4096",
    );
    let small = Scenario::from_str(&scenario("", ok_agent), "small.toml", dir.path()).unwrap();
    let e = small.with_agent_count(50, 1).unwrap_err();
    t.check(
        class(&e),
        e.to_string(),
        "small.toml: cannot place 50 agents: only 10 distinct start/goal pairs fit the map",
    );
    let e = Scenario::load(dir.path().join("missing.toml")).unwrap_err();
    let io = e
        .to_string()
        .replace(&dir.path().display().to_string(), "DIR");
    t.check(
        class(&e),
        io,
        "DIR/missing.toml: cannot read scenario file: No such file or directory (os error 2)",
    );
    t.finish(&[
        "BadCoordinates",
        "BadFault",
        "BadPriority",
        "DuplicateGoal",
        "DuplicateStart",
        "FaultAgentOutOfRange",
        "GoalOnObstacle",
        "GoalOutsideMap",
        "InvalidParameter",
        "Io",
        "Map",
        "MapFileAndRows",
        "MissingKey",
        "NoAgents",
        "NoMapSource",
        "NonPositiveSpeed",
        "NotEnoughFreeCells",
        "SpeedTooHigh",
        "StartOnObstacle",
        "StartOutsideMap",
        "Toml",
        "TooManyAgents",
        "UnknownKey",
        "UnreachableGoal",
    ]);
}

fn header() -> Record {
    Record::Header(RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: 1,
        seed: 1,
        clock: "lockstep".into(),
        width: 4,
        height: 3,
        agents: vec![AgentEntry {
            start: 0,
            goal: 11,
            speed: 1.0,
            priority: 1.0,
        }],
    })
}

fn round(r: u64, agent: u32, verdict: u8) -> Record {
    Record::Round(RoundRecord {
        round: r,
        candidates: 1,
        candidates_digest: 0,
        decisions: vec![LoggedDecision {
            agent,
            verdict,
            refused: 0,
            kind: 0,
            cell: 1,
            waypoint: u32::MAX,
        }],
    })
}

fn end(r: u64) -> Record {
    Record::End(EndRecord {
        round: r,
        at_goal: 1,
        reason: EndReason::AllAtGoal,
    })
}

fn frame(record: &Record) -> Vec<u8> {
    let mut buf = Vec::new();
    encode_frame(record, &mut buf).unwrap();
    buf
}

fn segment(records: &[Record]) -> Vec<u8> {
    let mut bytes = MAGIC.to_vec();
    for r in records {
        bytes.extend_from_slice(&frame(r));
    }
    bytes
}

/// A log directory of `segments`, numbered from 0.
fn log_dir(segments: &[Vec<u8>]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (i, s) in segments.iter().enumerate() {
        fs::write(segment_path(dir.path(), i as u32), s).unwrap();
    }
    dir
}

fn in_dir(message: String, dir: &Path) -> String {
    message.replace(&dir.display().to_string(), "DIR")
}

#[test]
fn every_log_error_class_has_its_exact_message() {
    let good = || vec![header(), round(1, 0, 1), end(1)];
    let first_len = frame(&header()).len();
    let mut t = Table::default();
    let mut error = |segments: Vec<Vec<u8>>, expected: &str| {
        let dir = log_dir(&segments);
        let e = read_log(dir.path()).expect_err(expected);
        let message = in_dir(e.to_string(), dir.path());
        assert_eq!(
            verify(dir.path()).problems,
            vec![e.to_string()],
            "verify reports the reader's error"
        );
        let class = match &e {
            hnav_runtime::consensus_log::LogError::Corrupt { problem, .. } => {
                format!("Corrupt/{}", class(problem))
            }
            other => class(other),
        };
        t.check(class, message, expected);
    };
    error(
        vec![],
        "DIR: no consensus-log segments (seg-00000000.hlog missing)",
    );
    let mut bad_magic = segment(&good());
    bad_magic[7] = b'2';
    error(
        vec![bad_magic],
        "DIR/seg-00000000.hlog: byte 0: not a consensus-log segment (missing or unknown magic)",
    );
    let mut bad_crc = segment(&good());
    bad_crc[MAGIC.len() + 10] ^= 1;
    error(
        vec![bad_crc],
        "DIR/seg-00000000.hlog: byte 8: corrupt: checksum mismatch (stored 0xa145659a, computed 0x9ce3b551)",
    );
    let mut bad_len = segment(&good());
    bad_len[MAGIC.len()..MAGIC.len() + 4].copy_from_slice(&0u32.to_le_bytes());
    error(
        vec![bad_len],
        "DIR/seg-00000000.hlog: byte 8: corrupt: impossible record length 0",
    );
    let garbage = [0xFFu8; 6];
    let mut undecodable = segment(&good()[..1]);
    undecodable.extend_from_slice(&(garbage.len() as u32).to_le_bytes());
    undecodable.extend_from_slice(&crc32c::crc32c(&garbage).to_le_bytes());
    undecodable.extend_from_slice(&garbage);
    undecodable.extend_from_slice(&frame(&end(0)));
    error(
        vec![undecodable],
        &format!(
            "DIR/seg-00000000.hlog: byte {}: corrupt: undecodable record: a malformed integer",
            MAGIC.len() + first_len
        ),
    );
    let mut short = segment(&good());
    short.truncate(short.len() - 3);
    error(
        vec![short.clone(), segment(&[round(2, 0, 1)])],
        "DIR/seg-00000000.hlog: byte 73: corrupt: record length 4 runs past the end of the file \
         (1 bytes left)",
    );
    error(
        vec![segment(&good()[1..])],
        "DIR/seg-00000000.hlog: byte 8: the first record is a round record, not a header",
    );
    let mut other = good();
    if let Record::Header(h) = &mut other[0] {
        h.version = REPLICATED_VERSION + 1;
    }
    error(
        vec![segment(&other)],
        "DIR/seg-00000000.hlog: byte 8: log format version 3, this build reads versions 1 and 2",
    );
    let dir = log_dir(&[segment(&good())]);
    fs::rename(segment_path(dir.path(), 0), segment_path(dir.path(), 2)).unwrap();
    let e = read_log(dir.path()).unwrap_err();
    t.check(
        class(&e),
        in_dir(e.to_string(), dir.path()),
        "DIR: segment seg-00000000.hlog missing (found segment 2 instead)",
    );
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(segment_path(dir.path(), 0)).unwrap();
    let e = read_log(dir.path()).unwrap_err();
    t.check(
        class(&e),
        in_dir(e.to_string(), dir.path()),
        "DIR/seg-00000000.hlog: Is a directory (os error 21)",
    );
    t.finish(&[
        "BadMagic",
        "Corrupt/BadChecksum",
        "Corrupt/BadLength",
        "Corrupt/LengthPastEnd",
        "Corrupt/Undecodable",
        "Io",
        "NoHeader",
        "NoSegments",
        "SegmentGap",
        "Version",
    ]);
}

#[test]
fn every_torn_tail_and_verify_problem_has_its_exact_message() {
    let good = vec![header(), round(1, 0, 1), end(1)];
    let intact = segment(&good);
    let last_at = intact.len() - frame(&end(1)).len();
    let mut t = Table::default();
    let mut torn = |bytes: Vec<u8>, expected: &str| {
        let dir = log_dir(&[bytes]);
        let contents = read_log(dir.path()).unwrap();
        let tail = contents.torn.expect(expected);
        let got = format!("byte {}: {}", tail.offset, tail.problem);
        t.check(class(&tail.problem), got, expected);
    };
    torn(
        MAGIC[..5].to_vec(),
        "byte 0: only 5 of 8 segment magic bytes",
    );
    torn(
        intact[..intact.len() - frame(&end(1)).len() + 3].to_vec(),
        &format!("byte {last_at}: only 3 of 8 record header bytes"),
    );
    torn(
        intact[..intact.len() - 2].to_vec(),
        &format!("byte {last_at}: record length 4 runs past the end of the file (2 bytes left)"),
    );
    let mut last_crc = intact.clone();
    let n = last_crc.len();
    last_crc[n - 1] ^= 1;
    torn(
        last_crc,
        &format!("byte {last_at}: checksum mismatch (stored 0x85a6703d, computed 0x77cdf33e)"),
    );
    let mut zeros = intact.clone();
    zeros.extend_from_slice(&[0; 20]);
    torn(
        zeros,
        &format!(
            "byte {}: 20 zero bytes up to the end of the file",
            intact.len()
        ),
    );

    let mut problems = |what: &str, records: Vec<Record>, expected: &[&str]| {
        let dir = log_dir(&[segment(&records)]);
        let report = verify(dir.path());
        t.check(
            what.into(),
            report.problems.join(" | "),
            &expected.join(" | "),
        );
    };
    problems(
        "second-header",
        vec![header(), round(1, 0, 1), header(), end(1)],
        &["seg-00000000.hlog byte 73: a second header record"],
    );
    problems(
        "round-gap",
        vec![header(), round(1, 0, 1), round(3, 0, 1), end(3)],
        &["seg-00000000.hlog byte 73: round 2 is missing (round 3 follows round 1)"],
    );
    problems(
        "first-round-missing-then-repeated",
        vec![header(), round(2, 0, 1), round(2, 0, 1)],
        &[
            "seg-00000000.hlog byte 50: round 1 is missing (round 2 follows round 0)",
            "seg-00000000.hlog byte 73: round 2 after round 2",
        ],
    );
    problems(
        "agent-out-of-range",
        vec![header(), round(1, 4, 1), end(1)],
        &["seg-00000000.hlog byte 50: agent 4 of a run of 1 agents"],
    );
    problems(
        "unknown-verdict",
        vec![header(), round(1, 0, 9), end(1)],
        &["seg-00000000.hlog byte 50: agent 0: unknown verdict 9"],
    );
    problems(
        "record-at-wrong-round",
        vec![
            header(),
            round(1, 0, 1),
            Record::Lifecycle(LifecycleRecord::new(5, &Lifecycle::down(Role::Agent, 0, 0))),
            end(1),
        ],
        &[
            "seg-00000000.hlog byte 73: lifecycle record for round 5, but the last round logged \
           before it is 1 (expected round 1)",
        ],
    );
    problems(
        "after-end",
        vec![
            header(),
            round(1, 0, 1),
            end(1),
            Record::Replan(ReplanRecord {
                round: 2,
                agent: 0,
                planner: "a-star".into(),
                found: false,
                waypoints: vec![],
            }),
            end(1),
        ],
        &[
            "seg-00000000.hlog byte 85: replan record after the end record",
            "seg-00000000.hlog byte 105: a second end record",
        ],
    );
    t.finish(&[
        "BadChecksum",
        "LengthPastEnd",
        "ShortHeader",
        "ShortMagic",
        "ZeroFill",
        "after-end",
        "agent-out-of-range",
        "first-round-missing-then-repeated",
        "record-at-wrong-round",
        "round-gap",
        "second-header",
        "unknown-verdict",
    ]);
}
