//! `hnav top` on a live run: the library's live feed read into the view's state and drawn
//! into ratatui's `TestBackend` while the demo runs in lockstep, then the binary's refusals
//! when there is nothing to show.

use std::path::Path;
use std::time::{Duration, Instant};

use hnav_operator::monitor::feed::{Feed, FeedError, Waited};
use hnav_operator::monitor::live::LiveFeed;
use hnav_operator::monitor::map::agent_label;
use hnav_operator::monitor::state::ViewState;
use hnav_operator::monitor::view::{self, Hints};
use hnav_operator::supervisor::registry::RunRegistry;
use hnav_tests::swarm::{hnav_output, repo_root, SwarmRun};
use hnav_tests::tmux::Tmux;
use hnav_tests::TestRun;
use ratatui::backend::TestBackend;
use ratatui::Terminal;

const WIDTH: u16 = 120;
const HEIGHT: u16 = 40;
/// The columns of the side panel (`monitor::view`): the map is left of them.
const SIDE: u16 = 46;

/// The screen's rows as text, split into the map part and the side panel.
fn screen(terminal: &Terminal<TestBackend>) -> (Vec<String>, Vec<String>) {
    let buf = terminal.backend().buffer();
    let row = |y: u16, xs: std::ops::Range<u16>| -> String {
        xs.map(|x| buf[(x, y)].symbol().to_string()).collect()
    };
    let map = (0..HEIGHT).map(|y| row(y, 0..WIDTH - SIDE)).collect();
    let side = (0..HEIGHT).map(|y| row(y, WIDTH - SIDE..WIDTH)).collect();
    (map, side)
}

/// Opens the feed of `run` once the supervisor has registered it (bounded).
fn open_feed(registry: &Path, run: &str, swarm: &SwarmRun) -> LiveFeed {
    let registry = RunRegistry::at(registry);
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        match LiveFeed::open(&registry, Some(run)) {
            Ok(f) => return f,
            // Not registered yet: the supervisor writes its record when it spawns.
            Err(FeedError::Lookup(_) | FeedError::NotFound { .. }) if Instant::now() < deadline => {
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(e) => panic!(
                "cannot open the live feed of {run}: {e}\n{}",
                swarm.log_tails()
            ),
        }
    }
}

#[test]
fn top_shows_every_robot_of_a_live_run_and_ends_with_all_at_goal() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let mut run = TestRun::new("top");
    let scenario = repo_root().join("scenarios/demo.toml");
    let mut swarm =
        SwarmRun::start(&mut run, &scenario, &tmp.path().join("out"), &registry, &[]).unwrap();
    let mut feed = open_feed(&registry, run.run.as_str(), &swarm);
    let mut state = ViewState::new(feed.info().clone());
    let agents = state.agents.len();
    assert_eq!(agents, 6, "the demo's robots");
    let mut terminal = Terminal::new(TestBackend::new(WIDTH, HEIGHT)).unwrap();
    let labels: Vec<String> = (0..agents).map(|i| agent_label(i).to_string()).collect();
    let (mut frames, mut frames_with_all, mut moving_seen) = (0, 0, false);
    let deadline = Instant::now() + Duration::from_secs(120);
    while state.ended.is_none() {
        assert!(
            Instant::now() < deadline,
            "the run did not end in 120 s (round {})\n{}",
            state.round,
            swarm.log_tails()
        );
        let until = Instant::now() + Duration::from_millis(20);
        assert_eq!(feed.wait(until).unwrap(), Waited::Ready);
        feed.pump(&mut |u| state.apply(u, Instant::now())).unwrap();
        let now = Instant::now();
        terminal
            .draw(|f| view::draw(f, &state, now, Hints::default()))
            .unwrap();
        let (map, side) = screen(&terminal);
        frames += 1;
        // Below the header and the map's border, every robot's label is on the map.
        let map_text = map[2..].join("\n");
        if labels.iter().all(|l| map_text.contains(l.as_str())) {
            frames_with_all += 1;
        }
        moving_seen |= side.iter().any(|l| l.contains("moving"));
    }
    drop(feed);
    let status = swarm.finish(Duration::from_secs(60)).unwrap();
    assert!(
        status.success(),
        "hnav run: {status:?}\n{}",
        swarm.log_tails()
    );
    assert!(frames > 5, "only {frames} frames of a live run");
    assert_eq!(
        frames_with_all, frames,
        "every frame shows every robot on the map"
    );
    assert!(moving_seen, "no frame showed a robot moving");
    let now = Instant::now();
    terminal
        .draw(|f| view::draw(f, &state, now, Hints::default()))
        .unwrap();
    let (_, side) = screen(&terminal);
    for l in &labels {
        let line = side.iter().find(|s| s.starts_with(&format!("│ {l} ")));
        let line = line.unwrap_or_else(|| panic!("no row of agent {l} in\n{}", side.join("\n")));
        assert!(line.contains("at goal"), "agent {l}: {line}");
    }
    let (map, _) = screen(&terminal);
    let bottom = &map[usize::from(HEIGHT) - 1];
    assert!(
        bottom.contains("run ended: every robot at its goal"),
        "{bottom}"
    );
    eprintln!(
        "{frames} frames, round {}, {} commits not seen by the viewer",
        state.round, state.missed_commits
    );
}

