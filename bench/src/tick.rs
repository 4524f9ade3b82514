//! A discrete-time multi-agent run, as in the dissertation's and seed 001's experiments.
//!
//! Every tick, each unfinished agent at rest picks its `probable` step by gradient ascent on
//! its **own** neural map (goal = activation point; the agents' maps share the static
//! obstacles only), all rows go to [`conflict::Resolver`], accepted agents commit their step
//! and refused ones follow a [`Policy`]. An agent on its goal becomes
//! [`Finished`](AgentMode::Finished): a type (d) obstacle for the others.
//!
//! [`Timing::Ticks`] is the papers' model: an accepted move completes within its tick, so all
//! agents move at one cell per tick. [`Timing::Speeds`] gives each agent a speed: a move of
//! length `l` (1 or `sqrt 2`) takes `l / speed` seconds, during which the agent's row is
//! "moving" (`next != current`) and holds both cells; it can ask again at the first tick
//! boundary after it arrived. The dissertation's Chapter 3 experiments need that, because
//! which robot is where when two meet depends on their speeds.
//!
//! Everything is recorded per agent (cells, arrival tick, length, turns) together with every
//! conflict and the rows at the end of each tick, so tests can check invariants afterwards.

use hnav_agent::neural_map::{
    ActivationField, DiagonalRule, Local, NeuralDynamics, NeuralMap, NeuralMapOptions, StopRule,
};
use hnav_agent::path_constructor::{DirectionMask, PathConstructor, PathOptions, Walker};
use hnav_coordinator::conflict::{self, AgentMode, AgentRow, Outcome, Resolver};
use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::{ConflictKind, Verdict};

/// What a refused (blocked) agent does.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Policy {
    /// Stay in place this tick. With `negate` (seed 001, rule (a)), the contested cell's
    /// activation becomes `-|E|` in the agent's own map for the rest of the run; without it
    /// the refused direction is masked at the next tick's pick (the virtual obstacle, §3.4).
    /// Corner cuts and refusals of the agent's own goal are always masked, never negated.
    Hold {
        /// Negate the contested cell in the agent's map.
        negate: bool,
    },
    /// Mask the refused direction and pick again at once, within the same tick, until no
    /// refused agent has anything new to ask.
    Sidestep,
}

/// How long a move takes.
#[derive(Clone, PartialEq, Debug)]
pub enum Timing {
    /// Every accepted move completes within its tick.
    Ticks,
    /// Agent `i` drives `speeds[i]` cells per second; a tick lasts `dt` seconds.
    Speeds {
        /// Cells per second, one per agent.
        speeds: Vec<f64>,
        /// Seconds per tick.
        dt: f64,
    },
}

/// How cells are numbered when printed: the papers number them from 1.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum CellIds {
    /// Row by row from the top-left (the dissertation): `y * width + x + 1`.
    RowMajor,
    /// Column by column (seed 001's MATLAB): `x * height + y + 1`.
    ColumnMajor,
}

impl CellIds {
    /// The 1-based id of a cell of `grid`.
    pub fn id(self, grid: &Grid, cell: Cell) -> u32 {
        match self {
            CellIds::RowMajor => grid.cell_id(cell),
            CellIds::ColumnMajor => cell.x * grid.height() + cell.y + 1,
        }
    }

    /// The cell with a 1-based id, if it lies on `grid`.
    pub fn cell(self, grid: &Grid, id: u32) -> Option<Cell> {
        match self {
            CellIds::RowMajor => grid.cell_from_id(id),
            CellIds::ColumnMajor => {
                let i = id.checked_sub(1)?;
                let c = Cell::new(i / grid.height(), i % grid.height());
                grid.contains(c).then_some(c)
            }
        }
    }
}

/// One agent of a run.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct AgentSpec {
    /// Start cell.
    pub start: Cell,
    /// Goal cell (the activation point of its map).
    pub goal: Cell,
    /// Conflict priority, larger wins.
    pub priority: f64,
}

/// Everything about a run but the agents.
#[derive(Clone, PartialEq, Debug)]
pub struct TickConfig {
    /// Neural-map options (each agent's map is built to full activation).
    pub map: NeuralMapOptions,
    /// Path-constructor options (heading bonus = eq. 3.7 smoothing).
    pub path: PathOptions,
    /// Conflict-resolution options.
    pub resolver: conflict::Options,
    /// What refused agents do.
    pub policy: Policy,
    /// How long moves take.
    pub timing: Timing,
    /// Give up after this many ticks.
    pub max_ticks: usize,
    /// How cells are printed.
    pub ids: CellIds,
}

