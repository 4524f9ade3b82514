//! MovingAI `.scen` reader, writer and validation against a map.
//!
//! Format: a first line `version 1` (or `version 1.0`), then one problem per line with 9
//! **tab-separated** fields:
//!
//! ```text
//! bucket  map  map_width  map_height  start_x  start_y  goal_x  goal_y  optimal_length
//! 3       maze-32-32-2.map  32  32  17  21  15  16  13.82842712
//! ```
//!
//! `optimal_length` is the octile single-agent distance **without corner cutting** (see
//! [`crate::grid::octile_shortest_path_len`]). Its original text is kept, so writing a file
//! that was read reproduces it byte for byte; values set in code are written with 8 decimals
//! like the benchmark files. Blank lines are skipped. A MAPF instance with N agents is the
//! first N entries (Stern et al. 2019).

use std::fmt::Write as _;
use std::path::Path;

use super::coord::Cell;
use super::error::{Endpoint, GridError};
use super::movingai::numbered_lines;
use super::Grid;

/// One problem of a `.scen` file.
#[derive(Clone, PartialEq, Debug)]
pub struct ScenEntry {
    /// Difficulty bucket (MovingAI groups problems by length in buckets of 4).
    pub bucket: u32,
    /// The map file name as written in the scenario (usually without a directory).
    pub map: String,
    /// Map width the entry was made for.
    pub map_width: u32,
    /// Map height the entry was made for.
    pub map_height: u32,
    /// Start cell.
    pub start: Cell,
    /// Goal cell.
    pub goal: Cell,
    /// Octile shortest-path length without corner cutting.
    pub optimal_length: f64,
    /// 1-based line in the file it was read from, 0 for entries made in code.
    pub line: usize,
    /// The optimal length exactly as written, used by the writer while it still parses to
    /// `optimal_length`.
    optimal_text: Option<String>,
}

impl ScenEntry {
    /// An entry made in code (line 0; the length is written with 8 decimals).
    pub fn new(
        map: &str,
        map_width: u32,
        map_height: u32,
        start: Cell,
        goal: Cell,
        optimal_length: f64,
    ) -> Self {
        ScenEntry {
            bucket: 0,
            map: map.into(),
            map_width,
            map_height,
            start,
            goal,
            optimal_length,
            line: 0,
            optimal_text: None,
        }
    }

    /// Checks the entry against a map: sizes agree, start and goal inside and free. Returns
    /// the first problem, naming `source_name` and the entry's line.
    pub fn validate(&self, grid: &Grid, source_name: &str) -> Result<(), GridError> {
        let line = self.line;
        if (self.map_width, self.map_height) != (grid.width(), grid.height()) {
            return Err(GridError::SizeMismatch {
                source_name: source_name.into(),
                line,
                scen_width: self.map_width,
                scen_height: self.map_height,
                width: grid.width(),
                height: grid.height(),
            });
        }
        for (endpoint, cell) in [(Endpoint::Start, self.start), (Endpoint::Goal, self.goal)] {
            if !grid.contains(cell) {
                return Err(GridError::OutsideMap {
                    source_name: source_name.into(),
                    line,
                    endpoint,
                    x: cell.x.into(),
                    y: cell.y.into(),
                    width: grid.width(),
                    height: grid.height(),
                });
            }
        }
        for (endpoint, cell) in [(Endpoint::Start, self.start), (Endpoint::Goal, self.goal)] {
            if let Some(tile) = grid.tile(cell).filter(|t| !t.is_passable()) {
                return Err(GridError::OnObstacle {
                    source_name: source_name.into(),
                    line,
                    endpoint,
                    x: cell.x,
                    y: cell.y,
                    ch: tile.to_char(),
                });
            }
        }
        Ok(())
    }

    /// The optimal-length field as the writer will emit it.
    pub fn optimal_length_text(&self) -> String {
        match &self.optimal_text {
            Some(t) if t.parse::<f64>().ok() == Some(self.optimal_length) => t.clone(),
            _ => format!("{:.8}", self.optimal_length),
        }
    }
}

