//! The run report: `DIR/report.svg`, one picture of a run, drawn with `plotters`' SVG
//! backend at the end of every `hnav run` and again by `hnav report DIR [--agents 0,3]`.
//!
//! It shows the map (obstacles), each robot's committed cells (the consensus log's accepted
//! decisions) and its true trajectory (`recording/trajectories.bin`) in one colour per robot,
//! starts and goals, conflicts (refused or held decisions) and replans marked at the
//! agent's cell in that round, collisions (at the recorded sample where the sim's count
//! rose), and the final neural map of chosen agents as log-scale heatmaps beside the map.
//!
//! | module | concept |
//! |---|---|
//! | [`data`] | what the report shows, gathered from the run directory |
//! | [`layout`] | where each panel and cell lands on the canvas, in pixels |
//! | [`style`] | colours, marker sizes and the heatmap's log scale |
//! | [`draw`] | the drawing, element by element |

pub mod data;
pub mod draw;
pub mod layout;
pub mod style;

use std::path::{Path, PathBuf};

pub use data::RunData;
pub use layout::Layout;

/// The report's file in the run directory.
pub const FILE: &str = "report.svg";
/// The copy of the run's map (MovingAI `.map`) that `hnav run` keeps in the run directory:
/// the consensus log holds the map's size, not its obstacles.
pub const MAP_FILE: &str = "map.map";

/// What to draw and where.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReportOptions {
    /// The agents whose final neural map is drawn.
    pub agents: Vec<u32>,
    /// The output file [default: `DIR/report.svg`].
    pub out: Option<PathBuf>,
}

impl Default for ReportOptions {
    fn default() -> Self {
        Self {
            agents: vec![0],
            out: None,
        }
    }
}

/// Why a report could not be drawn; each names the file or the argument.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The consensus log.
    #[error("report: {0}")]
    Log(#[from] hnav_runtime::consensus_log::LogError),
    /// The log has no run header (the coordinator never started).
    #[error("report: {}: the consensus log has no run header", dir.display())]
    NoHeader {
        /// The log directory.
        dir: PathBuf,
    },
    /// The copy of the map.
    #[error("report: {0}")]
    Map(#[from] hnav_runtime::grid::GridError),
    /// The map copy does not fit the log.
    #[error("report: {}: a {map_w} x {map_h} map, the log's run is {log_w} x {log_h}", path.display())]
    MapMismatch {
        /// The map file.
        path: PathBuf,
        /// The map's width.
        map_w: u32,
        /// The map's height.
        map_h: u32,
        /// The log's width.
        log_w: u32,
        /// The log's height.
        log_h: u32,
    },
    /// A recording file.
    #[error("report: {0}")]
    Recording(#[from] crate::recording::RecordingError),
    /// `summary.json`.
    #[error("report: {}: {problem}", path.display())]
    Summary {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// An agent asked for that the run does not have.
    #[error("report: --agents {agent}: the run has {agents} agents (0-{})", agents.saturating_sub(1))]
    NoSuchAgent {
        /// The agent asked for.
        agent: u32,
        /// The run's agents.
        agents: usize,
    },
    /// Writing the SVG.
    #[error("report: {}: {problem}", path.display())]
    Draw {
        /// The output file.
        path: PathBuf,
        /// What the drawing backend said.
        problem: String,
    },
}

/// What [`write_report`] produced.
#[derive(Clone, Debug, PartialEq)]
pub struct Written {
    /// The SVG file.
    pub path: PathBuf,
    /// What is missing from the picture and why (no recording, an agent without a map).
    pub notes: Vec<String>,
}

/// Gathers the run in `dir` and draws its report (by default into `DIR/report.svg`).
pub fn write_report(dir: &Path, opts: &ReportOptions) -> Result<Written, ReportError> {
    let data = RunData::load(dir, &opts.agents)?;
    let path = opts.out.clone().unwrap_or_else(|| dir.join(FILE));
    draw::draw(&data, &path)?;
    Ok(Written {
        path,
        notes: data.notes,
    })
}
