//! A lifelong run's tasks in the summary (`[tasks]`), from the consensus log's task records.
//!
//! Task `k` of an agent is given at the round of its task record (task 0, its `[[agents]]
//! goal`, at round 0) and done at the round of the agent's next task record: the coordinator
//! gives the next goal the round the robot stands on the last one. A task's time is the
//! rounds between the two, in simulated seconds (rounds times the control period; in
//! realtime rounds follow the odometry, so this is close to the wall clock, not exact). A
//! task record logged twice (a coordinator restarted between it and its round) counts once.

use serde::Serialize;

use hnav_runtime::consensus_log::TaskRecord;

/// How long one window of [`TaskSummary::per_window`] is, in simulated seconds.
pub const WINDOW_S: f64 = 300.0;

/// The tasks of a lifelong run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TaskSummary {
    /// Tasks done (goals reached that had a next one given), over all robots.
    pub tasks_done: u64,
    /// Simulated time of the run in seconds (its rounds).
    pub sim_time_s: f64,
    /// Tasks done per hour of simulated time.
    pub throughput_per_hour: f64,
    /// Median time from a task's assignment to the robot's arrival, simulated seconds.
    pub task_time_p50_s: f64,
    /// 99th percentile of the same (nearest rank).
    pub task_time_p99_s: f64,
    /// Length of the windows of `per_window`, simulated seconds.
    pub window_s: f64,
    /// Tasks done in each window of simulated time from the start (the last one may be
    /// partial); a 0 in a full window means the robots did not get anywhere for that long.
    pub per_window: Vec<u64>,
}

impl TaskSummary {
    /// The summary of `records` (in log order) of a run of `rounds` rounds `period_s` apart.
    pub fn new(records: &[TaskRecord], rounds: u64, period_s: f64) -> TaskSummary {
        let mut given: Vec<(u64, u64)> = Vec::new(); // per agent: (last task, its round)
        let mut times = Vec::new();
        let windows = ((rounds as f64 * period_s) / WINDOW_S).ceil().max(1.0) as usize;
        let mut per_window = vec![0u64; windows];
        for t in records {
            let a = t.agent as usize;
            if given.len() <= a {
                given.resize(a + 1, (0, 0));
            }
            let (last, since) = given[a];
            if t.task <= last {
                continue;
            }
            given[a] = (t.task, t.round);
            times.push(t.round.saturating_sub(since) as f64 * period_s);
            let w = ((t.round as f64 * period_s) / WINDOW_S) as usize;
            per_window[w.min(windows - 1)] += 1;
        }
        times.sort_by(f64::total_cmp);
        let rank = |p: f64| -> f64 {
            if times.is_empty() {
                return 0.0;
            }
            let k = ((p * times.len() as f64).ceil() as usize).clamp(1, times.len());
            times[k - 1]
        };
        let sim_time_s = rounds as f64 * period_s;
        TaskSummary {
            tasks_done: times.len() as u64,
            sim_time_s,
            throughput_per_hour: if sim_time_s > 0.0 {
                times.len() as f64 * 3600.0 / sim_time_s
            } else {
                0.0
            },
            task_time_p50_s: rank(0.5),
            task_time_p99_s: rank(0.99),
            window_s: WINDOW_S,
            per_window,
        }
    }

    /// The fewest tasks done in a full window (all windows when none is full).
    pub fn fewest_per_full_window(&self) -> u64 {
        let full = (self.sim_time_s / WINDOW_S).floor() as usize;
        let n = if full == 0 {
            self.per_window.len()
        } else {
            full
        };
        self.per_window.iter().take(n).copied().min().unwrap_or(0)
    }

    /// The summary table's line.
    pub fn render(&self) -> String {
        format!(
            "tasks: {} done in {:.0} s, {:.1} per hour, p50 {:.1} s, p99 {:.1} s, fewest in a {:.0} s window {}\n",
            self.tasks_done,
            self.sim_time_s,
            self.throughput_per_hour,
            self.task_time_p50_s,
            self.task_time_p99_s,
            self.window_s,
            self.fewest_per_full_window()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(round: u64, agent: u32, task: u64) -> TaskRecord {
        TaskRecord {
            round,
            agent,
            task,
            goal: 0,
        }
    }

    #[test]
    fn times_run_from_one_task_record_to_the_next_and_repeats_count_once() {
        // 10 ms rounds: 20 000 rounds = 200 s, one window.
        let r = [t(100, 0, 1), t(100, 0, 1), t(300, 1, 1), t(400, 0, 2)];
        let s = TaskSummary::new(&r, 20_000, 0.01);
        assert_eq!(s.tasks_done, 3);
        assert_eq!(s.per_window, [3]);
        assert!((s.task_time_p50_s - 3.0).abs() < 1e-9, "{s:?}");
        assert!((s.task_time_p99_s - 3.0).abs() < 1e-9, "{s:?}");
        assert!((s.throughput_per_hour - 54.0).abs() < 1e-9, "{s:?}");
        // 700 s: two full windows and a partial one; the empty second one shows.
        let s = TaskSummary::new(&[t(100, 0, 1), t(69_000, 0, 2)], 70_000, 0.01);
        assert_eq!(s.per_window, [1, 0, 1]);
        assert_eq!(s.fewest_per_full_window(), 0);
    }
}
