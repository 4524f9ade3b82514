//! The dissertation's four 20x20 tasks of Table 3-8 and the figures it printed for them.
//!
//! The layouts are not in the text (only the figures, which are unavailable), so the maps in
//! `maps/dissertation/` are reconstructions: each follows its one-line description and was
//! sized so that our A* and HNAV step counts equal the table's where that was reachable
//! (`docs/experiments/hnav-vs-astar.md` says where and how we guessed). The four queries are
//! the entries of `maps/dissertation/tables-3-8.scen`, bucket = task number, so that the
//! tasks and the MovingAI files go through the same reader and validation.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use hnav_runtime::grid::{read_map_file, read_scen_file, Grid, ScenEntry};

/// A row of Table 3-8: the dissertation's time (ms, Python on a Xeon X5660) and steps.
#[derive(Clone, Copy, PartialEq, Debug, serde::Serialize)]
pub struct PaperRow {
    /// The task's words in the table.
    pub task: &'static str,
    /// A*'s time, ms.
    pub astar_ms: f64,
    /// A*'s steps.
    pub astar_steps: usize,
    /// HNAV's time, ms.
    pub hnav_ms: f64,
    /// HNAV's steps.
    pub hnav_steps: usize,
}

/// Table 3-8 as printed (notes `000_ch3.md` §4.4).
pub const TABLE_3_8: [PaperRow; 4] = [
    PaperRow {
        task: "go around a simple obstacle",
        astar_ms: 26.37,
        astar_steps: 33,
        hnav_ms: 7.22,
        hnav_steps: 33,
    },
    PaperRow {
        task: "find the exit from a room",
        astar_ms: 28.57,
        astar_steps: 29,
        hnav_ms: 6.95,
        hnav_steps: 29,
    },
    PaperRow {
        task: "go around several obstacles",
        astar_ms: 36.27,
        astar_steps: 28,
        hnav_ms: 7.81,
        hnav_steps: 27,
    },
    PaperRow {
        task: "several obstacles, variant 2",
        astar_ms: 39.86,
        astar_steps: 30,
        hnav_ms: 8.23,
        hnav_steps: 31,
    },
];

/// Table 3-9 and §3.5's conclusions, the claims the second table checks.
pub const TABLE_3_9: [(&str, &str); 3] = [
    (
        "tanh -> linear activation",
        "map formation up to 2.5x faster; one activation cycle 1.5-2.5x shorter",
    ),
    (
        "full -> partial activation (stop at the start's neuron)",
        "1.3-3x fewer cycles and shorter activation, depending on the agent-target distance",
    ),
    (
        "weights: 9 stored coefficients",
        "moderate RAM (not measured here)",
    ),
];

/// One task: its number, the paper's row, its map and its query.
#[derive(Clone, Debug)]
pub struct Task {
    /// 1..4, as in the table.
    pub number: u32,
    /// The map's file name in `maps/dissertation/`.
    pub map_name: String,
    /// The paper's figures.
    pub paper: PaperRow,
    /// The map.
    pub grid: Grid,
    /// Start, goal and the octile optimal length.
    pub entry: ScenEntry,
}

/// The repository's `maps/` directory.
pub fn maps_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps")
}

/// Reads the four tasks from `maps/dissertation/`; a missing or malformed file, an entry
/// that does not fit its map or a task number outside 1..4 is an error naming the file.
pub fn load() -> Result<Vec<Task>> {
    let dir = maps_dir().join("dissertation");
    let scen_path = dir.join("tables-3-8.scen");
    let scen = read_scen_file(&scen_path).map_err(anyhow::Error::msg)?;
    let mut tasks = Vec::with_capacity(TABLE_3_8.len());
    for entry in scen.entries {
        let at = format!("{}:{}", scen_path.display(), entry.line);
        let paper = usize::try_from(entry.bucket)
            .ok()
            .and_then(|b| b.checked_sub(1))
            .and_then(|i| TABLE_3_8.get(i))
            .copied()
            .with_context(|| format!("{at}: bucket {} is not a task 1..4", entry.bucket))?;
        let grid = read_map_file(dir.join(&entry.map)).map_err(anyhow::Error::msg)?;
        entry
            .validate(&grid, &scen.source_name)
            .map_err(anyhow::Error::msg)?;
        tasks.push(Task {
            number: entry.bucket,
            map_name: entry.map.clone(),
            paper,
            grid,
            entry,
        });
    }
    let numbers: Vec<u32> = tasks.iter().map(|t| t.number).collect();
    if numbers != [1, 2, 3, 4] {
        anyhow::bail!(
            "{}: expected tasks 1, 2, 3, 4 in order, found {numbers:?}",
            scen_path.display()
        );
    }
    Ok(tasks)
}