/// A whole `.scen` file.
#[derive(Clone, PartialEq, Debug)]
pub struct ScenFile {
    /// Where it was read from (a path or `"<inline>"`), used in validation errors.
    pub source_name: String,
    /// The version as written after `version ` (`"1"` or `"1.0"`).
    pub version: String,
    /// The problems, in file order.
    pub entries: Vec<ScenEntry>,
}

/// Field names, 1-based field `i` is `FIELDS[i - 1]`.
const FIELDS: [&str; 9] = [
    "bucket",
    "map",
    "map_width",
    "map_height",
    "start_x",
    "start_y",
    "goal_x",
    "goal_y",
    "optimal_length",
];

/// Reads a `.scen` from text; `source_name` is used in errors and kept in the result.
pub fn read_scen(text: &str, source_name: &str) -> Result<ScenFile, GridError> {
    let mut lines = numbered_lines(text);
    let first = lines.next().map(|(_, l)| l).unwrap_or("");
    let version = match first.trim().split_once(char::is_whitespace) {
        Some(("version", v)) if matches!(v.trim(), "1" | "1.0") => v.trim().to_string(),
        _ => {
            return Err(GridError::BadVersion {
                source_name: source_name.into(),
                line: 1,
                found: first.into(),
            })
        }
    };
    let mut entries = Vec::new();
    for (line, text) in lines {
        if text.trim().is_empty() {
            continue;
        }
        entries.push(parse_entry(text, source_name, line)?);
    }
    Ok(ScenFile {
        source_name: source_name.into(),
        version,
        entries,
    })
}

/// Reads a `.scen` file; errors and [`ScenFile::source_name`] carry the path as given.
pub fn read_scen_file(path: impl AsRef<Path>) -> Result<ScenFile, GridError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| GridError::Io {
        source_name: name.clone(),
        message: format!("cannot read scenario file: {e}"),
    })?;
    read_scen(&text, &name)
}

/// Writes a `.scen` file's text (LF line ends, final newline).
pub fn write_scen(scen: &ScenFile) -> String {
    let mut out = format!("version {}\n", scen.version);
    for e in &scen.entries {
        // Writing to a String cannot fail.
        let _ = writeln!(
            out,
            "{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}",
            e.bucket,
            e.map,
            e.map_width,
            e.map_height,
            e.start.x,
            e.start.y,
            e.goal.x,
            e.goal.y,
            e.optimal_length_text()
        );
    }
    out
}

/// Validates every entry against a map and returns all problems (empty if all are fine).
pub fn validate_scen(grid: &Grid, scen: &ScenFile) -> Vec<GridError> {
    scen.entries
        .iter()
        .filter_map(|e| e.validate(grid, &scen.source_name).err())
        .collect()
}

