//! The summary as the table `hnav run` prints.

use super::{AgentSummary, RunSummary};

impl RunSummary {
    /// The table `hnav run` prints: a line per agent, the run's line (naming the rules it
    /// ran, so that runs under different rules are not compared by mistake) and, when any
    /// process was restarted, its restarts.
    pub fn render(&self) -> String {
        let mut s = String::from(
            "agent  goal  steps  length  conflicts  waited  replans  optimal  to-goal  energy  budget  repairs  false+\n",
        );
        for a in &self.agents {
            let goal = match (a.reached_goal, a.unreachable, a.lost) {
                (true, _, _) => "yes",
                (false, _, true) => "lost",
                (false, true, false) => "unreachable",
                (false, false, false) => "NO",
            };
            s += &match self.counts_on_host {
                None => format!(
                    "{:>5}  {:>4}  {:>5}  {:>6.2}  {:>9}  {:>6}  {:>7}  {}\n",
                    a.id,
                    goal,
                    a.steps,
                    a.length,
                    a.conflicts,
                    a.waited,
                    a.replans,
                    criteria_columns(a, true)
                ),
                Some(_) => format!(
                    "{:>5}  {goal:>4}  {:>5}  {:>6}  {:>9}  {:>6}  {:>7}  {}\n",
                    a.id,
                    "-",
                    "-",
                    "-",
                    "-",
                    "-",
                    criteria_columns(a, false)
                ),
            };
        }
        if let Some(host) = &self.counts_on_host {
            s += &format!(
                "(steps, length, conflicts, waited, replans: in the consensus log on host {host}; optimal and false+ too; goals, collisions and rounds: from what crossed the bridge)\n"
            );
        }
        let at_goal = self.agents.iter().filter(|a| a.reached_goal).count();
        let rules = if self.rules.is_empty() {
            String::new()
        } else {
            format!("{} rules, ", self.rules)
        };
        s += &format!(
            "{} of {} at goal, {} collisions, {} rounds, {:.2} s wall ({}, {rules}{})\n",
            at_goal,
            self.agents.len(),
            self.collisions,
            self.rounds,
            self.wall_time_s,
            self.mode,
            self.end
        );
        if let Some(l) = &self.consensus_latency_us {
            s += &format!(
                "consensus: candidate -> commit p50 {} us, p99 {} us; last candidate -> commit p50 {} us, p99 {} us ({} rounds)\n",
                l.p50, l.p99, l.decide_p50, l.decide_p99, l.rounds
            );
        }
        if let Some(t) = &self.tasks {
            s += &t.render();
        }
        if !self.restarts.is_empty() {
            let each: Vec<String> = self
                .restarts
                .iter()
                .map(|(p, n)| format!("{p} {n}"))
                .collect();
            s += &format!("restarts: {}\n", each.join(", "));
        }
        s
    }
}

/// The criteria columns of agent `a`'s line: optimality, time to goal (s), energy and its
/// budget (J), repairs (partial/rebuild/route), false positives; `-` for what is not known
/// (the log-based ones without the log: `from_log` false).
fn criteria_columns(a: &AgentSummary, from_log: bool) -> String {
    let or_dash =
        |v: Option<f64>, prec: usize| v.map_or("-".to_string(), |v| format!("{v:.prec$}"));
    let fp = if from_log {
        a.false_positives.to_string()
    } else {
        "-".to_string()
    };
    format!(
        "{:>7}  {:>7}  {:>6}  {:>6}  {:>7}  {:>6}",
        or_dash(a.optimality.filter(|_| from_log), 3),
        or_dash(a.time_to_goal_s, 2),
        or_dash(a.energy_j, 2),
        or_dash(a.energy_budget_j, 2),
        format!(
            "{}/{}/{}",
            a.repairs_partial, a.repairs_rebuild, a.repairs_replan
        ),
        fp
    )
}
