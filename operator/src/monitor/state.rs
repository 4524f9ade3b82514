//! What the live view shows, folded from a feed's [`Update`]s: each agent's state, the round
//! and its rate, the latest decisions and, apart from them, the process events (down,
//! restarted, lost), the processes' health.
//!
//! Process events are kept in their own list ([`ViewState::events`]): a run under `lacam` or
//! `pibt` holds a waiting robot every round, and among the latest decisions a restart would
//! scroll away at once. Among the decisions, a robot's hold or block that repeats its
//! previous one (same verdict, kind and cell: the same request still waiting) updates that
//! line's round and count instead of adding a line.
//!
//! ## An agent's state
//!
//! | state | when |
//! |---|---|
//! | down | the supervisor announced it `Down` or `Lost` (until `Restarted`/`Up`) |
//! | at goal | its robot's ground-truth cell is its goal, with no accepted move pending and its last decision not a block or replan |
//! | moving | its last accepted move has not arrived yet (ground truth not in the accepted cell), or ground truth moved since the previous sample |
//! | blocked / replanning / held | its last decision was `Block` / `Replan` / `Hold` |
//! | waiting | no decision seen yet |
//!
//! A moving robot is held every round with "no move asked" (the agent asks for its next cell
//! only at rest), so such a hold keeps it moving; a hold for a conflict, a block and a replan
//! are given at rest and end a pending move. Ground truth is what the sim says, so a commit
//! the view did not see (a viewer reads at its own pace and may miss some) cannot leave a
//! robot that drives shown as standing.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::feed::{RunEnd, RunInfo, Update};
use super::health::HealthRow;
use crate::recording::world::apply_due;
use hnav_runtime::msg::{
    CommitView, ConflictKind, Decision, Lifecycle, LifecycleEvent, MoverPlace, Pose, Progress,
    Role, RosterState, TruthView, Verdict, View,
};

/// How many of the latest decisions and events the view keeps.
pub const RECENT: usize = 10;

/// An agent's state as the view names it (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AgentState {
    /// No decision seen yet.
    Waiting,
    /// Driving to an accepted cell.
    Moving,
    /// Held: a conflict, or nothing to ask for away from its goal.
    Held,
    /// Its move was refused.
    Blocked,
    /// The coordinator replanned it.
    Replanning,
    /// Standing on its goal.
    AtGoal,
    /// Its process is down or lost.
    Down,
}

impl AgentState {
    /// The label the view prints.
    pub fn label(self) -> &'static str {
        match self {
            AgentState::Waiting => "waiting",
            AgentState::Moving => "moving",
            AgentState::Held => "held",
            AgentState::Blocked => "blocked",
            AgentState::Replanning => "replanning",
            AgentState::AtGoal => "at goal",
            AgentState::Down => "down",
        }
    }
}

/// One agent as the view knows it.
#[derive(Debug, Clone, PartialEq)]
pub struct AgentView {
    /// Its goal cell.
    pub goal: u32,
    /// Its robot's cell: ground truth once the sim has reported, its start before.
    pub cell: Option<u32>,
    pose: Option<Pose>,
    moved: bool,
    pending: Option<u32>,
    last: Option<(Verdict, ConflictKind)>,
    down: bool,
    lost: bool,
    /// Its robot's latest view (`[sensing]`).
    view: Option<View>,
}

impl AgentView {
    fn new(start: u32, goal: u32) -> Self {
        Self {
            goal,
            cell: Some(start),
            pose: None,
            moved: false,
            pending: None,
            last: None,
            down: false,
            lost: false,
            view: None,
        }
    }

    /// Its state now (see the [module docs](self)).
    pub fn state(&self) -> AgentState {
        if self.down {
            return AgentState::Down;
        }
        let settled = !matches!(
            self.last,
            Some((Verdict::Block | Verdict::Replan, _)) | None
        );
        if self.pose.is_some() && self.cell == Some(self.goal) && self.pending.is_none() && settled
        {
            return AgentState::AtGoal;
        }
        if self.pending.is_some() || self.moved {
            return AgentState::Moving;
        }
        match self.last {
            None => AgentState::Waiting,
            Some((Verdict::Accept, _)) => AgentState::Moving,
            Some((Verdict::Hold, _)) => AgentState::Held,
            Some((Verdict::Block, _)) => AgentState::Blocked,
            Some((Verdict::Replan, _)) => AgentState::Replanning,
            Some((Verdict::Task, _)) => AgentState::Waiting,
        }
    }