/// One refused or held request.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct ConflictEvent {
    /// Tick (1-based: the first decision is tick 1).
    pub tick: usize,
    /// The agent (0-based).
    pub agent: usize,
    /// The other agent, if any.
    pub other: Option<usize>,
    /// The contested (requested) cell.
    pub cell: Option<Cell>,
    /// Where the agent was.
    pub current: Cell,
    /// The conflict type.
    pub kind: ConflictKind,
    /// Block or Hold.
    pub verdict: Verdict,
}

/// What one agent did.
#[derive(Clone, PartialEq, Debug, Default)]
pub struct AgentTrace {
    /// Cells from the start, one per move.
    pub cells: Vec<Cell>,
    /// The tick in which it arrived (the papers' `steps`: waits included), if it did.
    pub arrived: Option<usize>,
    /// Ticks in which it was at rest, unfinished and did not start a move.
    pub waits: usize,
    /// Straight moves count 1, diagonal ones `sqrt 2`.
    pub length: f64,
    /// Changes of direction between consecutive moves.
    pub turns: usize,
}

impl AgentTrace {
    /// Moves made.
    pub fn moves(&self) -> usize {
        self.cells.len().saturating_sub(1)
    }
}

/// A finished run.
#[derive(Clone, PartialEq, Debug)]
pub struct TickRun {
    /// Per agent.
    pub agents: Vec<AgentTrace>,
    /// Every Block and Hold with a conflict kind, in order.
    pub conflicts: Vec<ConflictEvent>,
    /// The rows at the start (index 0) and at the end of every tick (with
    /// [`Timing::Speeds`], one more after the last arrivals).
    pub history: Vec<Vec<AgentRow>>,
    /// Seconds per tick (1 with [`Timing::Ticks`]).
    pub dt: f64,
}

impl TickRun {
    /// Whether every agent arrived.
    pub fn all_arrived(&self) -> bool {
        self.agents.iter().all(|a| a.arrived.is_some())
    }

    /// The refusals (Block) only: the papers' conflict logs list these.
    pub fn refusals(&self) -> impl Iterator<Item = &ConflictEvent> {
        self.conflicts
            .iter()
            .filter(|e| e.verdict == Verdict::Block)
    }

    /// Invariant breaches: two agents holding a common cell at the end of a tick (under
    /// `options`), or two agents swapping cells between two ticks.
    pub fn violations(&self, options: &conflict::Options) -> Vec<String> {
        let mut v = Vec::new();
        for (t, rows) in self.history.iter().enumerate() {
            for (i, a) in rows.iter().enumerate() {
                for (j, b) in rows.iter().enumerate().skip(i + 1) {
                    let held_b: Vec<Cell> = b.held(options).into_iter().flatten().collect();
                    if let Some(c) = a
                        .held(options)
                        .into_iter()
                        .flatten()
                        .find(|c| held_b.contains(c))
                    {
                        v.push(format!("tick {t}: agents {i} and {j} both hold {c}"));
                    }
                    if t > 0 {
                        let (pa, pb) = (&self.history[t - 1][i], &self.history[t - 1][j]);
                        if a.current == pb.current
                            && b.current == pa.current
                            && a.current != pa.current
                        {
                            v.push(format!("tick {t}: agents {i} and {j} swap"));
                        }
                    }
                }
            }
        }
        v
    }
}

/// A map with some cells' activations negated (seed 001's `E_i(N) <- -|E_i(N)|`), read
/// through the [`ActivationField`] the path constructor climbs.
struct Negated<'a> {
    map: &'a NeuralMap,
    negated: &'a [bool],
}

impl ActivationField for Negated<'_> {
    fn width(&self) -> u32 {
        self.map.width()
    }
    fn height(&self) -> u32 {
        self.map.height()
    }
    fn is_blocked(&self, cell: Cell) -> bool {
        self.map.is_blocked(cell)
    }
    fn diagonal_rule(&self) -> DiagonalRule {
        self.map.diagonal_rule()
    }
    fn target(&self) -> Option<Cell> {
        self.map.target()
    }
    fn local(&self, cell: Cell) -> Local {
        let mut local = self.map.local(cell);
        let w = self.map.width();
        let is_negated =
            |c: Cell| c.x < w && c.y < self.map.height() && self.negated[(c.y * w + c.x) as usize];
        for d in Direction::ALL {
            if cell.offset(d.dx(), d.dy()).is_some_and(is_negated) {
                local.values[d.index()] = -local.values[d.index()].abs();
            }
        }
        if is_negated(cell) {
            local.values[8] = -local.values[8].abs();
        }
        local
    }
    fn log2_value(&self, cell: Cell) -> f64 {
        self.map.log2_value(cell)
    }
}

