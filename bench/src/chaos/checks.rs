//! What every chaos run must show, each check returning what it found wrong in words.

use std::path::Path;

use serde::Deserialize;

/// One line of the supervisor's `events.jsonl` (the fields the campaign reads).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
pub struct EventLine {
    /// [`monotonic_ns`](hnav_runtime::clock::monotonic_ns) when it was recorded.
    pub t_ns: u64,
    /// `signalled`, `exited`, `hung`, `spawned`, `up` or `gave_up`.
    pub event: String,
    /// Node name, e.g. `agent-3`.
    pub node: String,
    /// The process, where the event names one.
    #[serde(default)]
    pub pid: Option<u32>,
    /// `SIGKILL`, `SIGSTOP`, ... for `signalled`.
    #[serde(default)]
    pub signal: Option<String>,
    /// The fault plan entry of a `signalled`.
    #[serde(default)]
    pub fault: Option<usize>,
    /// How long a `hung` process had been silent.
    #[serde(default)]
    pub silent_ms: Option<u64>,
}

/// Reads `DIR/events.jsonl`; a line that does not parse is an error naming it.
pub fn read_events(dir: &Path) -> Result<Vec<EventLine>, String> {
    let path = dir.join(hnav_operator::supervisor::events::EVENTS_FILE);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|e| format!("{}:{}: {e}", path.display(), i + 1))
        })
        .collect()
}

/// What the commit check counted when it passed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CommitCount {
    /// Distinct rounds seen (every round of the log).
    pub rounds: usize,
    /// Identical commits of the round just seen again (a restarted coordinator's resend).
    pub resends: usize,
}

/// The commits an observer received (`(round, digest)` in order of receipt) against the
/// log's rounds (`(round, digest)`, in log order): every logged round seen once, in order,
/// as logged; an identical commit of the round seen last counts as a resend. A gap, a round
/// seen twice differently, a round again after later ones, a round not in the log, or log
/// rounds never seen is a failure.
pub fn check_commits(seen: &[(u64, u64)], logged: &[(u64, u64)]) -> Result<CommitCount, String> {
    let mut count = CommitCount::default();
    let mut last: Option<(u64, u64)> = None;
    let mut next = 0usize;
    for &(round, digest) in seen {
        if last == Some((round, digest)) {
            count.resends += 1;
            continue;
        }
        if last.is_some_and(|(r, _)| r == round) {
            return Err(format!("round {round} was committed twice, differently"));
        }
        match logged.get(next) {
            Some(&(lr, ld)) if lr == round => {
                if ld != digest {
                    return Err(format!(
                        "the commit of round {round} differs from the log's"
                    ));
                }
                next += 1;
                count.rounds += 1;
                last = Some((round, digest));
            }
            Some(&(lr, _)) if round > lr => {
                return Err(format!(
                    "round {lr} was never received (round {round} came after {})",
                    last.map_or("none".to_string(), |l| l.0.to_string())
                ));
            }
            Some(_) => {
                return Err(format!(
                    "round {round} was received again after round {}",
                    last.map_or(0, |l| l.0)
                ));
            }
            None => return Err(format!("round {round} was received but is not in the log")),
        }
    }
    if let Some(&(first_missing, _)) = logged.get(next) {
        let last_logged = logged.last().map_or(first_missing, |l| l.0);
        return Err(format!(
            "rounds {first_missing}..={last_logged} of the log were never received"
        ));
    }
    Ok(count)
}

/// The logs of a run's `log_dir` to check the commits against, each with a name for the
/// failure message: the log itself, or every replica's (`log/<id>/`, `" of replica <id>"`).
pub fn logs_of(log_dir: &Path) -> Vec<(String, std::path::PathBuf)> {
    let replicas = hnav_runtime::consensus_log::replica_dirs(log_dir).unwrap_or_default();
    if replicas.is_empty() {
        return vec![(String::new(), log_dir.to_path_buf())];
    }
    replicas
        .into_iter()
        .map(|(id, dir)| (format!(" of replica {id}"), dir))
        .collect()
}