    /// Whether the supervisor gave it up (`Lost`).
    pub fn lost(&self) -> bool {
        self.lost
    }

    fn decide(&mut self, verdict: Verdict, kind: ConflictKind, cell: u32) {
        match (verdict, kind) {
            (Verdict::Accept, _) => self.pending = Some(cell),
            // Asked for nothing: still driving to what was accepted, if anything.
            (Verdict::Hold, ConflictKind::None) | (Verdict::Task, _) => {}
            _ => self.pending = None,
        }
        self.last = Some((verdict, kind));
    }

    fn place(&mut self, cell: Option<u32>, pose: Pose) {
        // A pose that changed at all, turning on the spot too, is a robot on its way.
        self.moved = self.pose.is_some_and(|p| {
            (p.x_m - pose.x_m).hypot(p.y_m - pose.y_m) > 1e-4
                || (p.theta_rad - pose.theta_rad).abs() > 1e-3
        });
        self.pose = Some(pose);
        self.cell = cell;
        if cell.is_some() && cell == self.pending {
            self.pending = None;
        }
    }
}

/// One line of the latest decisions: a decision other than "held, nothing asked", or a run
/// of the same hold or block of one agent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecentLine {
    /// The round of the latest decision of the line.
    pub round: u64,
    /// The agent.
    pub agent: u32,
    /// What was decided.
    pub verdict: Verdict,
    /// Why (for a block or hold).
    pub kind: ConflictKind,
    /// The cell decided (accepted, or the one asked for and refused or held).
    pub cell: u32,
    /// The rounds the line stands for: 1, or how many times a hold or block repeated.
    pub times: u32,
}

/// A process went down, was restarted or lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProcessEvent {
    /// The round last seen when it was announced.
    pub round: u64,
    /// Its role.
    pub role: Role,
    /// Its agent index (or replica id), else 0.
    pub index: u32,
    /// Down, restarted or lost.
    pub event: LifecycleEvent,
}

/// Rounds per second over the last second, from (time, round) samples.
#[derive(Debug, Clone, Default)]
pub struct RateMeter {
    samples: VecDeque<(Instant, u64)>,
}

impl RateMeter {
    /// The window the rate is measured over.
    pub const WINDOW: Duration = Duration::from_secs(1);

    /// Notes that `round` was the latest at `at`.
    pub fn note(&mut self, at: Instant, round: u64) {
        if self.samples.back().is_some_and(|&(_, r)| r == round) {
            return;
        }
        self.samples.push_back((at, round));
        self.trim(at);
    }

    /// Rounds per second over the window ending `now`: the round now less the round at the
    /// window's start (the latest noted at or before it), so a stalled run falls to 0 within
    /// a window. A meter younger than the window measures the span its samples cover.
    pub fn rate(&self, now: Instant) -> f64 {
        let Some(&(t1, r1)) = self.samples.back() else {
            return 0.0;
        };
        let start = self
            .samples
            .iter()
            .rev()
            .find(|&&(t, _)| now.saturating_duration_since(t) >= Self::WINDOW);
        let (r0, span) = match start {
            Some(&(_, r0)) => (r0, Self::WINDOW),
            None => {
                let (t0, r0) = self.samples[0];
                (r0, t1.saturating_duration_since(t0))
            }
        };
        let span = span.as_secs_f64();
        if span <= 0.0 {
            0.0
        } else {
            (r1 - r0) as f64 / span
        }
    }

    fn trim(&mut self, now: Instant) {
        // Keep the newest sample at or before the window's start, and everything after it.
        while self.samples.len() > 1
            && now.saturating_duration_since(self.samples[1].0) >= Self::WINDOW
        {
            self.samples.pop_front();
        }
    }
}

