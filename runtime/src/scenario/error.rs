//! Scenario errors: one variant per problem, each naming the file and line.
//!
//! Agents and faults are numbered from 0 in the order of their `[[agents]]` / `[[faults]]`
//! entries, the same numbers a fault's `index` and the runtime use.

use std::fmt;

use crate::grid::{Cell, GridError};

/// A number from a scenario as an error message prints it: as written for ordinary
/// magnitudes, in scientific notation (`1e300`) where `{}` of an `f64` would print hundreds of
/// digits.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Number(pub f64);

/// [`Number`] of `x`.
pub(crate) fn number(x: f64) -> Number {
    Number(x)
}

impl fmt::Display for Number {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        let a = x.abs();
        if x == 0.0 || !x.is_finite() || (1e-6..1e15).contains(&a) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// A place in a scenario file: the file name and a 1-based line (0 = no line, e.g. for a
/// scenario built or changed in code).
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Loc {
    /// File name as given, or `"<inline>"`.
    pub source_name: String,
    /// 1-based line, 0 if unknown.
    pub line: usize,
}

impl Loc {
    /// A location.
    pub fn new(source_name: &str, line: usize) -> Loc {
        Loc {
            source_name: source_name.into(),
            line,
        }
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}", self.source_name, self.line)
        } else {
            f.write_str(&self.source_name)
        }
    }
}

/// Shown after a map error when the map came from a file the scenario references.
fn referenced(from: &Option<Loc>) -> String {
    from.as_ref()
        .map(|l| format!(" (map referenced from {l})"))
        .unwrap_or_default()
}

/// Everything that can make a scenario unusable.
#[derive(Clone, PartialEq, Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The scenario file could not be read.
    #[error("{source_name}: cannot read scenario file: {message}")]
    Io {
        /// Path as given.
        source_name: String,
        /// Operating-system message.
        message: String,
    },
    /// TOML syntax error or a value of the wrong type.
    #[error("{at}: {message}")]
    Toml {
        /// Where.
        at: Loc,
        /// The parser's message.
        message: String,
    },
    /// A key the format does not know (usually a typo).
    #[error("{at}: unknown key `{key}` ({expected})")]
    UnknownKey {
        /// Where.
        at: Loc,
        /// The key.
        key: String,
        /// The keys allowed there.
        expected: String,
    },
    /// A required key is missing.
    #[error("{at}: missing key `{key}`")]
    MissingKey {
        /// The enclosing table.
        at: Loc,
        /// The key.
        key: String,
    },
    /// The map (file or inline rows) is malformed.
    #[error("{error}{}", referenced(.referenced_from))]
    Map {
        /// The `file = ...` line for a map file; `None` for inline rows.
        referenced_from: Option<Loc>,
        /// The map error, naming the map file (or the scenario, for inline rows) and line.
        /// Boxed to keep `Result<_, ScenarioError>` small.
        error: Box<GridError>,
    },
    /// `[map]` has both `file` and `rows`.
    #[error("{at}: [map] has both `file` and `rows`; give exactly one")]
    MapFileAndRows {
        /// The `[map]` table.
        at: Loc,
    },
    /// `[map]` has neither `file` nor `rows`.
    #[error("{at}: [map] needs `file = \"...\"` or `rows = [...]`")]
    NoMapSource {
        /// The `[map]` table.
        at: Loc,
    },
    /// A numeric parameter out of range.
    #[error("{at}: {key} {problem}")]
    InvalidParameter {
        /// Where.
        at: Loc,
        /// `section.key`.
        key: String,
        /// What is wrong.
        problem: String,
    },
    /// No `[[agents]]` at all.
    #[error("{at}: the scenario has no [[agents]]")]
    NoAgents {
        /// The file.
        at: Loc,
    },
    /// A coordinate that is not an `[x, y]` pair.
    #[error("{at}: agent {agent} {endpoint} must be [x, y], got {len} numbers")]
    BadCoordinates {
        /// Where.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// `start` or `goal`.
        endpoint: crate::grid::Endpoint,
        /// Numbers given.
        len: usize,
    },
    /// Start outside the map.
    #[error("{at}: agent {agent} start [{x}, {y}] is outside the {width}x{height} map")]
    StartOutsideMap {
        /// Where.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// Column as written.
        x: i64,
        /// Row as written.
        y: i64,
        /// Map width.
        width: u32,
        /// Map height.
        height: u32,
    },
    /// Goal outside the map.
    #[error("{at}: agent {agent} goal [{x}, {y}] is outside the {width}x{height} map")]
    GoalOutsideMap {
        /// Where.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// Column as written.
        x: i64,
        /// Row as written.
        y: i64,
        /// Map width.
        width: u32,
        /// Map height.
        height: u32,
    },
    /// Start on a blocked cell.
    #[error("{at}: agent {agent} start {cell} is on an obstacle ({ch:?})")]
    StartOnObstacle {
        /// Where.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// The cell.
        cell: Cell,
        /// Its map character.
        ch: char,
    },
    /// Goal on a blocked cell.
    #[error("{at}: agent {agent} goal {cell} is on an obstacle ({ch:?})")]
    GoalOnObstacle {
        /// Where.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// The cell.
        cell: Cell,
        /// Its map character.
        ch: char,
    },
    /// Two agents start on the same cell.
    #[error("{at}: agent {agent} starts at {cell}, where agent {other} starts too")]
    DuplicateStart {
        /// Where (the later agent).
        at: Loc,
        /// The later agent.
        agent: usize,
        /// The earlier agent.
        other: usize,
        /// The cell.
        cell: Cell,
    },
    /// Two agents share a goal.
    #[error("{at}: agent {agent} has goal {cell}, which is agent {other}'s goal too")]
    DuplicateGoal {
        /// Where (the later agent).
        at: Loc,
        /// The later agent.
        agent: usize,
        /// The earlier agent.
        other: usize,
        /// The cell.
        cell: Cell,
    },
    /// Speed zero, negative or not finite.
    #[error("{at}: agent {agent} speed must be a positive number of cells/s, got {}", number(*.speed))]
    NonPositiveSpeed {
        /// Where.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// The speed.
        speed: f64,
    },
    /// Speed above what the wheels can do.
    #[error("{at}: agent {agent} speed {} cells/s exceeds the robot's {} cells/s (max_wheel_speed_rad_s * wheel_radius_m / cell_size_m)", number(*.speed), number((*.max * 1000.0).round() / 1000.0))]
    SpeedTooHigh {
        /// Where.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// The speed.
        speed: f64,
        /// The robot's limit.
        max: f64,
    },
    /// Priority zero, negative or not finite.
    #[error("{at}: agent {agent} priority must be a positive number, got {}", number(*.priority))]
    BadPriority {
        /// Where.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// The priority.
        priority: f64,
    },
    /// A fault naming an agent that does not exist.
    #[error("{at}: fault {fault} targets agent {index}, but agents are numbered 0..{agents}")]
    FaultAgentOutOfRange {
        /// Where.
        at: Loc,
        /// Fault number.
        fault: usize,
        /// The index given.
        index: i64,
        /// Number of agents.
        agents: usize,
    },
    /// A fault with a missing or superfluous `index`.
    #[error("{at}: fault {fault}: {problem}")]
    BadFault {
        /// Where.
        at: Loc,
        /// Fault number.
        fault: usize,
        /// What is wrong.
        problem: String,
    },
    /// More agents than a run can carry: the round and truth messages have room for
    /// [`MAX_AGENTS`](crate::msg::MAX_AGENTS).
    #[error("{at}: {agents} agents, but a run holds at most {max}")]
    TooManyAgents {
        /// The first agent beyond the limit, or the scenario for a requested agent count.
        at: Loc,
        /// Agents in the scenario or requested.
        agents: usize,
        /// The limit.
        max: usize,
    },
    /// An agent's goal cannot be reached from its start, walls and the corner-cutting rule
    /// considered, and the scenario does not say `allow_unreachable = true`.
    #[error(
        "{at}: agent {agent}: goal {goal} is unreachable from start {start} \
         (write allow_unreachable = true at the top of the scenario to run it anyway)"
    )]
    UnreachableGoal {
        /// The agent's goal.
        at: Loc,
        /// Agent number.
        agent: usize,
        /// Start cell.
        start: Cell,
        /// Goal cell.
        goal: Cell,
    },
    /// [`crate::scenario::Scenario::with_agent_count`] could not place enough agents.
    #[error("{at}: cannot place {requested} agents: only {placed} distinct start/goal pairs fit the map")]
    NotEnoughFreeCells {
        /// The scenario.
        at: Loc,
        /// Agents requested.
        requested: usize,
        /// Agents that could be placed.
        placed: usize,
    },
}

