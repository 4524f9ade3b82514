//! The demo's recording and report, end to end: `hnav run scenarios/demo.toml` (lockstep)
//! writes `DIR/recording/` with the expected sample counts and `DIR/report.svg` with every
//! element the report promises, counted against the consensus log's numbers; `hnav report
//! DIR --agents 0,3` draws two heatmaps.

use std::path::Path;
use std::time::Duration;

use hnav_operator::recording::{self, MapReader, PoseSource, TrajectoryReader};
use hnav_operator::report::{layout::Panel, Layout};
use hnav_runtime::scenario::Scenario;
use hnav_tests::swarm::{hnav_output, repo_root, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(120);

/// The SVG's elements of one tag.
fn elements<'a>(doc: &'a roxmltree::Document<'a>, tag: &str) -> Vec<roxmltree::Node<'a, 'a>> {
    doc.descendants()
        .filter(|n| n.tag_name().name() == tag)
        .collect()
}

fn num(n: &roxmltree::Node<'_, '_>, attr: &str) -> f64 {
    n.attribute(attr)
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN)
}

/// Filled rectangles whose top-left corner lies on `panel`.
fn cells_on(doc: &roxmltree::Document<'_>, panel: &Panel) -> usize {
    elements(doc, "rect")
        .iter()
        .filter(|r| r.attribute("fill") != Some("none"))
        .filter(|r| panel.contains(num(r, "x"), num(r, "y")))
        .count()
}

fn sum(summary: &serde_json::Value, key: &str) -> u64 {
    summary["agents"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a[key].as_u64().unwrap())
        .sum()
}

#[test]
fn the_demo_records_its_run_and_draws_every_element_of_its_report() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let dir = tmp.path().join("demo");
    let scenario_path = repo_root().join("scenarios/demo.toml");
    let scenario = Scenario::load(&scenario_path).unwrap();
    let mut run = TestRun::new("report");
    let mut swarm = SwarmRun::start(
        &mut run,
        &scenario_path,
        &dir,
        &registry,
        &["--mode", "lockstep"],
    )
    .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let summary = swarm.summary().unwrap();
    assert!(summary.get("report_error").is_none(), "{summary}");
    check_recording(&dir, &scenario, &summary);
    check_report(&dir, &scenario, &summary);
    check_redraw(&dir, &registry);
}

/// Truth samples: one per robot per 1/20 s of simulated time; estimates about as many; at
/// least one neural map per agent; the summary's counts are the files'.
fn check_recording(dir: &Path, scenario: &Scenario, summary: &serde_json::Value) {
    let rec = dir.join(recording::DIR);
    let r = TrajectoryReader::open(&rec.join(recording::TRAJECTORIES)).unwrap();
    let h = *r.header();
    assert_eq!((h.robots, h.rate_hz, h.truncated), (6, 20, false));
    let (samples, torn) = r.read_all().unwrap();
    assert_eq!(torn, 0);
    let truth = samples
        .iter()
        .filter(|s| s.source == PoseSource::Truth)
        .count() as u64;
    let estimates = samples.len() as u64 - truth;
    let rounds = summary["rounds"].as_u64().unwrap();
    let sim_s = rounds as f64 * scenario.sim.control_period_s();
    let expected = (sim_s * 20.0).floor() as u64 * 6;
    let recorded = &summary["recording"];
    assert_eq!(
        recorded["truth_samples"].as_u64(),
        Some(truth),
        "{recorded}"
    );
    assert_eq!(recorded["estimate_samples"].as_u64(), Some(estimates));
    let missed = recorded["missed"].as_u64().unwrap();
    // Every boundary is sampled unless the recorder lost truth messages (counted).
    assert!(
        truth + 6 >= expected && truth <= expected + 12,
        "{truth} truth samples for {sim_s} s of 6 robots at 20 Hz ({expected}), {missed} missed"
    );
    // An estimate the recorder did not read before the agent's next overwrote it leaves
    // its sampling time out (counted: a busy machine's run once recorded 6077 of 6228).
    let estimates_missed = recorded["estimates_missed"].as_u64().unwrap();
    assert!(
        estimates + estimates_missed + 12 * 6 >= expected,
        "{estimates} estimates and {estimates_missed} missed for {expected} expected"
    );
    let (maps, torn) = MapReader::open(&rec.join(recording::MAPS))
        .unwrap()
        .read_all()
        .unwrap();
    assert_eq!(torn, 0);
    assert_eq!(recorded["map_snapshots"].as_u64(), Some(maps.len() as u64));
    for a in 0..6 {
        assert!(
            maps.iter()
                .any(|m| m.header.agent == a && m.values.len() == 144),
            "no 12 x 12 snapshot of agent {a}"
        );
    }
}