/// Everything the screen shows.
#[derive(Debug, Clone)]
pub struct ViewState {
    /// The run's static picture.
    pub info: RunInfo,
    /// One entry per agent.
    pub agents: Vec<AgentView>,
    /// The latest round seen (commit or progress).
    pub round: u64,
    /// The coordinator's latest tally.
    pub progress: Option<Progress>,
    /// Collisions so far (ground truth).
    pub collisions: u32,
    /// Commits the view did not receive since the first it did (it reads at its own pace;
    /// the coordinator never waits for it).
    pub missed_commits: u64,
    /// The latest decisions, newest last.
    pub recent: VecDeque<RecentLine>,
    /// The latest process events (down, restarted, lost), newest last.
    pub events: VecDeque<ProcessEvent>,
    /// The run's processes.
    pub health: Vec<HealthRow>,
    /// Set once the run is over.
    pub ended: Option<RunEnd>,
    /// Where the moving obstacles on the floor are (a run with movers).
    pub movers: Vec<MoverPlace>,
    rate: RateMeter,
    last_commit: Option<u64>,
    truth_period: Option<u64>,
    /// The scenario's closes and opens applied to the map so far.
    changed: usize,
}

impl ViewState {
    /// The state of a run nothing has been heard from yet.
    pub fn new(info: RunInfo) -> Self {
        let agents = info
            .starts
            .iter()
            .zip(&info.goals)
            .map(|(&s, &g)| AgentView::new(s, g))
            .collect();
        Self {
            info,
            agents,
            round: 0,
            progress: None,
            collisions: 0,
            missed_commits: 0,
            recent: VecDeque::with_capacity(RECENT),
            events: VecDeque::with_capacity(RECENT),
            health: Vec::new(),
            ended: None,
            movers: Vec::new(),
            rate: RateMeter::default(),
            last_commit: None,
            truth_period: None,
            changed: 0,
        }
    }

    /// Folds one update in, received at `now`.
    pub fn apply(&mut self, update: Update<'_>, now: Instant) {
        match update {
            Update::Truth(t) => self.truth(t),
            Update::Commit(c) => self.commit(c, now),
            Update::Progress(p) => self.progress(p, now),
            Update::Lifecycle(l) => self.lifecycle(l),
            Update::Health(rows) => {
                self.health.clear();
                self.health.extend_from_slice(rows);
            }
            Update::Ended(why) => {
                self.ended.get_or_insert(why);
            }
            Update::View(v) => {
                if let Some(a) = self.agents.get_mut(v.agent as usize) {
                    a.view = Some(*v);
                }
            }
            Update::Movers(poses) => {
                self.movers.clear();
                self.movers.extend_from_slice(poses);
            }
        }
    }