impl ScenarioError {
    /// The wrapped map error, for [`ScenarioError::Map`].
    pub fn grid_error(&self) -> Option<&GridError> {
        match self {
            ScenarioError::Map { error, .. } => Some(error),
            _ => None,
        }
    }

    /// The 1-based line the error points at (in the scenario or, for map errors, the map
    /// file), if known.
    pub fn line(&self) -> Option<usize> {
        use ScenarioError::*;
        let at = match self {
            Io { .. } => return None,
            Map { error, .. } => return error.line(),
            Toml { at, .. }
            | UnknownKey { at, .. }
            | MissingKey { at, .. }
            | MapFileAndRows { at }
            | NoMapSource { at }
            | InvalidParameter { at, .. }
            | NoAgents { at }
            | BadCoordinates { at, .. }
            | StartOutsideMap { at, .. }
            | GoalOutsideMap { at, .. }
            | StartOnObstacle { at, .. }
            | GoalOnObstacle { at, .. }
            | DuplicateStart { at, .. }
            | DuplicateGoal { at, .. }
            | NonPositiveSpeed { at, .. }
            | SpeedTooHigh { at, .. }
            | BadPriority { at, .. }
            | FaultAgentOutOfRange { at, .. }
            | BadFault { at, .. }
            | TooManyAgents { at, .. }
            | UnreachableGoal { at, .. }
            | NotEnoughFreeCells { at, .. } => at,
        };
        (at.line > 0).then_some(at.line)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_file_and_line() {
        let e = ScenarioError::NonPositiveSpeed {
            at: Loc::new("s.toml", 12),
            agent: 2,
            speed: -1.0,
        };
        assert_eq!(
            e.to_string(),
            "s.toml:12: agent 2 speed must be a positive number of cells/s, got -1"
        );
        assert_eq!(e.line(), Some(12));
        let e = ScenarioError::NoAgents {
            at: Loc::new("s.toml", 0),
        };
        assert_eq!(e.to_string(), "s.toml: the scenario has no [[agents]]");
        assert_eq!(e.line(), None);
        let e = ScenarioError::Map {
            referenced_from: Some(Loc::new("s.toml", 3)),
            error: Box::new(GridError::TruncatedHeader {
                source_name: "m.map".into(),
                line: 2,
            }),
        };
        assert!(e.to_string().starts_with("m.map:2: "), "{e}");
        assert!(
            e.to_string().ends_with(" (map referenced from s.toml:3)"),
            "{e}"
        );
        assert_eq!(e.line(), Some(2));
    }
}