/// Per-agent state of a run.
struct Agent {
    map: NeuralMap,
    walker: Walker,
    negated: Vec<bool>,
    /// Directions refused for the coming pick.
    mask: DirectionMask,
    /// Time at which the current move ends.
    arrives_at: f64,
}

/// Runs `agents` on `grid` until all have arrived or `config.max_ticks` ticks have passed.
pub fn run(grid: &Grid, agents: &[AgentSpec], config: &TickConfig) -> Result<TickRun, String> {
    let pc = PathConstructor::new(config.path).map_err(|e| e.to_string())?;
    let (speeds, dt) = match &config.timing {
        Timing::Ticks => (vec![f64::INFINITY; agents.len()], 1.0),
        Timing::Speeds { speeds, dt } => {
            if speeds.len() != agents.len()
                || speeds.iter().any(|s| !(s.is_finite() && *s > 0.0))
                || !(dt.is_finite() && *dt > 0.0)
            {
                return Err("one positive speed per agent and a positive dt".into());
            }
            (speeds.clone(), *dt)
        }
    };
    let mut state = Vec::new();
    let mut rows = Vec::new();
    for a in agents {
        let mut map = NeuralMap::new(grid, config.map).map_err(|e| e.to_string())?;
        map.build(a.goal, StopRule::FullActivation)
            .map_err(|e| e.to_string())?;
        state.push(Agent {
            map,
            walker: Walker::new(grid.width(), grid.height(), a.start),
            negated: vec![false; grid.len()],
            mask: DirectionMask::NONE,
            arrives_at: 0.0,
        });
        let mut row = AgentRow::at_rest(a.start, None, a.priority);
        if a.start == a.goal {
            row.mode = AgentMode::Finished;
        }
        rows.push(row);
    }
    let mut run = TickRun {
        agents: agents
            .iter()
            .map(|a| AgentTrace {
                cells: vec![a.start],
                arrived: (a.start == a.goal).then_some(0),
                ..AgentTrace::default()
            })
            .collect(),
        conflicts: Vec::new(),
        history: vec![rows.clone()],
        dt,
    };
    let mut resolver = Resolver::new(grid, agents.len(), config.resolver);
    let corners = config.resolver.corner_cutting;
    let mut out: Vec<Outcome> = Vec::new();
    for tick in 1..=config.max_ticks {
        let now = (tick - 1) as f64 * dt;
        // Arrivals.
        for (i, row) in rows.iter_mut().enumerate() {
            if !row.is_at_rest() && state[i].arrives_at <= now + 1e-9 {
                row.current = row.next;
                if row.current == agents[i].goal {
                    row.mode = AgentMode::Finished;
                    run.agents[i].arrived = Some(tick - 1);
                }
            }
        }
        if rows.iter().all(|r| r.mode == AgentMode::Finished) {
            if config.timing != Timing::Ticks {
                run.history.push(rows.clone());
            }
            break;
        }
        // Picks.
        for (i, row) in rows.iter_mut().enumerate() {
            row.probable = None;
            if row.mode == AgentMode::Active && row.is_at_rest() {
                row.probable = pick(&pc, &state[i], grid, corners);
            }
        }
        resolver.resolve(&rows, &mut out);
        log(&mut run, tick, &rows, &out, Verdict::Block);
        if config.policy == Policy::Sidestep {
            // Masks only grow, so this ends within 8 passes per agent.
            for _ in 0..8 * agents.len() + 1 {
                let mut changed = false;
                for (i, o) in out.iter().enumerate() {
                    if o.verdict == Verdict::Block {
                        let s = &mut state[i];
                        s.mask = DirectionMask(s.mask.0 | o.refused);
                        let p = pick(&pc, s, grid, corners);
                        changed |= p != rows[i].probable;
                        rows[i].probable = p;
                    }
                }
                if !changed {
                    break;
                }
                resolver.resolve(&rows, &mut out);
                log(&mut run, tick, &rows, &out, Verdict::Block);
            }
        }
        log(&mut run, tick, &rows, &out, Verdict::Hold);
        // Apply.
        for (i, o) in out.iter().enumerate() {
            let row = &mut rows[i];
            let s = &mut state[i];
            match o.verdict {
                Verdict::Accept => {
                    let p = o.cell.ok_or("accepted without a cell")?;
                    let d = Direction::between(row.current, p).ok_or("accepted a non-neighbour")?;
                    let trace = &mut run.agents[i];
                    if s.walker.heading().is_some_and(|h| h != d) {
                        trace.turns += 1;
                    }
                    s.walker.advance(d);
                    trace.cells.push(p);
                    trace.length += d.cost();
                    s.mask = DirectionMask::NONE;
                    row.next = p;
                    s.arrives_at = now + d.cost() / speeds[i];
                    if config.timing == Timing::Ticks {
                        row.current = p;
                        if p == agents[i].goal {
                            row.mode = AgentMode::Finished;
                            run.agents[i].arrived = Some(tick);
                        }
                    }
                }
                _ if row.mode != AgentMode::Active || !row.is_at_rest() => {}
                Verdict::Block => {
                    run.agents[i].waits += 1;
                    match config.policy {
                        // A corner cut's trouble is the swept side cell, not the requested
                        // one, and negating its own goal would send an agent away for good:
                        // those get the direction mask instead.
                        Policy::Hold { negate: true }
                            if o.kind != ConflictKind::CornerCut
                                && o.cell.is_some_and(|c| c != agents[i].goal) =>
                        {
                            if let Some(c) = o.cell {
                                s.negated[grid.index(c)] = true;
                            }
                            s.mask = DirectionMask::NONE;
                        }
                        Policy::Hold { .. } => s.mask = DirectionMask(o.refused),
                        Policy::Sidestep => s.mask = DirectionMask::NONE,
                    }
                }
                _ => {
                    run.agents[i].waits += 1;
                    s.mask = DirectionMask::NONE;
                }
            }
        }
        run.history.push(rows.clone());
    }
    Ok(run)
}

