//! Detection and recovery figures over a campaign: differences of the supervisor's stamps
//! (`events.jsonl`) and the observer's, both [`monotonic_ns`](hnav_runtime::clock::monotonic_ns).

use hdrhistogram::Histogram;
use hnav_runtime::msg::{LifecycleEvent, Role};

use super::checks::EventLine;
use super::observer::Observed;

/// One latency figure: a histogram of microseconds, and the events that found no partner
/// (a kill whose `Down` never arrived, say).
pub struct Figure {
    /// What it measures, for the table.
    pub name: &'static str,
    /// The aim it is held against, if the issue sets one.
    pub aim: &'static str,
    hist: Histogram<u64>,
    /// Start events without a matching end.
    pub unmatched: usize,
    /// The largest sample's run and process (`plan 12 agent-3`), to look it up.
    pub worst: Option<(u64, String)>,
}

impl Figure {
    fn new(name: &'static str, aim: &'static str) -> Self {
        Figure {
            name,
            aim,
            // Microseconds up to an hour, 3 significant digits: the bounds cannot be wrong.
            hist: Histogram::new_with_bounds(1, 3_600_000_000, 3).expect("valid bounds"),
            unmatched: 0,
            worst: None,
        }
    }

    fn add_ns(&mut self, from: u64, to: Option<u64>, what: impl FnOnce() -> String) {
        match to {
            Some(to) => {
                let us = (to.saturating_sub(from) / 1000).max(1);
                self.hist.saturating_record(us);
                if self.worst.as_ref().is_none_or(|w| us > w.0) {
                    self.worst = Some((us, what()));
                }
            }
            None => self.unmatched += 1,
        }
    }

    /// Samples recorded.
    pub fn len(&self) -> u64 {
        self.hist.len()
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.hist.is_empty()
    }

    /// The `q` quantile in milliseconds.
    pub fn quantile_ms(&self, q: f64) -> f64 {
        self.hist.value_at_quantile(q) as f64 / 1000.0
    }

    /// The largest sample in milliseconds.
    pub fn max_ms(&self) -> f64 {
        self.hist.max() as f64 / 1000.0
    }
}

/// The campaign's figures.
pub struct Figures {
    /// SIGKILL (`signalled`) → the observer's receipt of that process's `Down`: when the
    /// coordinator and every other process are told.
    pub kill_to_down: Figure,
    /// SIGKILL (`signalled`) → the supervisor reaped that process (`exited`): the kernel's
    /// teardown of the killed process, the floor under `kill_to_down` for any supervisor
    /// that learns of a death from the kernel (its `Down` cannot be sent earlier).
    pub kill_to_exit: Figure,
    /// SIGSTOP (`signalled`) → `hung` declared for that process.
    pub freeze_to_hung: Figure,
    /// How long each hung process had been silent when it was declared (`silent_ms`): the
    /// deadline in effect, as the supervisor measured it.
    pub hang_silence: Figure,
    /// A restarted agent's `spawned` → its first candidate.
    pub agent_back: Figure,
    /// A restarted coordinator's `spawned` → its first commit of a new round.
    pub coordinator_back: Figure,
    /// A restarted sim's `spawned` → its first ground truth.
    pub sim_back: Figure,
    /// The Raft leader's SIGKILL → the first commit of a new round (by the new leader).
    pub failover: Figure,
}

impl Default for Figures {
    fn default() -> Self {
        Figures {
            kill_to_down: Figure::new("SIGKILL -> Down received", "p99 <= 10 ms"),
            kill_to_exit: Figure::new("SIGKILL -> exit reaped (the floor)", "the kernel's"),
            freeze_to_hung: Figure::new("SIGSTOP -> hang declared", "beside the deadline"),
            hang_silence: Figure::new("silence when declared hung", "the deadline"),
            agent_back: Figure::new("agent spawned -> first candidate", "<= 300 ms"),
            coordinator_back: Figure::new("coordinator spawned -> first commit", "<= 300 ms"),
            sim_back: Figure::new("sim spawned -> first truth", "<= 300 ms"),
            failover: Figure::new("leader SIGKILL -> next leader commits", "election_ms..2x"),
        }
    }
}