    /// The cells (0-based row-major) the moving obstacles' centres are in now.
    pub fn mover_cells(&self) -> impl Iterator<Item = u32> + '_ {
        self.movers
            .iter()
            .filter_map(|m| self.info.cell_of(&m.pose))
    }

    /// Per cell of the map, whether a robot's range sensor sees it now (its latest view).
    pub fn sensed(&self) -> Vec<bool> {
        let g = &self.info.grid;
        let mut out = vec![false; g.len()];
        for v in self.agents.iter().filter_map(|a| a.view.as_ref()) {
            for (x, y, _) in v
                .cells()
                .filter(|&(x, y, _)| x < g.width() && y < g.height())
            {
                out[(y * g.width() + x) as usize] = true;
            }
        }
        out
    }

    /// Rounds per second over the last second.
    pub fn rounds_per_s(&self, now: Instant) -> f64 {
        if self.ended.is_some() {
            return 0.0;
        }
        self.rate.rate(now)
    }

    /// How many agents are at their goal now.
    pub fn at_goal(&self) -> usize {
        self.agents
            .iter()
            .filter(|a| a.state() == AgentState::AtGoal)
            .count()
    }

    fn truth(&mut self, t: TruthView<'_>) {
        if self.truth_period.is_some_and(|p| t.period() <= p) {
            return; // a restarted sim sends its last period again
        }
        self.truth_period = Some(t.period());
        self.collisions = t.collisions();
        // The world's changes the sim has made by now: closed cells are walls on screen.
        let info = &mut self.info;
        apply_due(
            &mut info.grid,
            &info.changes,
            &mut self.changed,
            t.sim_time_ns(),
        );
        for (agent, pose) in self.agents.iter_mut().zip(t.poses()) {
            let cell = self.info.cell_of(pose);
            agent.place(cell, *pose);
        }
    }

    fn commit(&mut self, c: CommitView<'_>, now: Instant) {
        if let Some(last) = self.last_commit {
            if c.round() <= last {
                return; // a restarted coordinator resends its last commit
            }
            self.missed_commits += c.round() - last - 1;
        }
        self.last_commit = Some(c.round());
        self.note_round(c.round(), now);
        for d in c.decisions() {
            self.decision(c.round(), d);
        }
    }

    fn decision(&mut self, round: u64, d: &Decision) {
        let (Some(verdict), Some(kind)) =
            (Verdict::from_u8(d.verdict), ConflictKind::from_u8(d.kind))
        else {
            return; // not a decision this build understands
        };
        let Some(agent) = self.agents.get_mut(d.agent as usize) else {
            return;
        };
        if verdict == Verdict::Task {
            // A lifelong run's next goal: the robot heads for it from where it stands.
            agent.goal = d.waypoint;
        }
        agent.decide(verdict, kind, d.cell);
        if !(verdict == Verdict::Hold && kind == ConflictKind::None) {
            self.push_recent(RecentLine {
                round,
                agent: d.agent,
                verdict,
                kind,
                cell: d.cell,
                times: 1,
            });
        }
    }

    fn progress(&mut self, p: &Progress, now: Instant) {
        self.progress = Some(*p);
        self.note_round(p.round, now);
        match p.done {
            Progress::ALL_AT_GOAL => self.apply(Update::Ended(RunEnd::AllAtGoal), now),
            Progress::TIME_LIMIT => self.apply(Update::Ended(RunEnd::TimeLimit), now),
            _ => {}
        }
    }

    fn lifecycle(&mut self, l: &Lifecycle) {
        let (Some(role), Some(event)) = (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
        else {
            return;
        };
        if event == LifecycleEvent::Stop {
            self.ended.get_or_insert(RunEnd::Stopped);
            return;
        }
        let agent = match role {
            Role::Agent => self.agents.get_mut(l.index as usize),
            _ => None,
        };
        if let Some(a) = agent {
            match event {
                LifecycleEvent::Down => a.down = true,
                LifecycleEvent::Lost => (a.down, a.lost) = (true, true),
                LifecycleEvent::Up | LifecycleEvent::Restarted => a.down = false,
                LifecycleEvent::Roster => match RosterState::from_u8(l.reason) {
                    Some(RosterState::Up) => a.down = false,
                    Some(RosterState::Down) => a.down = true,
                    Some(RosterState::Lost) => (a.down, a.lost) = (true, true),
                    None => {}
                },
                _ => {}
            }
        }
        if matches!(
            event,
            LifecycleEvent::Down | LifecycleEvent::Restarted | LifecycleEvent::Lost
        ) {
            if self.events.len() == RECENT {
                self.events.pop_front();
            }
            self.events.push_back(ProcessEvent {
                round: self.round,
                role,
                index: l.index,
                event,
            });
        }
    }

    fn note_round(&mut self, round: u64, now: Instant) {
        if round > self.round {
            self.round = round;
            self.rate.note(now, round);
        }
    }

    /// Adds a decision's line; a hold or block that repeats the agent's latest line (the
    /// same request still waiting) moves that line to the end with its count raised.
    fn push_recent(&mut self, line: RecentLine) {
        let same = |l: &RecentLine| {
            (l.verdict, l.kind, l.cell) == (line.verdict, line.kind, line.cell)
                && line.verdict != Verdict::Accept
        };
        if let Some(k) = self.recent.iter().rposition(|l| l.agent == line.agent) {
            if same(&self.recent[k]) {
                if let Some(mut old) = self.recent.remove(k) {
                    old.round = line.round;
                    old.times = old.times.saturating_add(1);
                    self.recent.push_back(old);
                }
                return;
            }
        }
        if self.recent.len() == RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back(line);
    }
}

#[cfg(test)]
#[path = "state_tests.rs"]
mod tests;