#[cfg(test)]
mod tests {
    use super::super::measure::{Variant, ASTAR, HNAV_LINEAR_PARTIAL, VARIANTS};
    use super::*;

    fn steps(task: &Task, variant: Variant) -> (usize, f64) {
        let r = variant
            .query(&task.grid, task.entry.start, task.entry.goal)
            .unwrap();
        assert!(r.found, "task {} {}", task.number, variant.name());
        (r.steps, r.length)
    }

    /// Table 3-8's step counts on the reconstructed maps. Tasks 1, 2 and 4 reach them for
    /// both planners; task 3's HNAV count (27, one fewer than A*'s optimal 28) is not
    /// reached on our map, whose HNAV path is the optimal one: pinned at 28, and the doc
    /// (`docs/experiments/hnav-vs-astar.md`) says why.
    #[test]
    fn step_counts_are_table_3_8s() {
        let tasks = load().unwrap();
        let ours: Vec<(usize, usize)> = tasks
            .iter()
            .map(|t| {
                (
                    steps(t, VARIANTS[ASTAR]).0,
                    steps(t, VARIANTS[HNAV_LINEAR_PARTIAL]).0,
                )
            })
            .collect();
        assert_eq!(ours, [(33, 33), (29, 29), (28, 28), (30, 31)]);
        for (t, (a, h)) in tasks.iter().zip(&ours) {
            assert_eq!(*a, t.paper.astar_steps, "task {}", t.number);
            if t.number != 3 {
                assert_eq!(*h, t.paper.hnav_steps, "task {}", t.number);
            }
        }
        assert_eq!(tasks[2].paper.hnav_steps, 27);
    }

    /// The `.scen` lengths are the oracle: A* (octile, no corner cutting) meets them, and
    /// every HNAV variant takes the same number of steps on a task (Table 3-8 ran only one).
    #[test]
    fn scen_lengths_are_optimal_and_variants_agree_on_steps() {
        for t in load().unwrap() {
            let (_, a) = steps(&t, VARIANTS[ASTAR]);
            assert!(
                (a - t.entry.optimal_length).abs() < 1e-6,
                "task {}",
                t.number
            );
            let first = steps(&t, VARIANTS[HNAV_LINEAR_PARTIAL]);
            for v in &VARIANTS[HNAV_LINEAR_PARTIAL..] {
                let s = steps(&t, *v);
                assert_eq!(s.0, first.0, "task {} {}", t.number, v.name());
                assert!(s.1 >= a - 1e-9, "task {} {} beats A*", t.number, v.name());
            }
        }
    }

    #[test]
    fn paper_ratios_are_the_notes() {
        // Notes §4.4: speed-ups 3.65, 4.11, 4.64, 4.84; summed 131.07 / 30.21 = 4.34.
        let up: Vec<f64> = TABLE_3_8.iter().map(|r| r.astar_ms / r.hnav_ms).collect();
        for (u, want) in up.iter().zip([3.65, 4.11, 4.64, 4.84]) {
            assert!((u - want).abs() < 0.005, "{u} vs {want}");
        }
        let (a, h) = TABLE_3_8
            .iter()
            .fold((0.0, 0.0), |(a, h), r| (a + r.astar_ms, h + r.hnav_ms));
        assert!((a - 131.07f64).abs() < 1e-9 && (h - 30.21f64).abs() < 1e-9);
    }
}