/// The agent's next cell by gradient ascent on its own map (with its negated cells and
/// masked directions), or `None` when every direction is refused. Diagonals that cut a
/// blocked map corner under `rule` are masked first (Fig. 3-7 on the map), so that the path
/// constructor's own corner rule can stay off for the coordinator's refusals.
fn pick(pc: &PathConstructor, agent: &Agent, grid: &Grid, rule: CornerCutting) -> Option<Cell> {
    let field = Negated {
        map: &agent.map,
        negated: &agent.negated,
    };
    let cell = agent.walker.cell();
    let mut mask = agent.mask;
    for d in Direction::ALL.into_iter().filter(|d| d.is_diagonal()) {
        let side = |dx: i32, dy: i32| cell.offset(dx, dy).is_none_or(|c| grid.is_blocked(c));
        let (a, b) = (side(d.dx(), 0), side(0, d.dy()));
        let cut = match rule {
            CornerCutting::Forbidden => a || b,
            CornerCutting::Allowed => a && b,
        };
        if cut {
            mask = mask.refuse(d);
        }
    }
    let (d, _) = agent.walker.propose(pc, &field, mask);
    d.and_then(|d| grid.step(cell, d))
}

/// Appends the outcomes with verdict `verdict` and a conflict kind to the run's log.
fn log(run: &mut TickRun, tick: usize, rows: &[AgentRow], out: &[Outcome], verdict: Verdict) {
    for (i, o) in out.iter().enumerate() {
        if o.verdict == verdict && o.kind != ConflictKind::None {
            run.conflicts.push(ConflictEvent {
                tick,
                agent: i,
                other: o.other.map(|j| j as usize),
                cell: o.cell,
                current: rows[i].current,
                kind: o.kind,
                verdict: o.verdict,
            });
        }
    }
}

/// One line per agent (ours), for `--nocapture` output.
pub fn summary(run: &TickRun, grid: &Grid, ids: CellIds) -> String {
    let mut s = String::new();
    for (i, a) in run.agents.iter().enumerate() {
        let cells: Vec<String> = a
            .cells
            .iter()
            .map(|&c| ids.id(grid, c).to_string())
            .collect();
        s += &format!(
            "agent {}: steps {:?} (time {:?} s), moves {}, waits {}, length {:.2}, turns {}, path {}\n",
            i + 1,
            a.arrived,
            a.arrived.map(|t| t as f64 * run.dt),
            a.moves(),
            a.waits,
            a.length,
            a.turns,
            cells.join(" ")
        );
    }
    for e in &run.conflicts {
        s += &format!("  {}\n", event_line(e, grid, ids));
    }
    s
}

/// A conflict as the papers print it: tick, agents, contested cell, current cell.
pub fn event_line(e: &ConflictEvent, grid: &Grid, ids: CellIds) -> String {
    format!(
        "t{} r{} vs r{} @{} cur {} ({:?} {})",
        e.tick,
        e.agent + 1,
        e.other.map_or("-".to_string(), |o| (o + 1).to_string()),
        e.cell
            .map_or("-".to_string(), |c| ids.id(grid, c).to_string()),
        ids.id(grid, e.current),
        e.verdict,
        e.kind.name()
    )
}