fn check_report(dir: &Path, scenario: &Scenario, summary: &serde_json::Value) {
    let text = std::fs::read_to_string(dir.join("report.svg")).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let robots = scenario.agents.len();
    let layout = Layout::new(12, 12, 1, robots);
    // One trajectory per robot.
    assert_eq!(elements(&doc, "polyline").len(), robots);
    // The legend draws one of each marker besides the run's.
    let filled_circles = elements(&doc, "circle")
        .iter()
        .filter(|c| c.attribute("fill") != Some("none"))
        .count() as u64;
    assert_eq!(filled_circles, sum(summary, "steps") + 1, "committed cells");
    let conflicts = sum(summary, "conflicts");
    assert!(conflicts > 0);
    assert_eq!(elements(&doc, "line").len() as u64, 2 * (conflicts + 1));
    // Replan triangles and the legend's triangle and agent-down diamond (no process died).
    assert_eq!(
        elements(&doc, "polygon").len() as u64,
        sum(summary, "replans") + 2
    );
    let rings = elements(&doc, "circle")
        .iter()
        .filter(|c| c.attribute("fill") == Some("none"))
        .count();
    assert_eq!(summary["collisions"].as_u64(), Some(0));
    assert_eq!(rings, 1, "no collision, only the legend's ring");
    // On the map, filled squares are the obstacles and the starts (goals are outlines).
    assert_eq!(
        cells_on(&doc, &layout.map),
        scenario.map.grid.blocked_count() + robots
    );
    assert_eq!(
        cells_on(&doc, &layout.heatmaps[0]),
        144,
        "agent 0's heatmap"
    );
    // plotters puts a text's content on a line of its own.
    let texts: Vec<&str> = elements(&doc, "text")
        .iter()
        .filter_map(|t| t.text())
        .map(str::trim)
        .collect();
    assert!(
        texts
            .iter()
            .any(|t| t.starts_with("agent 0 neural map after round")),
        "{texts:?}"
    );
    assert_eq!(summary["rules"], "dissertation");
    assert!(
        texts
            .iter()
            .any(|t| t.starts_with("6 robots, dissertation rules, ")),
        "the title names the rules: {texts:?}"
    );
    // The cell coordinates along the edges: 0 to 11 once for x and once for y.
    for n in 0..12 {
        let label = n.to_string();
        assert!(
            texts.iter().filter(|t| **t == label).count() >= 2,
            "{n}: {texts:?}"
        );
    }
    for i in 0..robots {
        assert!(texts.contains(&format!("robot {i}").as_str()), "{texts:?}");
    }
}

/// `hnav report DIR --agents 0,3 --out FILE` draws two heatmaps; an agent the run does not
/// have is refused by name.
fn check_redraw(dir: &Path, registry: &Path) {
    let out = dir.join("two.svg");
    let args = |agents: &str| {
        vec![
            "report".to_string(),
            dir.display().to_string(),
            "--agents".into(),
            agents.into(),
            "--out".into(),
            out.display().to_string(),
        ]
    };
    let o = hnav_output(&args("0,3"), registry, Duration::from_secs(60)).unwrap();
    assert!(o.status.success(), "{o:?}");
    let text = std::fs::read_to_string(&out).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let layout = Layout::new(12, 12, 2, 6);
    for (k, agent) in [0, 3].into_iter().enumerate() {
        assert_eq!(cells_on(&doc, &layout.heatmaps[k]), 144, "agent {agent}");
    }
    let captions = elements(&doc, "text")
        .iter()
        .filter_map(|t| t.text())
        .filter(|t| t.contains("neural map"))
        .count();
    assert_eq!(captions, 2);
    let o = hnav_output(&args("0,9"), registry, Duration::from_secs(60)).unwrap();
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert!(
        o.stderr.contains("--agents 9: the run has 6 agents (0-5)"),
        "{}",
        o.stderr
    );
}
