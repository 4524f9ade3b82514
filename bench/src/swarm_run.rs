//! Running a whole swarm from a benchmark: `hnav run` as a child process with its own run
//! id, output directory and run registry, and what every such run is checked for afterwards
//! (its summary, `hnav log verify`, nothing of it left in shared memory). Shared by the chaos
//! campaign ([`crate::chaos`]), the MAPF benchmark ([`crate::mapf`]) and the `dynamic` experiment.

use std::path::{Path, PathBuf};

use hnav_operator::supervisor::child::ChildSpec;
use hnav_runtime::msg::Role;
use hnav_runtime::transport::RunId;

/// The directory of the running executable, where cargo also puts `hnav` and the process
/// binaries.
pub fn bin_dir() -> Result<PathBuf, String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?;
    exe.parent()
        .map(Path::to_path_buf)
        .ok_or_else(|| format!("{} has no directory", exe.display()))
}

/// `hnav run SCENARIO --run RUN --out OUT --mode MODE`, its output appended to `log_file`,
/// with its run registry in `registry` (`HNAV_RUNS_DIR`), so that it never meets the
/// machine's other runs.
pub fn hnav_run_spec(
    hnav: &Path,
    scenario: &Path,
    run: &RunId,
    out: &Path,
    mode: &str,
    registry: &Path,
    log_file: PathBuf,
) -> ChildSpec {
    // `ChildSpec` names a process of a run; the supervisor has no role of its own, and the
    // role only names the process in a warning.
    ChildSpec::new(Role::Sim, 0, hnav, log_file)
        .arg("run")
        .arg(scenario)
        .arg("--run")
        .arg(run.as_str())
        .arg("--out")
        .arg(out)
        .arg("--mode")
        .arg(mode)
        .env("HNAV_RUNS_DIR", registry)
}

/// `OUT/summary.json`, parsed.
pub fn read_summary(out: &Path) -> Result<serde_json::Value, String> {
    let path = out.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// `hnav log verify DIR`: `Ok` when it exits 0, else its output.
pub fn verify_log(hnav: &Path, dir: &Path) -> Result<(), String> {
    let out = std::process::Command::new(hnav)
        .args(["log", "verify"])
        .arg(dir)
        .output()
        .map_err(|e| format!("cannot run {} log verify: {e}", hnav.display()))?;
    if out.status.success() {
        return Ok(());
    }
    Err(format!(
        "hnav log verify {} ({}): {}{}",
        dir.display(),
        out.status,
        String::from_utf8_lossy(&out.stdout).trim(),
        String::from_utf8_lossy(&out.stderr).trim()
    ))
}

/// Robots at goal and robots whose goal is reachable (not reported unreachable), from
/// `summary.json`.
pub fn goal_counts(summary: &serde_json::Value) -> (usize, usize) {
    let agents = summary["agents"].as_array().map_or(&[][..], Vec::as_slice);
    let reachable = agents.iter().filter(|a| a["unreachable"] != true);
    let at_goal = reachable
        .clone()
        .filter(|a| a["reached_goal"] == true)
        .count();
    (at_goal, reachable.count())
}

/// The summary's verdict on the robots: every robot whose goal is reachable at it, and no
/// collision.
pub fn check_summary(summary: &serde_json::Value) -> Result<(), String> {
    let agents = summary["agents"]
        .as_array()
        .ok_or("summary.json has no agents")?;
    let (at_goal, reachable) = goal_counts(summary);
    let collisions = summary["collisions"].as_u64().unwrap_or(u64::MAX);
    let mut wrong = Vec::new();
    if at_goal < reachable {
        let missing: Vec<String> = agents
            .iter()
            .filter(|a| a["unreachable"] != true && a["reached_goal"] != true)
            .map(|a| a["id"].to_string())
            .collect();
        wrong.push(format!(
            "{at_goal} of {reachable} robots at goal (not: {})",
            missing.join(", ")
        ));
    }
    if collisions != 0 {
        wrong.push(format!("{collisions} collisions"));
    }
    if wrong.is_empty() {
        Ok(())
    } else {
        Err(format!("{} (end: {})", wrong.join(", "), summary["end"]))
    }
}

/// The run's files in `/dev/shm` and under iceoryx2's root directory. Only the run's own
/// (its prefix): other runs on the machine come and go meanwhile, so a whole-directory
/// comparison would blame them on this one.
pub fn run_files(run: &hnav_runtime::transport::RunId) -> Vec<PathBuf> {
    let mut files = hnav_runtime::transport::run_shm_files(run);
    files.extend(hnav_runtime::transport::run_iceoryx2_files(run));
    files.sort();
    files
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_check_names_what_is_wrong() {
        let ok = serde_json::json!({"agents": [
            {"id": 0, "reached_goal": true, "unreachable": false},
            {"id": 1, "reached_goal": false, "unreachable": true}], "collisions": 0, "end": "all-at-goal"});
        assert_eq!(check_summary(&ok), Ok(()));
        assert_eq!(goal_counts(&ok), (1, 1));
        let bad = serde_json::json!({"agents": [
            {"id": 0, "reached_goal": false, "unreachable": false}], "collisions": 2, "end": "time-limit"});
        assert_eq!(
            check_summary(&bad),
            Err("0 of 1 robots at goal (not: 0), 2 collisions (end: \"time-limit\")".into())
        );
        assert_eq!(goal_counts(&bad), (0, 1));
    }
}
