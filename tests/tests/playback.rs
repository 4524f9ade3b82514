//! `hnav log replay DIR --speed X`: a finished demo run's recording played back into the
//! `hnav top` view. The library's playback feed is folded into the view's state and drawn
//! into ratatui's `TestBackend`; the binary plays it in a real terminal (tmux) to the end;
//! bad speeds and directories without a recording are refused with exit code 2.
//!
//! One demo run serves every check (it is the expensive part), so this is one test.

use std::path::Path;
use std::time::{Duration, Instant};

use hnav_operator::monitor::feed::{Feed, RunEnd, Waited};
use hnav_operator::monitor::map::agent_label;
use hnav_operator::monitor::playback::PlaybackFeed;
use hnav_operator::monitor::state::{AgentState, ViewState};
use hnav_operator::monitor::view::{self, Hints};
use hnav_runtime::consensus_log::{read_log, Record};
use hnav_tests::swarm::{hnav_output, repo_root, workspace_bin, SwarmRun};
use hnav_tests::tmux::Tmux;
use hnav_tests::TestRun;
use ratatui::backend::TestBackend;
use ratatui::Terminal;

const SPEED: f64 = 8.0;

/// The demo's last round and the simulated time its recording covers, ns.
fn extent(dir: &Path) -> (u64, u64) {
    let records = read_log(dir.join("log")).unwrap().records;
    let last = records.iter().filter_map(Record::round).max().unwrap();
    let (samples, _) =
        hnav_operator::recording::TrajectoryReader::open(&dir.join("recording/trajectories.bin"))
            .unwrap()
            .read_all()
            .unwrap();
    (last, samples.iter().map(|s| s.t_ns).max().unwrap())
}

/// Plays `dir` back through the library into a `TestBackend`, checking what the view shows.
fn play_in_the_library(dir: &Path, summary: &serde_json::Value) {
    let (last_round, _) = extent(dir);
    let mut feed = PlaybackFeed::open(dir, SPEED).unwrap();
    let mut state = ViewState::new(feed.info().clone());
    assert_eq!(state.agents.len(), 6, "the demo's robots");
    assert!(
        feed.info().mode.contains("lockstep playback x8"),
        "{:?}",
        feed.info().mode
    );
    let mut terminal = Terminal::new(TestBackend::new(120, 40)).unwrap();
    let (started, mut frames, mut moving_seen) = (Instant::now(), 0, false);
    let mut rounds_seen = Vec::new();
    while state.ended.is_none() {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "the playback did not end in 120 s (round {})",
            state.round
        );
        let until = Instant::now() + Duration::from_millis(20);
        assert_eq!(feed.wait(until).unwrap(), Waited::Ready);
        feed.pump(&mut |u| state.apply(u, Instant::now())).unwrap();
        rounds_seen.push(state.round);
        moving_seen |= state.agents.iter().any(|a| a.state() == AgentState::Moving);
        let now = Instant::now();
        terminal
            .draw(|f| view::draw(f, &state, now, Hints::default()))
            .unwrap();
        frames += 1;
    }
    let took = started.elapsed();
    assert_eq!(state.ended, Some(RunEnd::AllAtGoal));
    assert_eq!(
        state.round, last_round,
        "the playback reaches the log's last round"
    );
    assert_eq!(
        state.missed_commits, 0,
        "a playback yields every round's commit"
    );
    assert!(state.agents.iter().all(|a| a.state() == AgentState::AtGoal));
    assert!(moving_seen, "no robot was ever shown moving");
    let conflicts: u64 = summary["agents"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["conflicts"].as_u64().unwrap())
        .sum();
    let p = state.progress.expect("progress was yielded");
    assert_eq!(
        u64::from(p.conflicts),
        conflicts,
        "the tally is the summary's"
    );
    assert_eq!(
        u64::from(state.collisions),
        summary["collisions"].as_u64().unwrap()
    );
    // Paced, not dumped: the rounds arrive over many pumps, and the whole run takes at least
    // its simulated duration divided by the speed (a lower bound only: a loaded machine may
    // take longer, never shorter).
    let period = feed_period_s(dir);
    let at_least = Duration::from_secs_f64(last_round as f64 * period / SPEED * 0.95);
    assert!(
        took >= at_least,
        "played in {took:?}, expected at least {at_least:?}"
    );
    rounds_seen.dedup();
    assert!(
        rounds_seen.len() > 10,
        "the rounds came in {} steps: not paced",
        rounds_seen.len()
    );
    assert!(frames > 10);
    let buf = terminal.backend().buffer();
    let text: String = (0..40)
        .flat_map(|y| (0..120).map(move |x| (x, y)))
        .map(|(x, y)| buf[(x, y)].symbol().to_string())
        .collect();
    for i in 0..6 {
        assert!(
            text.contains(agent_label(i)),
            "robot {} not drawn",
            agent_label(i)
        );
    }
}

