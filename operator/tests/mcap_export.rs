//! `hnav_operator::export::export_mcap` on a run directory made of fixtures: a scenario and
//! its `invocation.json`, a log written by the log's own writer, and recording files written
//! by the recording's writers. The MCAP file is read back with the `mcap` crate: the channel
//! set, each channel's schema and encodings, and the message counts must be what the
//! fixtures hold.

use std::collections::BTreeMap;
use std::path::Path;

use hnav_operator::export::export_mcap;
use hnav_operator::invocation::Invocation;
use hnav_operator::recording::{
    self, MapWriter, PoseSample, PoseSource, TrajectoryHeader, TrajectoryWriter,
};
use hnav_runtime::consensus_log::{
    AgentEntry, EndReason, EndRecord, LifecycleRecord, LogWriter, LoggedDecision, Record,
    ReplanRecord, RoundRecord, RunHeader, FORMAT_VERSION,
};
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{
    ActivationKind, ConflictKind, Lifecycle, MapHeader, Role, Verdict, NO_CELL,
};
use hnav_runtime::scenario::FsyncPolicy;

const SCENARIO: &str = r#"
name = "fixture"
[map]
rows = ["....",
        ".@..",
        "...."]
[[agents]]
start = [0, 0]
goal = [3, 2]
[[agents]]
start = [3, 0]
goal = [0, 2]
"#;
const ROUNDS: u64 = 5;
const WIDTH: u32 = 4;
const HEIGHT: u32 = 3;

fn decision(agent: u32, verdict: Verdict, cell: u32) -> LoggedDecision {
    LoggedDecision {
        agent,
        verdict: verdict as u8,
        refused: 0,
        kind: ConflictKind::None as u8,
        cell,
        waypoint: NO_CELL,
    }
}

/// A run directory with a scenario, its invocation and a log of `ROUNDS` rounds of two
/// decisions each (agent 0 moving, agent 1 held), one replan, agent 1 killed and restarted
/// after round 4 (as `hnav kill RUN agent:1` and the supervisor log it) and an end.
fn run_dir(dir: &Path) {
    let scenario_path = dir.join("fixture.toml");
    std::fs::write(&scenario_path, SCENARIO).unwrap();
    let args = ProcessArgs::new("fixture", scenario_path);
    let scenario = args.scenario().unwrap();
    Invocation::new(&args, &scenario).write(dir).unwrap();
    let (mut log, _) = LogWriter::open(dir.join("log"), FsyncPolicy::None).unwrap();
    let agents = scenario
        .agents
        .iter()
        .map(|a| AgentEntry {
            start: a.start.y * WIDTH + a.start.x,
            goal: a.goal.y * WIDTH + a.goal.x,
            speed: a.speed,
            priority: a.effective_priority(),
        })
        .collect();
    log.append(&Record::Header(RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: scenario.scenario_hash(),
        seed: scenario.sim.seed,
        clock: "lockstep".into(),
        width: WIDTH,
        height: HEIGHT,
        agents,
    }))
    .unwrap();
    for round in 1..=ROUNDS {
        if round == 3 {
            log.append(&Record::Replan(ReplanRecord {
                round,
                agent: 1,
                planner: "lazy-theta-star".into(),
                found: true,
                waypoints: vec![3, 11],
            }))
            .unwrap();
        }
        log.append(&Record::Round(RoundRecord {
            round,
            candidates: 2,
            candidates_digest: round,
            decisions: vec![
                decision(0, Verdict::Accept, round as u32),
                decision(1, Verdict::Hold, NO_CELL),
            ],
        }))
        .unwrap();
        if round == 4 {
            for event in [
                Lifecycle::down(Role::Agent, 1, 0),
                Lifecycle::restarted(Role::Agent, 1, 1),
            ] {
                log.append(&Record::Lifecycle(LifecycleRecord::new(round, &event)))
                    .unwrap();
            }
        }
    }
    log.append(&Record::End(EndRecord {
        round: ROUNDS,
        at_goal: 2,
        reason: EndReason::AllAtGoal,
    }))
    .unwrap();
}

