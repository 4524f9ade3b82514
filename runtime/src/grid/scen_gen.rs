//! Seeded random MovingAI `.scen` files (`hnav map scen`), for maps that come without one
//! (`maps/warehouse-10-20-10-2-1.map`).
//!
//! Made the way MovingAI's MAPF "random" scenarios are: every start and every goal a free
//! cell of the map's largest connected component (corner cutting forbidden, the rule of the
//! optimal lengths), all starts distinct, all goals distinct, no agent's goal its own start,
//! entries in random order; the optimal length is the octile A* length without corner cutting
//! ([`octile_shortest_path_len`]) and the bucket `floor(length / 4)`. So any first N entries
//! are an N-agent MAPF instance. The random numbers are [`SplitMix64`]'s, so a seed gives the
//! same file on every platform.

use super::neighbours::CornerCutting;
use super::scen::{ScenEntry, ScenFile};
use super::shortest::{components, octile_shortest_path_len};
use super::{Cell, Grid};
use crate::hash::SplitMix64;

/// Why a scenario could not be generated.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ScenGenError {
    /// More entries asked for than the largest component has cells for distinct starts and
    /// goals.
    #[error(
        "{map}: cannot place {requested} agents with distinct starts and goals: the largest \
         connected component has {cells} free cells (at most {max} agents)"
    )]
    TooManyAgents {
        /// The map, as named in the entries.
        map: String,
        /// Entries asked for.
        requested: usize,
        /// Free cells in the largest component.
        cells: usize,
        /// The most entries it can hold.
        max: usize,
    },
}

/// MovingAI's difficulty bucket of an optimal length: buckets of 4 cells.
pub fn bucket_of(length: f64) -> u32 {
    (length / 4.0).floor() as u32
}

/// The free cells of `grid`'s largest connected component without corner cutting, in
/// row-major order (the first such component on a tie).
pub fn largest_component(grid: &Grid) -> Vec<Cell> {
    let label = components(grid, CornerCutting::Forbidden);
    let mut sizes: Vec<usize> = Vec::new();
    for &l in label.iter().filter(|&&l| l != u32::MAX) {
        let l = l as usize;
        if sizes.len() <= l {
            sizes.resize(l + 1, 0);
        }
        sizes[l] += 1;
    }
    let Some(best) = (0..sizes.len()).max_by_key(|&l| (sizes[l], std::cmp::Reverse(l))) else {
        return Vec::new();
    };
    grid.passable_cells()
        .filter(|&c| label[grid.index(c)] == best as u32)
        .collect()
}

/// `entries` random problems on `grid` (see the [module docs](self)), seeded by `seed`;
/// `map_name` is the map field of every entry (MovingAI writes the file name only).
pub fn generate_scen(
    grid: &Grid,
    map_name: &str,
    entries: usize,
    seed: u64,
) -> Result<ScenFile, ScenGenError> {
    let cells = largest_component(grid);
    // Each agent needs a goal other than its own start among the goals still free: the last
    // agent of a component of `entries` cells may find only its own start left.
    let max = cells.len().saturating_sub(1);
    if entries > max {
        return Err(ScenGenError::TooManyAgents {
            map: map_name.into(),
            requested: entries,
            cells: cells.len(),
            max,
        });
    }
    let mut rng = SplitMix64::new(seed);
    let mut starts = cells.clone();
    let mut goals = cells;
    let mut out = Vec::with_capacity(entries);
    for _ in 0..entries {
        let start = starts.swap_remove(rng.below(starts.len() as u64) as usize);
        // `goals` holds at least two cells here (entries <= cells - 1), so a goal other than
        // the start exists; redrawing keeps the choice uniform among them.
        let goal = loop {
            let k = rng.below(goals.len() as u64) as usize;
            if goals[k] != start {
                break goals.swap_remove(k);
            }
        };
        // Both ends lie in one component, so the oracle always finds a path.
        let length = octile_shortest_path_len(grid, start, goal, CornerCutting::Forbidden)
            .unwrap_or(f64::INFINITY);
        let mut entry = ScenEntry::new(map_name, grid.width(), grid.height(), start, goal, length);
        entry.bucket = bucket_of(length);
        out.push(entry);
    }
    Ok(ScenFile {
        source_name: "<generated>".into(),
        version: "1".into(),
        entries: out,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::check::LENGTH_TOLERANCE;
    use crate::grid::{read_scen, validate_scen, write_scen};
    use std::collections::HashSet;

    fn two_rooms() -> Grid {
        // A 3-cell room on the left, walled off from a 12-cell room on the right.
        Grid::from_rows(&[".@....", ".@....", ".@...."]).unwrap()
    }

    #[test]
    fn entries_are_distinct_in_the_largest_component_with_oracle_lengths() {
        let g = two_rooms();
        let scen = generate_scen(&g, "rooms.map", 11, 7).unwrap();
        assert_eq!(scen.entries.len(), 11);
        assert!(validate_scen(&g, &scen).is_empty());
        let starts: HashSet<Cell> = scen.entries.iter().map(|e| e.start).collect();
        let goals: HashSet<Cell> = scen.entries.iter().map(|e| e.goal).collect();
        assert_eq!((starts.len(), goals.len()), (11, 11));
        for e in &scen.entries {
            assert!(
                e.start.x >= 2 && e.goal.x >= 2,
                "{e:?} is outside the big room"
            );
            assert_ne!(e.start, e.goal);
            let oracle =
                octile_shortest_path_len(&g, e.start, e.goal, CornerCutting::Forbidden).unwrap();
            assert!((oracle - e.optimal_length).abs() < LENGTH_TOLERANCE);
            assert_eq!(e.bucket, bucket_of(e.optimal_length));
        }
    }

    #[test]
    fn a_seed_gives_one_file_and_another_seed_another() {
        let g = Grid::new(16, 16).unwrap();
        let a = write_scen(&generate_scen(&g, "e.map", 40, 1).unwrap());
        assert_eq!(a, write_scen(&generate_scen(&g, "e.map", 40, 1).unwrap()));
        assert_ne!(a, write_scen(&generate_scen(&g, "e.map", 40, 2).unwrap()));
        // What is written reads back as the same problems (MovingAI's version 1 format).
        let back = read_scen(&a, "e.scen").unwrap();
        assert_eq!(back.entries.len(), 40);
        assert!(a.starts_with("version 1\n"));
    }

    #[test]
    fn too_many_agents_is_an_error_naming_the_room() {
        let g = two_rooms();
        assert!(generate_scen(&g, "rooms.map", 11, 0).is_ok());
        let err = generate_scen(&g, "rooms.map", 12, 0).unwrap_err();
        assert_eq!(
            err.to_string(),
            "rooms.map: cannot place 12 agents with distinct starts and goals: the largest \
             connected component has 12 free cells (at most 11 agents)"
        );
    }

    #[test]
    fn buckets_are_floors_of_quarters() {
        assert_eq!(bucket_of(0.0), 0);
        assert_eq!(bucket_of(3.99), 0);
        assert_eq!(bucket_of(4.0), 1);
        assert_eq!(bucket_of(13.65685425), 3);
    }
}