/// The recording's control period, s.
fn feed_period_s(dir: &Path) -> f64 {
    let r =
        hnav_operator::recording::TrajectoryReader::open(&dir.join("recording/trajectories.bin"))
            .unwrap();
    f64::from(r.header().control_period_us) * 1e-6
}

/// `hnav log replay DIR --speed X --exit-on-end` in a real terminal: the view to the end, then
/// the farewell line and exit 0.
fn play_in_tmux(dir: &Path, id: &str) {
    let Some(tmux) = Tmux::new(id) else {
        return;
    };
    let command = format!(
        "'{}' log replay '{}' --speed 8 --exit-on-end; echo replay-exit=$?; read -r _",
        workspace_bin("hnav").display(),
        dir.display()
    );
    let started = tmux.start(120, 40, &command);
    assert!(started.status.success(), "{started:?}");
    let playing = tmux
        .wait_for(Duration::from_secs(60), |s| s.contains("playback x8"))
        .unwrap_or_else(|s| panic!("no playback view on the screen:\n{s}"));
    assert!(
        playing.contains("hnav top  out  lockstep playback x8"),
        "{playing}"
    );
    let left = tmux
        .wait_for(Duration::from_secs(120), |s| s.contains("replay-exit="))
        .unwrap_or_else(|s| panic!("the playback did not end:\n{s}"));
    assert!(
        left.contains("run out ended: every robot at its goal") && left.contains("6/6 at goal"),
        "{left}"
    );
    assert!(left.contains("replay-exit=0"), "{left}");
}

#[test]
fn a_recorded_demo_plays_back_into_the_view_at_the_chosen_speed() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let dir = tmp.path().join("out");
    let mut run = TestRun::new("playback");
    let scenario = repo_root().join("scenarios/demo.toml");
    let mut swarm = SwarmRun::start(&mut run, &scenario, &dir, &registry, &[]).unwrap();
    let status = swarm.finish(Duration::from_secs(300)).unwrap();
    assert!(status.success(), "{status:?}\n{}", swarm.log_tails());
    let summary = swarm.summary().unwrap();

    play_in_the_library(&dir, &summary);
    play_in_tmux(&dir, run.run.as_str());

    // Refusals: exit 2 and a line that names what is wrong.
    let replay = |args: &[&str]| {
        let mut a: Vec<String> = vec!["log".into(), "replay".into()];
        a.extend(args.iter().map(|s| s.to_string()));
        hnav_output(&a, &registry, Duration::from_secs(30)).unwrap()
    };
    let d = dir.display().to_string();
    let zero = replay(&[&d, "--speed", "0"]);
    assert_eq!(zero.status.code(), Some(2), "{zero:?}");
    assert!(
        zero.stderr
            .contains("speed 0: it must lie between 0.01 and 10000"),
        "{}",
        zero.stderr
    );
    let piped = replay(&[&d, "--speed", "4"]);
    assert_eq!(piped.status.code(), Some(2), "{piped:?}");
    assert!(piped.stderr.contains("terminal"), "{}", piped.stderr);
    std::fs::remove_file(dir.join("recording/trajectories.bin")).unwrap();
    let gone = replay(&[&d, "--speed", "4"]);
    assert_eq!(gone.status.code(), Some(2), "{gone:?}");
    assert!(gone.stderr.contains("trajectories.bin"), "{}", gone.stderr);
}
