//! `hnav map check`: load a map (and optionally a `.scen`), validate every entry and compare
//! every optimal length with the octile oracle. The binary only prints [`MapCheck::render`].

use std::fmt::Write as _;
use std::path::Path;

use super::coord::Cell;
use super::error::GridError;
use super::neighbours::CornerCutting;
use super::scen::{read_scen_file, validate_scen};
use super::shortest::octile_shortest_path_len;
use super::{read_map_file, Grid};

/// Largest accepted difference between a `.scen` optimal length and the oracle. The files
/// print 8 decimals, so a correct entry is off by at most 5e-9.
pub const LENGTH_TOLERANCE: f64 = 1e-6;

/// An entry whose optimal length disagrees with the oracle.
#[derive(Clone, PartialEq, Debug)]
pub struct LengthMismatch {
    /// 1-based line in the `.scen` file.
    pub line: usize,
    /// Start cell.
    pub start: Cell,
    /// Goal cell.
    pub goal: Cell,
    /// The file's optimal length.
    pub expected: f64,
    /// The oracle's length (`None`: unreachable).
    pub found: Option<f64>,
}

/// The outcome of [`check_map`].
#[derive(Clone, PartialEq, Debug)]
pub struct MapCheck {
    /// Map path as given.
    pub map_source: String,
    /// The loaded map.
    pub grid: Grid,
    /// Scenario path as given, if any.
    pub scen_source: Option<String>,
    /// Number of scenario entries read.
    pub entries: usize,
    /// Entries that do not fit the map (size, bounds, obstacles).
    pub invalid: Vec<GridError>,
    /// Valid entries whose optimal length is wrong.
    pub mismatches: Vec<LengthMismatch>,
    /// Non-fatal remarks (e.g. the entries name another map file).
    pub warnings: Vec<String>,
}

impl MapCheck {
    /// Whether every entry is valid and has the right optimal length.
    pub fn is_ok(&self) -> bool {
        self.invalid.is_empty() && self.mismatches.is_empty()
    }

    /// A human-readable report, at most `limit` lines per problem list.
    pub fn render(&self, limit: usize) -> String {
        let g = &self.grid;
        let mut out = String::new();
        let _ = writeln!(out, "map      {}", self.map_source);
        let _ = writeln!(
            out,
            "size     {} x {} ({} cells, {} blocked = {:.1} %)",
            g.width(),
            g.height(),
            g.len(),
            g.blocked_count(),
            100.0 * g.blocked_fraction()
        );
        if let Some(scen) = &self.scen_source {
            let good = self.entries - self.invalid.len() - self.mismatches.len();
            let _ = writeln!(out, "scen     {scen}");
            let _ = writeln!(
                out,
                "entries  {} ({good} ok, {} invalid, {} wrong length)",
                self.entries,
                self.invalid.len(),
                self.mismatches.len()
            );
        }
        for w in &self.warnings {
            let _ = writeln!(out, "warning: {w}");
        }
        for e in self.invalid.iter().take(limit) {
            let _ = writeln!(out, "error: {e}");
        }
        for m in self.mismatches.iter().take(limit) {
            let found = m
                .found
                .map_or_else(|| "unreachable".to_string(), |f| format!("{f:.8}"));
            let scen = self.scen_source.as_deref().unwrap_or("<scen>");
            let _ = writeln!(
                out,
                "error: {scen}:{}: optimal length {:.8} from {} to {} but the octile oracle finds {found}",
                m.line, m.expected, m.start, m.goal
            );
        }
        let hidden =
            self.invalid.len().saturating_sub(limit) + self.mismatches.len().saturating_sub(limit);
        if hidden > 0 {
            let _ = writeln!(out, "... and {hidden} more");
        }
        let _ = writeln!(out, "{}", if self.is_ok() { "ok" } else { "FAILED" });
        out
    }
}

/// Loads `map` and, if given, `scen`; validates every entry and checks every optimal length
/// against [`octile_shortest_path_len`] with corner cutting forbidden. Fails only if a file
/// cannot be read or parsed; per-entry problems are collected in the result.
pub fn check_map(map: &Path, scen: Option<&Path>) -> Result<MapCheck, GridError> {
    let grid = read_map_file(map)?;
    let mut check = MapCheck {
        map_source: map.display().to_string(),
        grid,
        scen_source: None,
        entries: 0,
        invalid: Vec::new(),
        mismatches: Vec::new(),
        warnings: Vec::new(),
    };
    let Some(scen_path) = scen else {
        return Ok(check);
    };
    let scen = read_scen_file(scen_path)?;
    check.scen_source = Some(scen.source_name.clone());
    check.entries = scen.entries.len();
    check.invalid = validate_scen(&check.grid, &scen);
    let map_name = map
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    if let Some(other) = scen.entries.iter().find(|e| e.map != map_name) {
        check.warnings.push(format!(
            "{}:{}: entry names map {:?}, checking against {:?}",
            scen.source_name, other.line, other.map, map_name
        ));
    }
    for e in &scen.entries {
        if e.validate(&check.grid, &scen.source_name).is_err() {
            continue;
        }
        let found =
            octile_shortest_path_len(&check.grid, e.start, e.goal, CornerCutting::Forbidden);
        if found.is_none_or(|f| (f - e.optimal_length).abs() > LENGTH_TOLERANCE) {
            check.mismatches.push(LengthMismatch {
                line: e.line,
                start: e.start,
                goal: e.goal,
                expected: e.optimal_length,
                found,
            });
        }
    }
    Ok(check)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_wrong_length_and_invalid_entry() {
        let dir = tempfile::tempdir().unwrap();
        let map = dir.path().join("m.map");
        let scen = dir.path().join("m.scen");
        std::fs::write(&map, "type octile\nheight 2\nwidth 3\nmap\n.@.\n...\n").unwrap();
        std::fs::write(
            &scen,
            "version 1\n0\tm.map\t3\t2\t0\t0\t2\t0\t4.00000000\n\
             0\tm.map\t3\t2\t0\t0\t2\t0\t3\n0\tm.map\t3\t2\t1\t0\t2\t0\t1\n",
        )
        .unwrap();
        let c = check_map(&map, Some(&scen)).unwrap();
        assert_eq!(c.entries, 3);
        assert_eq!(c.invalid.len(), 1);
        assert_eq!(c.mismatches.len(), 1);
        assert_eq!(c.mismatches[0].line, 3);
        assert!(!c.is_ok());
        let text = c.render(10);
        assert!(text.contains(":3: optimal length 3.00000000"), "{text}");
        assert!(text.ends_with("FAILED\n"));
        let c = check_map(&map, None).unwrap();
        assert!(c.is_ok());
    }
}