/// The `(round, digest)` of every round record of the consensus log in `log_dir` (its
/// committed records, for a replica's log).
pub fn logged_commits(log_dir: &Path) -> Result<Vec<(u64, u64)>, String> {
    use hnav_runtime::consensus_log::{read_decided, Record};
    let contents = read_decided(log_dir).map_err(|e| e.to_string())?;
    Ok(contents
        .records
        .iter()
        .filter_map(|r| match r {
            Record::Round(rec) => Some((
                rec.round,
                super::observer::commit_digest(rec.commit().view()),
            )),
            _ => None,
        })
        .collect())
}

/// The processes of `pids` that still run as part of the run (their command line names the
/// run id, so a pid reused by an unrelated process is not taken for one of the run's).
pub fn alive_of_run(pids: &[u32], run_id: &str) -> Vec<u32> {
    pids.iter()
        .copied()
        .filter(|pid| {
            std::fs::read(format!("/proc/{pid}/cmdline"))
                .is_ok_and(|c| c.split(|&b| b == 0).any(|arg| arg == run_id.as_bytes()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log(n: u64) -> Vec<(u64, u64)> {
        (1..=n).map(|r| (r, r * 10)).collect()
    }

    #[test]
    fn every_round_once_in_order_passes_and_resends_are_counted() {
        let seen = [(1, 10), (2, 20), (2, 20), (3, 30)];
        assert_eq!(
            check_commits(&seen, &log(3)),
            Ok(CommitCount {
                rounds: 3,
                resends: 1
            })
        );
    }

    #[test]
    fn each_way_of_losing_or_repeating_a_commit_fails() {
        let cases: [(&[(u64, u64)], &str); 6] = [
            (
                &[(1, 10), (3, 30)],
                "round 2 was never received (round 3 came after 1)",
            ),
            (
                &[(1, 10), (2, 21), (3, 30)],
                "the commit of round 2 differs from the log's",
            ),
            (
                &[(1, 10), (2, 20), (2, 22)],
                "round 2 was committed twice, differently",
            ),
            (
                &[(1, 10), (2, 20), (1, 10)],
                "round 1 was received again after round 2",
            ),
            (
                &[(1, 10), (2, 20), (3, 30), (4, 40)],
                "round 4 was received but is not in the log",
            ),
            (&[(1, 10)], "rounds 2..=3 of the log were never received"),
        ];
        for (seen, want) in cases {
            assert_eq!(
                check_commits(seen, &log(3)),
                Err(want.to_string()),
                "{seen:?}"
            );
        }
    }

    #[test]
    fn event_lines_parse_and_a_bad_one_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("events.jsonl");
        std::fs::write(
            &path,
            "{\"t_ns\":5,\"event\":\"signalled\",\"node\":\"agent-3\",\"pid\":9,\"signal\":\"SIGKILL\",\"fault\":0,\"round\":40}\n{\"t_ns\":7,\"event\":\"gave_up\",\"node\":\"sim\",\"why\":\"x\"}\n",
        )
        .unwrap();
        let events = read_events(dir.path()).unwrap();
        assert_eq!(events.len(), 2);
        assert_eq!(events[0].signal.as_deref(), Some("SIGKILL"));
        assert_eq!(events[1].pid, None);
        std::fs::write(&path, "{\"t_ns\":5}\n").unwrap();
        let err = read_events(dir.path()).unwrap_err();
        assert!(err.contains("events.jsonl:1:"), "{err}");
    }

    #[test]
    fn only_processes_naming_the_run_count_as_alive() {
        let me = std::process::id();
        assert!(alive_of_run(&[me], "no-such-run-id").is_empty());
        let own_arg = std::env::args().next().unwrap();
        assert_eq!(alive_of_run(&[me, u32::MAX], &own_arg), vec![me]);
    }
}