#[test]
fn top_without_a_live_run_says_so_and_exits_2() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let none = hnav_output(&["top".into()], &registry, Duration::from_secs(30)).unwrap();
    assert_eq!(none.status.code(), Some(2), "{none:?}");
    assert_eq!(
        none.stderr.trim(),
        format!(
            "error: no live run in the run registry {} (`hnav run` starts one)",
            registry.display()
        )
    );
    let unknown = hnav_output(
        &["top".into(), "nosuch".into()],
        &registry,
        Duration::from_secs(30),
    )
    .unwrap();
    assert_eq!(unknown.status.code(), Some(2), "{unknown:?}");
    assert!(
        unknown.stderr.contains("no live run `nosuch`"),
        "{}",
        unknown.stderr
    );
}

#[test]
fn top_in_tmux_shows_the_run_until_q_and_gives_the_terminal_back() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let mut run = TestRun::new("toptmux");
    let Some(tmux) = Tmux::new(run.run.as_str()) else {
        return;
    };
    let scenario = repo_root().join("scenarios/demo.toml");
    let mut swarm =
        SwarmRun::start(&mut run, &scenario, &tmp.path().join("out"), &registry, &[]).unwrap();
    let id = run.run.as_str().to_string();
    hnav_tests::swarm::wait_for_ps(&registry, &id, Duration::from_secs(60), |_| true).unwrap();
    let hnav = hnav_tests::swarm::workspace_bin("hnav");
    // The shell stays after `hnav top` has left, showing its exit status, until the server
    // is killed.
    let command = format!(
        "HNAV_RUNS_DIR='{}' '{}' top {id}; echo top-exit=$?; read -r _",
        registry.display(),
        hnav.display()
    );
    let started = tmux.start(WIDTH, HEIGHT, &command);
    assert!(started.status.success(), "{started:?}");
    let labels: Vec<String> = (0..6).map(|i| agent_label(i).to_string()).collect();
    let ended = tmux
        .wait_for(Duration::from_secs(120), |s| s.contains("run ended"))
        .unwrap_or_else(|s| panic!("no `run ended` on the screen:\n{s}\n{}", swarm.log_tails()));
    assert!(
        ended.contains(&format!("hnav top  {id}  lockstep")),
        "{ended}"
    );
    let rows: Vec<&str> = ended.lines().collect();
    for l in &labels {
        let on_map = rows[2..].iter().any(|r| {
            r.chars()
                .take(usize::from(WIDTH - SIDE))
                .collect::<String>()
                .contains(l.as_str())
        });
        assert!(on_map, "robot {l} not on the map:\n{ended}");
        let row = rows.iter().find(|r| r.contains(&format!("│ {l} ")));
        assert!(
            row.is_some_and(|r| r.contains("at goal")),
            "agent {l} not at goal:\n{ended}"
        );
    }
    assert!(swarm.finish(Duration::from_secs(60)).unwrap().success());
    tmux.cmd(&["send-keys", "-t", "top", "q"]);
    let left = tmux
        .wait_for(Duration::from_secs(30), |s| s.contains("top-exit="))
        .unwrap_or_else(|s| panic!("hnav top did not leave on `q`:\n{s}"));
    // The main screen is back: the view is gone, the farewell line and the exit status are
    // there.
    assert!(!left.contains("latest decisions"), "{left}");
    assert!(
        left.contains(&format!("run {id} ended: every robot at its goal"))
            && left.contains("6/6 at goal"),
        "{left}"
    );
    assert!(left.contains("top-exit=0"), "{left}");
}
