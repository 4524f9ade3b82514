//! Single planning queries: `hnav-bench plan`.
//!
//! One command answers a query with any of HNAV's planners, so that the neural map and the
//! coordinator's global planners are compared on the same inputs and against the same
//! external oracle, the optimal lengths of MovingAI's `.scen` files.
//!
//! With `--start`/`--goal` it answers one query; with `--scen FILE [--first N]` it answers
//! every entry (or the first N), each line adding the scenario's `optimal` length, and ends
//! with one summary line. `--json` prints JSON lines; without it, a table.

mod output;

use std::path::PathBuf;
use std::str::FromStr;

use anyhow::{bail, Context, Result};
use hnav_agent::neural_map::Activation;
use hnav_agent::plan::{PlanOptions, PlanStop, Planner as HnavPlanner};
use hnav_coordinator::planner::{
    run_query_with, Planner as GlobalPlanner, PlannerConfig, PlannerKind as GlobalKind,
};
use hnav_runtime::grid::{read_map_file, read_scen_file, Cell, CornerCutting, Grid};
use hnav_runtime::plan::PlanResult;

pub use output::{render, Summary};

/// The planners `--planner` accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlannerKind {
    /// The agent's Hopfield neural map and path constructor.
    Hnav,
    /// One of the coordinator's global planners (A*, Basic Theta*, Lazy Theta*).
    Global(GlobalKind),
}

impl FromStr for PlannerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "hnav" => Ok(Self::Hnav),
            other => other.parse().map(Self::Global).map_err(|_| {
                format!("unknown planner {other:?} (expected astar, theta, lazy-theta or hnav)")
            }),
        }
    }
}

/// A query's options, as given on the command line.
#[derive(Debug, Clone)]
pub struct PlanArgs {
    /// Which planner answers.
    pub planner: PlannerKind,
    /// The MovingAI map.
    pub map: PathBuf,
    /// One query's start and goal.
    pub endpoints: Option<(Cell, Cell)>,
    /// Or a scenario file, and how many of its entries to answer.
    pub scen: Option<(PathBuf, Option<usize>)>,
    /// The neural map's activation function.
    pub activation: Activation,
    /// The neural map's stop rule.
    pub stop: PlanStop,
    /// Whether diagonals may pass between two blocked cells.
    pub corner_cutting: bool,
}

/// Parses `X,Y` into a cell.
pub fn parse_cell(s: &str) -> Result<Cell, String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("expected X,Y, got {s:?}"))?;
    let x = x.trim().parse().map_err(|_| format!("bad x in {s:?}"))?;
    let y = y.trim().parse().map_err(|_| format!("bad y in {s:?}"))?;
    Ok(Cell { x, y })
}

/// Builds the planner once per map, so a scenario file's queries share its buffers.
enum Engine {
    Hnav(Box<HnavPlanner>),
    Global(Box<dyn GlobalPlanner + Send>),
}

impl Engine {
    fn new(args: &PlanArgs, grid: &Grid) -> Result<Self> {
        let corner_cutting = if args.corner_cutting {
            CornerCutting::Allowed
        } else {
            CornerCutting::Forbidden
        };
        match args.planner {
            PlannerKind::Hnav => {
                let options = PlanOptions {
                    activation: args.activation,
                    stop: args.stop,
                    corner_cutting,
                };
                Ok(Self::Hnav(Box::new(HnavPlanner::new(grid, &options)?)))
            }
            PlannerKind::Global(kind) => {
                Ok(Self::Global(kind.build(PlannerConfig::new(corner_cutting))))
            }
        }
    }

    fn query(&mut self, grid: &Grid, start: Cell, goal: Cell) -> Result<PlanResult> {
        match self {
            Self::Hnav(p) => Ok(p.query(start, goal)?),
            Self::Global(p) => Ok(run_query_with(p.as_mut(), grid, start, goal)?),
        }
    }
}

/// Runs the queries `args` asks for and hands each line to `emit`; returns the summary
/// (scenario runs) or `None` (a single query).
pub fn run(args: &PlanArgs, mut emit: impl FnMut(&PlanResult)) -> Result<Option<Summary>> {
    let grid = read_map_file(&args.map).map_err(anyhow::Error::msg)?;
    let mut engine = Engine::new(args, &grid)?;
    match (&args.endpoints, &args.scen) {
        (Some((start, goal)), None) => {
            emit(&engine.query(&grid, *start, *goal)?);
            Ok(None)
        }
        (None, Some((scen, first))) => {
            let file = read_scen_file(scen).map_err(anyhow::Error::msg)?;
            let mut summary = Summary::new(args.planner_name());
            for entry in file.entries.iter().take(first.unwrap_or(usize::MAX)) {
                let mut line = engine
                    .query(&grid, entry.start, entry.goal)
                    .with_context(|| format!("{}:{}", scen.display(), entry.line))?;
                line.optimal = Some(entry.optimal_length);
                summary.add(&line);
                emit(&line);
            }
            Ok(Some(summary))
        }
        _ => bail!("give either --start and --goal, or --scen"),
    }
}

impl PlanArgs {
    fn planner_name(&self) -> &'static str {
        match self.planner {
            PlannerKind::Hnav => "hnav",
            PlannerKind::Global(GlobalKind::AStar) => "astar",
            PlannerKind::Global(GlobalKind::Theta) => "theta",
            PlannerKind::Global(GlobalKind::LazyTheta) => "lazy-theta",
        }
    }
}