/// `agent-3` → (agent, 3); `coordinator-2` (replica 2) → (coordinator, 2); `sim`,
/// `coordinator` → index 0.
fn parse_node(node: &str) -> Option<(Role, u32)> {
    match node.split_once('-') {
        Some(("agent", i)) => i.parse().ok().map(|i| (Role::Agent, i)),
        Some(("coordinator", i)) => i.parse().ok().map(|i| (Role::Coordinator, i)),
        _ => Role::from_name(node).map(|r| (r, 0)),
    }
}

/// When the observer first saw a commit of a round later than every round committed by
/// `t_ns`: a resend of the last round is not a decision, the next round is.
fn first_new_round(seen: &Observed, t_ns: u64) -> Option<u64> {
    let before = seen
        .commits
        .iter()
        .filter(|c| c.t_ns <= t_ns)
        .map(|c| c.round)
        .max()
        .unwrap_or(0);
    seen.commits
        .iter()
        .find(|c| c.t_ns > t_ns && c.round > before)
        .map(|c| c.t_ns)
}

impl Figures {
    /// Adds one run's events and observations; `run` names the run (`plan 12`).
    pub fn add_run(&mut self, run: &str, events: &[EventLine], seen: &Observed) {
        for e in events {
            let what = || format!("{run} {}", e.node);
            let Some((role, index)) = parse_node(&e.node) else {
                continue;
            };
            match (e.event.as_str(), e.signal.as_deref()) {
                ("signalled", Some("SIGKILL")) => {
                    let down = seen
                        .lifecycle
                        .iter()
                        .find(|l| {
                            l.t_ns >= e.t_ns
                                && l.event == LifecycleEvent::Down
                                && (l.role, l.index) == (role, index)
                        })
                        .map(|l| l.t_ns);
                    self.kill_to_down.add_ns(e.t_ns, down, what);
                    let exited = events
                        .iter()
                        .find(|x| x.event == "exited" && x.node == e.node && x.t_ns >= e.t_ns)
                        .map(|x| x.t_ns);
                    self.kill_to_exit.add_ns(e.t_ns, exited, what);
                    if role == Role::Coordinator && index > 0 && e.fault.is_some() {
                        let first = first_new_round(seen, e.t_ns);
                        self.failover.add_ns(e.t_ns, first, what);
                    }
                }
                ("signalled", Some("SIGSTOP")) => {
                    let hung = events
                        .iter()
                        .find(|h| h.event == "hung" && h.node == e.node && h.t_ns >= e.t_ns)
                        .map(|h| h.t_ns);
                    self.freeze_to_hung.add_ns(e.t_ns, hung, what);
                }
                ("hung", _) => {
                    if let Some(ms) = e.silent_ms {
                        self.hang_silence.add_ns(0, Some(ms * 1_000_000), what);
                    }
                }
                ("spawned", _) => self.add_respawn(role, index, e.t_ns, seen, what()),
                _ => {}
            }
        }
    }

    fn add_respawn(&mut self, role: Role, index: u32, spawned: u64, seen: &Observed, what: String) {
        let what = move || what;
        match role {
            Role::Agent => {
                let first = seen
                    .candidates
                    .iter()
                    .find(|&&(t, a)| t > spawned && a == index)
                    .map(|c| c.0);
                self.agent_back.add_ns(spawned, first, what);
            }
            // A restarted replica comes back as a follower: another one decides.
            Role::Coordinator if index > 0 => {}
            Role::Coordinator => {
                let first = first_new_round(seen, spawned);
                self.coordinator_back.add_ns(spawned, first, what);
            }
            Role::Sim => {
                let first = seen.truths.iter().copied().find(|&t| t > spawned);
                self.sim_back.add_ns(spawned, first, what);
            }
            // Chaos runs on one host: no bridge.
            Role::Bridge => {}
        }
    }

