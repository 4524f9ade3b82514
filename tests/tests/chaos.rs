//! The chaos campaign as a test: 30 seeded runs of the chaos swarm (`scenarios/chaos.toml`)
//! in the quick campaign's proportions — 17 killing 1–3 random agents at random rounds, 5
//! killing the coordinator, 2 freezing an agent, 2 killing the sim, 2 killing two agents and
//! the coordinator at once, 2 killing the Raft leader of 3 coordinator replicas — split over
//! lockstep and realtime. The quick campaign of 59 runs (`hnav-bench chaos --quick`, about
//! four minutes on 2 cores) and the full one of 118 are `hnav-bench` commands; this one keeps
//! the test command within its time. Every run must finish with every
//! robot at goal, no collision, a log that verifies, every commit seen once, and nothing
//! left behind; the table and the figures are printed at the end (`--nocapture`).
//!
//! The same code as `hnav-bench chaos --quick` (`hnav_bench::chaos`). In its own test binary
//! because it SIGKILLs and SIGSTOPs processes. `HNAV_CHAOS_SEED` draws another campaign.

use hnav_bench::chaos::plan::Class;
use hnav_bench::chaos::{run_campaign, CampaignConfig};
use hnav_tests::swarm::workspace_bin;

/// Runs of the campaign this test runs: every class at least twice, so in lockstep and in
/// realtime (`hnav_bench::chaos::plan::class_counts`).
const TEST_RUNS: usize = 30;

#[test]
fn every_run_of_the_chaos_campaign_finishes_with_nothing_lost_or_left() {
    campaign(TEST_RUNS, None, 1);
}

/// The same checks with `[run] agents_per_process = 8`: the chaos swarm's six robots in one
/// agent process, so a fault on any agent takes all six down and the restarted process
/// brings each back from its checkpoint. Every class twice: once in lockstep, once in
/// realtime.
#[test]
fn every_chaos_class_passes_with_eight_agents_per_process() {
    for class in Class::ALL {
        campaign(2, Some(class), 8);
    }
}

fn campaign(runs: usize, class: Option<Class>, agents_per_process: u32) {
    let seed = std::env::var("HNAV_CHAOS_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(12);
    let hnav = workspace_bin("hnav");
    let config = CampaignConfig {
        runs,
        seed,
        only: None,
        class,
        bin_dir: hnav
            .parent()
            .expect("binaries live in a directory")
            .to_path_buf(),
        agents_per_process,
    };
    let report = run_campaign(&config, |line| println!("{line}")).expect("the campaign runs");
    println!("{}", report.render());
    assert!(
        report.passed(),
        "chaos campaign (seed {seed}) failed:\n{}",
        report.failures().join("\n")
    );
}