/// Recording files: `poses` samples per robot and source, `maps` snapshots of agent 0 and
/// one of agent 1.
fn recording(dir: &Path, poses: u64, maps: u64) {
    let rec = dir.join(recording::DIR);
    std::fs::create_dir_all(&rec).unwrap();
    let header = TrajectoryHeader {
        robots: 2,
        rate_hz: 20,
        cell_size_m: 0.16,
        width: WIDTH,
        height: HEIGHT,
        truncated: false,
        control_period_us: 10_000,
        movers: 0,
    };
    let mut t =
        TrajectoryWriter::create(&rec.join(recording::TRAJECTORIES), header, 1 << 20).unwrap();
    for i in 0..poses {
        for robot in 0..2 {
            for source in [PoseSource::Truth, PoseSource::Estimate] {
                t.push(&PoseSample {
                    t_ns: i * 50_000_000,
                    robot,
                    source,
                    x_m: 0.08 + i as f32 * 0.01,
                    y_m: 0.08,
                    theta_rad: std::f32::consts::FRAC_PI_2,
                })
                .unwrap();
            }
        }
    }
    t.finish().unwrap();
    let mut m = MapWriter::create(&rec.join(recording::MAPS), 1 << 20).unwrap();
    let cells = (WIDTH * HEIGHT) as usize;
    for i in 0..maps + 1 {
        let agent = u32::from(i == maps);
        let header = MapHeader {
            round: i,
            agent,
            width: WIDTH,
            height: HEIGHT,
            iterations: 7,
            target: 11,
            activation: ActivationKind::Tanh as u8,
            reserved: [0; 3],
        };
        let values: Vec<f32> = (0..cells).map(|c| 0.5f32.powi(c as i32)).collect();
        m.push(i * 10_000_000, &header, &values).unwrap();
    }
    m.finish().unwrap();
}

/// Per topic: (schema name, schema encoding, message encoding, messages), read back.
fn read_back(path: &Path) -> BTreeMap<String, (String, String, String, u64)> {
    let bytes = std::fs::read(path).unwrap();
    let mut out = BTreeMap::new();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    for c in summary.channels.values() {
        let schema = c.schema.as_ref().expect("every channel has a schema");
        out.insert(
            c.topic.clone(),
            (
                schema.name.clone(),
                schema.encoding.clone(),
                c.message_encoding.clone(),
                0,
            ),
        );
    }
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        serde_json::from_slice::<serde_json::Value>(&m.data).expect("JSON messages");
        out.get_mut(&m.channel.topic).unwrap().3 += 1;
    }
    out
}

fn counts(topics: &BTreeMap<String, (String, String, String, u64)>) -> BTreeMap<&str, (&str, u64)> {
    topics
        .iter()
        .map(|(t, (schema, s_enc, m_enc, n))| {
            assert_eq!(
                (s_enc.as_str(), m_enc.as_str()),
                ("jsonschema", "json"),
                "{t}"
            );
            (t.as_str(), (schema.as_str(), *n))
        })
        .collect()
}

#[test]
fn every_channel_reads_back_with_its_schema_and_count() {
    let tmp = tempfile::tempdir().unwrap();
    run_dir(tmp.path());
    recording(tmp.path(), 6, 3);
    let out = tmp.path().join("run.mcap");
    let report = export_mcap(tmp.path(), &out).unwrap();
    assert!(report.notes.is_empty(), "{:?}", report.notes);
    let topics = read_back(&out);
    let pose = "foxglove.PoseInFrame";
    let expected: BTreeMap<&str, (&str, u64)> = [
        ("/map", ("foxglove.Grid", 1)),
        // The live view's channels: a scene and a speed per sampling time (6), a log line
        // per accepted move (agent 0, every round) and per process event (2).
        ("/scene", ("foxglove.SceneUpdate", 6)),
        ("/robots/0/stats", ("hnav.RobotStats", 6)),
        ("/robots/1/stats", ("hnav.RobotStats", 6)),
        ("/log", ("foxglove.Log", ROUNDS + 2)),
        ("/robots/0/truth", (pose, 6)),
        ("/robots/0/estimate", (pose, 6)),
        ("/robots/1/truth", (pose, 6)),
        ("/robots/1/estimate", (pose, 6)),
        ("/robots/0/neural_map", ("foxglove.Grid", 3)),
        ("/robots/1/neural_map", ("foxglove.Grid", 1)),
        ("/commits", ("hnav.CommittedCells", ROUNDS)),
        ("/decisions", ("hnav.Decision", 2 * ROUNDS)),
        ("/replans", ("hnav.Replan", 1)),
        ("/lifecycle", ("hnav.Lifecycle", 2)),
    ]
    .into_iter()
    .collect();
    assert_eq!(counts(&topics), expected);
    let reported: BTreeMap<&str, (&str, u64)> = report
        .channels
        .iter()
        .map(|(t, (s, n))| (t.as_str(), (s.as_str(), *n)))
        .collect();
    assert_eq!(reported, expected);
}