    /// Every figure, in table order.
    pub fn all(&self) -> [&Figure; 8] {
        [
            &self.kill_to_down,
            &self.kill_to_exit,
            &self.freeze_to_hung,
            &self.hang_silence,
            &self.agent_back,
            &self.coordinator_back,
            &self.sim_back,
            &self.failover,
        ]
    }

    /// The figures as a table: samples, p50, p99, max, unmatched, the aim.
    pub fn render(&self) -> String {
        let mut out = format!(
            "{:<38} {:>5} {:>9} {:>9} {:>9} {:>9}  {:<20} max at\n",
            "figure", "n", "p50 ms", "p99 ms", "max ms", "unmatched", "aim"
        );
        for f in self.all() {
            if f.is_empty() {
                out += &format!(
                    "{:<38} {:>5} {:>9} {:>9} {:>9} {:>9}  {}\n",
                    f.name, 0, "-", "-", "-", f.unmatched, f.aim
                );
            } else {
                out += &format!(
                    "{:<38} {:>5} {:>9.2} {:>9.2} {:>9.2} {:>9}  {:<20} {}\n",
                    f.name,
                    f.len(),
                    f.quantile_ms(0.5),
                    f.quantile_ms(0.99),
                    f.max_ms(),
                    f.unmatched,
                    f.aim,
                    f.worst.as_ref().map_or("", |w| w.1.as_str())
                );
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::observer::{SeenCommit, SeenLifecycle};
    use super::*;

    fn event(t_ns: u64, event: &str, node: &str, signal: Option<&str>) -> EventLine {
        EventLine {
            t_ns,
            event: event.into(),
            node: node.into(),
            pid: Some(1),
            signal: signal.map(String::from),
            fault: None,
            silent_ms: None,
        }
    }

    #[test]
    fn stamps_pair_up_per_process() {
        let events = [
            event(1_000_000, "signalled", "agent-2", Some("SIGKILL")),
            event(1_500_000, "exited", "agent-2", None),
            event(101_000_000, "spawned", "agent-2", None),
            event(200_000_000, "signalled", "coordinator", Some("SIGKILL")),
            event(300_000_000, "spawned", "coordinator", None),
        ];
        let seen = Observed {
            lifecycle: vec![SeenLifecycle {
                t_ns: 3_000_000,
                event: LifecycleEvent::Down,
                role: Role::Agent,
                index: 2,
            }],
            // Agent 1's candidate does not count for agent 2.
            candidates: vec![(102_000_000, 1), (121_000_000, 2)],
            commits: vec![
                SeenCommit {
                    t_ns: 150_000_000,
                    round: 40,
                    digest: 0,
                },
                SeenCommit {
                    t_ns: 310_000_000,
                    round: 40,
                    digest: 0,
                },
                SeenCommit {
                    t_ns: 350_000_000,
                    round: 41,
                    digest: 0,
                },
            ],
            ..Observed::default()
        };
        let mut f = Figures::default();
        f.add_run("plan 7", &events, &seen);
        assert_eq!(f.kill_to_down.len(), 1);
        // The histogram keeps 3 significant digits.
        let near = |got: f64, want: f64| (got - want).abs() < want / 100.0;
        assert!(near(f.kill_to_down.quantile_ms(0.5), 2.0));
        // The coordinator's Down never arrived.
        assert_eq!(f.kill_to_down.unmatched, 1);
        // Agent 2 was reaped 0.5 ms after its SIGKILL; the coordinator's exit is missing.
        assert!(near(f.kill_to_exit.quantile_ms(0.5), 0.5));
        assert_eq!(f.kill_to_exit.unmatched, 1);
        assert!(near(f.agent_back.quantile_ms(0.5), 20.0));
        // The resend of round 40 at 310 ms is skipped: round 41 at 350 ms is its first.
        assert!(near(f.coordinator_back.quantile_ms(0.5), 50.0));
        assert!(f.sim_back.is_empty() && f.freeze_to_hung.is_empty());
        assert_eq!(f.agent_back.worst, Some((20_000, "plan 7 agent-2".into())));
        assert!(f.render().contains("SIGKILL -> Down received"));
    }
}
