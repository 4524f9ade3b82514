//! A lifelong run's goals (`[tasks]`): the next goal of an agent that stands on its goal,
//! and the goals of a log replayed.
//!
//! An agent that says it stands on its goal on another cell than the coordinator's goal for
//! it has an old goal: a restarted agent (it starts from its `[[agents]] goal`), or one whose
//! commit with its task was lost in realtime. It gets its current goal again, without a new
//! task record. So does a restarted agent that was given tasks, in its first candidate (it
//! is marked restarted), unless it is moved in that round.

use hnav_runtime::consensus_log::TaskRecord;
use hnav_runtime::grid::Cell;
use hnav_runtime::msg::{CandidateFlags, Decision, Verdict};

use super::{Arbiter, Round};

impl Arbiter {
    /// Whether the run is lifelong (`[tasks]`): it ends by time, not when all are at goal.
    pub fn lifelong(&self) -> bool {
        self.tasks.is_some()
    }

    /// The tasks given in the last round decided, in agent order.
    pub fn assigned(&self) -> &[TaskRecord] {
        &self.assigned
    }

    /// Agent `i`'s answer with its next task in place of `answer` when it stands on its goal
    /// and was not moved.
    pub(super) fn give_task(
        &mut self,
        round: u64,
        i: usize,
        answer: Option<Decision>,
    ) -> Option<Decision> {
        let Some(stream) = self.tasks.as_mut() else {
            return answer;
        };
        let moved = answer.is_some_and(|d| d.verdict == Verdict::Accept as u8);
        let at_goal = self.flags[i] & CandidateFlags::AT_GOAL != 0;
        // A restarted agent heads for its first goal again: it learns its current one at once.
        let restarted = self.flags[i] & CandidateFlags::RESTARTED != 0 && stream.given(i) > 0;
        if moved || !(at_goal || restarted) {
            return answer;
        }
        let here = self.rows[i].current;
        let goal = match stream.goal(i) {
            Some(g) if g != here || !at_goal => g,
            _ => {
                let Some((task, goal)) = stream.next(i) else {
                    return answer;
                };
                self.assigned.push(TaskRecord {
                    round,
                    agent: i as u32,
                    task,
                    goal: self.grid.index(goal) as u32,
                });
                self.head_for(i, goal);
                goal
            }
        };
        Some(Decision {
            agent: i as u32,
            verdict: Verdict::Task as u8,
            waypoint: self.grid.index(goal) as u32,
            ..Decision::default()
        })
    }

    /// Folds a logged task record in: the stream and the rules head for its goal.
    pub fn replay_task(&mut self, t: &TaskRecord) {
        let Some(goal) = self.grid.cell_at(t.goal as usize) else {
            return;
        };
        if let Some(stream) = self.tasks.as_mut() {
            stream.assigned(t.agent as usize, t.task, goal);
            self.head_for(t.agent as usize, goal);
        }
    }

    /// Agent `i`'s goal is `goal` from now on, for the replans and the rules.
    fn head_for(&mut self, i: usize, goal: Cell) {
        if let Some(g) = self.goals.get_mut(i) {
            *g = goal;
        }
        match &mut self.round {
            Round::Dissertation(_) => {}
            Round::Pibt(p) => p.set_goal(&self.grid, i, goal),
            Round::Lacam(l) => l.set_goal(&self.grid, i, goal),
        }
    }
}