#[test]
fn messages_carry_simulated_time_and_foxglove_shapes() {
    let tmp = tempfile::tempdir().unwrap();
    run_dir(tmp.path());
    recording(tmp.path(), 2, 1);
    let out = tmp.path().join("run.mcap");
    export_mcap(tmp.path(), &out).unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let mut seen = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        seen.entry(m.channel.topic.clone())
            .or_insert((m.log_time, v));
    }
    // Round 1 is decided once one 10 ms period has been simulated.
    let (t, commit) = &seen["/commits"];
    assert_eq!(*t, 10_000_000);
    assert_eq!(
        commit["cells"],
        serde_json::json!([{"agent": 0, "cell": [1, 0]}])
    );
    let (t, decision) = &seen["/decisions"];
    assert_eq!(*t, 10_000_000);
    assert_eq!(decision["verdict"], "accept");
    assert_eq!(
        decision["timestamp"],
        serde_json::json!({"sec": 0, "nsec": 10_000_000})
    );
    let (_, replan) = &seen["/replans"];
    assert_eq!(replan["waypoints"], serde_json::json!([[3, 0], [3, 2]]));
    let (_, pose) = &seen["/robots/1/truth"];
    assert_eq!(pose["frame_id"], "map");
    let q = &pose["pose"]["orientation"];
    let yaw = 2.0 * q["z"].as_f64().unwrap().atan2(q["w"].as_f64().unwrap());
    assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-6, "{pose}");
    let (_, grid) = &seen["/robots/0/neural_map"];
    assert_eq!(grid["column_count"], WIDTH);
    assert_eq!(grid["cell_stride"], 8);
    assert_eq!(grid["row_stride"], 8 * WIDTH);
    use base64::Engine as _;
    let data = base64::engine::general_purpose::STANDARD
        .decode(grid["data"].as_str().unwrap())
        .unwrap();
    assert_eq!(data.len(), 8 * (WIDTH * HEIGHT) as usize);
    let f = |i: usize| f32::from_le_bytes(data[i..i + 4].try_into().unwrap());
    // Cell 2 holds 0.25: its activation, then its log10.
    assert_eq!(f(16), 0.25);
    assert!((f(20) - 0.25f32.log10()).abs() < 1e-6);
    let (_, map) = &seen["/map"];
    let occupied = base64::engine::general_purpose::STANDARD
        .decode(map["data"].as_str().unwrap())
        .unwrap();
    assert_eq!(occupied, [0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0]);
}

#[test]
fn missing_recording_files_leave_the_log_channels_and_say_so() {
    let tmp = tempfile::tempdir().unwrap();
    run_dir(tmp.path());
    let out = tmp.path().join("run.mcap");
    let report = export_mcap(tmp.path(), &out).unwrap();
    let notes = report.notes.join("\n");
    assert!(notes.contains("trajectories.bin missing"), "{notes}");
    assert!(notes.contains("maps.bin missing"), "{notes}");
    let topics: Vec<String> = read_back(&out).into_keys().collect();
    assert_eq!(
        topics,
        ["/commits", "/decisions", "/lifecycle", "/map", "/replans"]
    );
}

#[test]
fn a_damaged_recording_names_the_file_and_offset_and_leaves_no_output() {
    let tmp = tempfile::tempdir().unwrap();
    run_dir(tmp.path());
    recording(tmp.path(), 2, 2);
    let maps = tmp.path().join(recording::DIR).join(recording::MAPS);
    let mut bytes = std::fs::read(&maps).unwrap();
    // A value of the first snapshot: its checksum no longer matches, and more follows.
    bytes[8 + 8 + 40 + 4] ^= 0xff;
    std::fs::write(&maps, bytes).unwrap();
    let out = tmp.path().join("run.mcap");
    let e = export_mcap(tmp.path(), &out).unwrap_err().to_string();
    assert!(e.contains("maps.bin: at byte 8:"), "{e}");
    assert!(!out.exists());
}

#[test]
fn a_kill_and_its_restart_are_on_the_lifecycle_channel() {
    let tmp = tempfile::tempdir().unwrap();
    run_dir(tmp.path());
    let out = tmp.path().join("run.mcap");
    export_mcap(tmp.path(), &out).unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let channel = summary
        .channels
        .values()
        .find(|c| c.topic == "/lifecycle")
        .expect("a /lifecycle channel");
    let schema = channel.schema.as_ref().unwrap();
    assert_eq!(schema.name, "hnav.Lifecycle");
    let schema: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
    for field in [
        "round", "process", "role", "index", "event", "restarts", "cell",
    ] {
        assert!(
            schema["properties"].get(field).is_some(),
            "{field}: {schema}"
        );
    }
    let events: Vec<(u64, serde_json::Value)> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic == "/lifecycle")
        .map(|m| (m.log_time, serde_json::from_slice(&m.data).unwrap()))
        .collect();
    // Logged after round 4, at 4 control periods of 10 ms; agent 1 held at its start [3, 0].
    let expect = |event: &str, restarts: u32| {
        serde_json::json!({
            "timestamp": {"sec": 0, "nsec": 40_000_000},
            "round": 4, "process": "agent-1", "role": "agent", "index": 1,
            "event": event, "restarts": restarts, "cell": [3, 0],
        })
    };
    assert_eq!(
        events,
        vec![
            (40_000_000, expect("down", 0)),
            (40_000_000, expect("restarted", 1))
        ]
    );
}
