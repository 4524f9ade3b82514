//! The campaign's table: one row per class and mode.

use std::collections::BTreeMap;

use super::plan::{Class, Mode};
use super::run::RunOutcome;

/// The counts of one row.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
struct Row {
    runs: usize,
    skipped: usize,
    finished: usize,
    at_goal: usize,
    reachable: usize,
    collisions: u64,
    verified: usize,
    commits_ok: usize,
    resends: usize,
    leaks: usize,
    alive: usize,
    failed: usize,
    needs: Option<String>,
}

/// The table of `outcomes`, and a line per skipped need.
pub fn render(outcomes: &[RunOutcome]) -> String {
    let mut rows: BTreeMap<(Class, Mode), Row> = BTreeMap::new();
    for o in outcomes {
        let r = rows.entry((o.plan.class, o.plan.mode)).or_default();
        r.runs += 1;
        if let Some(why) = &o.skipped {
            r.skipped += 1;
            r.needs = Some(why.clone());
            continue;
        }
        r.finished += usize::from(o.exit.is_some_and(|e| e.code() == Some(0)));
        r.at_goal += o.at_goal.0;
        r.reachable += o.at_goal.1;
        r.collisions += o.collisions;
        r.verified += usize::from(o.verified);
        r.commits_ok += usize::from(o.commits.is_some());
        r.resends += o.commits.map_or(0, |c| c.resends);
        r.leaks += usize::from(o.leaked_files > 0);
        r.alive += o.left_alive;
        r.failed += usize::from(!o.failures.is_empty());
    }
    let mut out = format!(
        "{:<17} {:<9} {:>4} {:>7} {:>8} {:>9} {:>10} {:>9} {:>10} {:>7} {:>5} {:>5} {:>6}\n",
        "class",
        "mode",
        "runs",
        "skipped",
        "finished",
        "at goal",
        "collisions",
        "verify ok",
        "commits ok",
        "resends",
        "leaks",
        "alive",
        "failed"
    );
    let mut needs = Vec::new();
    for ((class, mode), r) in &rows {
        out += &format!(
            "{:<17} {:<9} {:>4} {:>7} {:>8} {:>9} {:>10} {:>9} {:>10} {:>7} {:>5} {:>5} {:>6}\n",
            class.name(),
            mode.name(),
            r.runs,
            r.skipped,
            r.finished,
            format!("{}/{}", r.at_goal, r.reachable),
            r.collisions,
            r.verified,
            r.commits_ok,
            r.resends,
            r.leaks,
            r.alive,
            r.failed
        );
        if let Some(n) = &r.needs {
            if !needs.contains(n) {
                needs.push(n.clone());
            }
        }
    }
    for n in needs {
        out += &format!("skipped: {n}\n");
    }
    out
}