fn parse_entry(text: &str, source_name: &str, line: usize) -> Result<ScenEntry, GridError> {
    let fields: Vec<&str> = text.split('\t').collect();
    if fields.len() != FIELDS.len() {
        return Err(GridError::FieldCount {
            source_name: source_name.into(),
            line,
            found: fields.len(),
        });
    }
    let bad = |i: usize, expected: &'static str| GridError::BadField {
        source_name: source_name.into(),
        line,
        field: i + 1,
        name: FIELDS[i],
        expected,
        value: fields[i].into(),
    };
    let int = |i: usize| {
        fields[i]
            .trim()
            .parse::<u32>()
            .map_err(|_| bad(i, "a non-negative integer"))
    };
    let map = fields[1].trim();
    if map.is_empty() {
        return Err(bad(1, "a map name"));
    }
    let opt_text = fields[8].trim();
    let optimal_length = opt_text
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v >= 0.0)
        .ok_or_else(|| bad(8, "a non-negative number"))?;
    Ok(ScenEntry {
        bucket: int(0)?,
        map: map.into(),
        map_width: int(2)?,
        map_height: int(3)?,
        start: Cell::new(int(4)?, int(5)?),
        goal: Cell::new(int(6)?, int(7)?),
        optimal_length,
        line,
        optimal_text: Some(opt_text.into()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::read_map;

    const SCEN: &str = "version 1\n3\tmaze-32-32-2.map\t32\t32\t17\t21\t15\t16\t13.82842712\n\
                        0\tloop.map\t4\t4\t0\t0\t0\t2\t0\n";

    #[test]
    fn reads_and_round_trips() {
        let s = read_scen(SCEN, "a.scen").unwrap();
        assert_eq!(s.version, "1");
        assert_eq!(s.entries.len(), 2);
        let e = &s.entries[0];
        assert_eq!(
            (e.bucket, e.map.as_str(), e.map_width, e.map_height),
            (3, "maze-32-32-2.map", 32, 32)
        );
        assert_eq!(
            (e.start, e.goal, e.line),
            (Cell::new(17, 21), Cell::new(15, 16), 2)
        );
        assert_eq!(e.optimal_length, 13.82842712);
        assert_eq!(write_scen(&s), SCEN);
        let s = read_scen("version 1.0\r\n", "b.scen").unwrap();
        assert_eq!(write_scen(&s), "version 1.0\n");
    }

    #[test]
    fn changed_length_is_reformatted() {
        let mut s = read_scen(SCEN, "a.scen").unwrap();
        s.entries[1].optimal_length = 2.0;
        assert!(write_scen(&s).ends_with("\t2.00000000\n"));
        let e = ScenEntry::new("m.map", 4, 4, Cell::new(0, 0), Cell::new(1, 1), 2f64.sqrt());
        assert_eq!(e.optimal_length_text(), "1.41421356");
    }

    #[test]
    fn errors_have_lines() {
        let e = read_scen("version 2\n", "a.scen").unwrap_err();
        assert!(matches!(e, GridError::BadVersion { line: 1, .. }), "{e}");
        assert!(matches!(
            read_scen("", "a.scen"),
            Err(GridError::BadVersion { .. })
        ));
        let e = read_scen("version 1\n\n0\tm.map\t4\t4\t0\t0\t0\t2\n", "a.scen").unwrap_err();
        assert_eq!(
            e,
            GridError::FieldCount {
                source_name: "a.scen".into(),
                line: 3,
                found: 8
            }
        );
        let e = read_scen("version 1\n0\tm.map\t4\t4\t-1\t0\t0\t2\t0\n", "a.scen").unwrap_err();
        assert!(
            matches!(
                e,
                GridError::BadField {
                    line: 2,
                    field: 5,
                    name: "start_x",
                    ..
                }
            ),
            "{e}"
        );
        let e = read_scen("version 1\n0\tm.map\t4\t4\t1\t0\t0\t2\tabc\n", "a.scen").unwrap_err();
        assert!(matches!(e, GridError::BadField { field: 9, .. }), "{e}");
        let e = read_scen("version 1\n0\tm.map\t4\t4\t1\t0\t0\t2\tNaN\n", "a.scen").unwrap_err();
        assert!(matches!(e, GridError::BadField { field: 9, .. }), "{e}");
    }

    #[test]
    fn validation_against_map() {
        let g = read_map("type octile\nheight 2\nwidth 3\nmap\n.@.\n...\n", "m.map").unwrap();
        let text = "version 1\n\
                    0\tm.map\t3\t2\t0\t0\t2\t1\t2.41421356\n\
                    0\tm.map\t3\t3\t0\t0\t2\t1\t1\n\
                    0\tm.map\t3\t2\t0\t0\t3\t1\t1\n\
                    0\tm.map\t3\t2\t1\t0\t2\t1\t1\n\
                    0\tm.map\t3\t2\t0\t0\t1\t0\t1\n";
        let s = read_scen(text, "m.scen").unwrap();
        let errs = validate_scen(&g, &s);
        assert_eq!(errs.len(), 4);
        assert!(matches!(
            errs[0],
            GridError::SizeMismatch {
                line: 3,
                scen_height: 3,
                ..
            }
        ));
        assert!(matches!(
            errs[1],
            GridError::OutsideMap {
                line: 4,
                endpoint: Endpoint::Goal,
                x: 3,
                ..
            }
        ));
        assert!(matches!(
            errs[2],
            GridError::OnObstacle {
                line: 5,
                endpoint: Endpoint::Start,
                ch: '@',
                ..
            }
        ));
        assert!(matches!(
            errs[3],
            GridError::OnObstacle {
                line: 6,
                endpoint: Endpoint::Goal,
                ..
            }
        ));
        assert_eq!(
            errs[2].to_string(),
            "m.scen:5: start [1, 0] is on an obstacle ('@')"
        );
    }
}
