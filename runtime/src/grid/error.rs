//! The single error type of the grid module.
//!
//! Every variant produced while reading a file names the file (`source_name`, a path or
//! `"<inline>"`) and the 1-based line, so a user can jump straight to the problem. The
//! `Display` form is always `file:line: problem` (plus `:column` for a bad character), which
//! is the shape editors and CI annotators understand.
//!
//! The type is `Clone + PartialEq` (I/O errors are kept as their message) so tests and callers
//! can compare errors structurally.

use std::fmt;

/// Which header dimension a [`GridError`] is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Dimension {
    /// The `width N` header line (number of columns).
    Width,
    /// The `height N` header line (number of rows).
    Height,
}

impl fmt::Display for Dimension {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Dimension::Width => "width",
            Dimension::Height => "height",
        })
    }
}

/// Which end of a MovingAI scenario entry (or an agent) an error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Endpoint {
    /// The start cell.
    Start,
    /// The goal cell.
    Goal,
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Endpoint::Start => "start",
            Endpoint::Goal => "goal",
        })
    }
}

/// `"s"` unless `n == 1`, for messages like "row has 1 character".
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// Everything that can go wrong while building, reading or validating grids and MovingAI files.
///
/// The field is called `source_name` rather than `source` because `thiserror` treats a field
/// named `source` as the underlying error.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GridError {
    /// The file could not be read or written.
    #[error("{source_name}: {message}")]
    Io {
        /// The path as given.
        source_name: String,
        /// The operating-system error message.
        message: String,
    },
    /// The input ended before the `map` line that closes a `.map` header.
    #[error("{source_name}:{line}: header ended before the `map` line (truncated header)")]
    TruncatedHeader {
        /// File name or `"<inline>"`.
        source_name: String,
        /// The line just past the end of the input.
        line: usize,
    },
    /// A header line that is neither `type`, `height`, `width` nor `map`.
    #[error(
        "{source_name}:{line}: unrecognised header line {text:?} \
         (expected `type octile`, `height N`, `width N` or `map`)"
    )]
    BadHeaderLine {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// The offending line.
        text: String,
    },
    /// `type` is something other than `octile`.
    #[error("{source_name}:{line}: unsupported map type {found:?}, expected `octile`")]
    UnsupportedType {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// The type that was given.
        found: String,
    },
    /// A `height`/`width` value that is not a positive integer, or is given twice.
    #[error("{source_name}:{line}: bad {which} {value:?}: {problem}")]
    BadDimension {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// Height or width.
        which: Dimension,
        /// The text after the keyword.
        value: String,
        /// What is wrong with it.
        problem: String,
    },
    /// The `map` line was reached without a `height` or `width` line before it.
    #[error("{source_name}:{line}: `map` line reached but no `{which}` line was given")]
    MissingDimension {
        /// File name or `"<inline>"`.
        source_name: String,
        /// Line of the `map` keyword.
        line: usize,
        /// The missing dimension.
        which: Dimension,
    },
    /// Width times height exceeds [`crate::grid::Grid::MAX_CELLS`] or is zero.
    #[error("{source_name}:{line}: a {width}x{height} grid is not supported ({problem})")]
    BadShape {
        /// File name, `"<inline>"`, or `"<grid>"` for programmatic construction.
        source_name: String,
        /// 1-based line number (0 for programmatic construction).
        line: usize,
        /// Requested width.
        width: u64,
        /// Requested height.
        height: u64,
        /// What is wrong with it.
        problem: String,
    },
    /// A map row whose length differs from the declared width.
    #[error("{source_name}:{line}: row has {found} character{}, expected {expected}", plural(*.found))]
    RowWidth {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number of the row.
        line: usize,
        /// Characters found on the row (after stripping a trailing CR).
        found: usize,
        /// The declared width.
        expected: u32,
    },
    /// The input ended before all declared rows were read.
    #[error("{source_name}:{line}: map ends after {found} rows, expected {expected}")]
    TooFewRows {
        /// File name or `"<inline>"`.
        source_name: String,
        /// The line just past the end of the input.
        line: usize,
        /// Rows present.
        found: u32,
        /// Rows declared.
        expected: u32,
    },
    /// A non-empty line after the last declared row.
    #[error("{source_name}:{line}: extra row after the {expected} rows the header declares")]
    TooManyRows {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number of the first extra row.
        line: usize,
        /// Rows declared.
        expected: u32,
    },
    /// A character that is not one of `. G S W T @ O`.
    #[error("{source_name}:{line}:{column}: unknown map character {ch:?} (known: . G S W T @ O)")]
    UnknownChar {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// 1-based column (in characters).
        column: usize,
        /// The character.
        ch: char,
    },
    /// A `.scen` file whose first line is not `version 1` / `version 1.0`.
    #[error("{source_name}:{line}: expected `version 1` or `version 1.0`, found {found:?}")]
    BadVersion {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number (always 1).
        line: usize,
        /// The first line (empty if the file is empty).
        found: String,
    },
    /// A `.scen` line without exactly 9 tab-separated fields.
    #[error("{source_name}:{line}: expected 9 tab-separated fields, found {found}")]
    FieldCount {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// Fields found.
        found: usize,
    },
    /// A `.scen` field that does not parse as the expected number.
    #[error("{source_name}:{line}: field {field} ({name}) is not {expected}: {value:?}")]
    BadField {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// 1-based field number.
        field: usize,
        /// Field name (`start_x`, `optimal_length`, ...).
        name: &'static str,
        /// What was expected (`a non-negative integer`, ...).
        expected: &'static str,
        /// The text found.
        value: String,
    },
    /// A start or goal outside the map.
    #[error("{source_name}:{line}: {endpoint} [{x}, {y}] is outside the {width}x{height} map")]
    OutsideMap {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// Start or goal.
        endpoint: Endpoint,
        /// Column.
        x: u64,
        /// Row.
        y: u64,
        /// Map width.
        width: u32,
        /// Map height.
        height: u32,
    },
    /// A start or goal on a blocked cell.
    #[error("{source_name}:{line}: {endpoint} [{x}, {y}] is on an obstacle ({ch:?})")]
    OnObstacle {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// Start or goal.
        endpoint: Endpoint,
        /// Column.
        x: u32,
        /// Row.
        y: u32,
        /// The map character at that cell.
        ch: char,
    },
    /// A `.scen` entry written for a map of another size.
    #[error(
        "{source_name}:{line}: entry is for a {scen_width}x{scen_height} map \
         but the map is {width}x{height}"
    )]
    SizeMismatch {
        /// File name or `"<inline>"`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// Width in the entry.
        scen_width: u32,
        /// Height in the entry.
        scen_height: u32,
        /// Actual map width.
        width: u32,
        /// Actual map height.
        height: u32,
    },
    /// A terrain layer that does not fit the grid (wrong length, NaN, negative cost).
    #[error("terrain: {problem}")]
    BadTerrain {
        /// What is wrong.
        problem: String,
    },
}

impl GridError {
    /// The file (or `"<inline>"`/`"<grid>"`) the error is about, if it names one.
    pub fn source_name(&self) -> Option<&str> {
        use GridError::*;
        match self {
            Io { source_name, .. }
            | TruncatedHeader { source_name, .. }
            | BadHeaderLine { source_name, .. }
            | UnsupportedType { source_name, .. }
            | BadDimension { source_name, .. }
            | MissingDimension { source_name, .. }
            | BadShape { source_name, .. }
            | RowWidth { source_name, .. }
            | TooFewRows { source_name, .. }
            | TooManyRows { source_name, .. }
            | UnknownChar { source_name, .. }
            | BadVersion { source_name, .. }
            | FieldCount { source_name, .. }
            | BadField { source_name, .. }
            | OutsideMap { source_name, .. }
            | OnObstacle { source_name, .. }
            | SizeMismatch { source_name, .. } => Some(source_name),
            BadTerrain { .. } => None,
        }
    }

    /// The 1-based line the error points at, if it has one.
    pub fn line(&self) -> Option<usize> {
        use GridError::*;
        match self {
            Io { .. } | BadTerrain { .. } => None,
            BadShape { line, .. } if *line == 0 => None,
            TruncatedHeader { line, .. }
            | BadHeaderLine { line, .. }
            | UnsupportedType { line, .. }
            | BadDimension { line, .. }
            | MissingDimension { line, .. }
            | BadShape { line, .. }
            | RowWidth { line, .. }
            | TooFewRows { line, .. }
            | TooManyRows { line, .. }
            | UnknownChar { line, .. }
            | BadVersion { line, .. }
            | FieldCount { line, .. }
            | BadField { line, .. }
            | OutsideMap { line, .. }
            | OnObstacle { line, .. }
            | SizeMismatch { line, .. } => Some(*line),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_is_file_line_problem() {
        let e = GridError::RowWidth {
            source_name: "maps/x.map".into(),
            line: 7,
            found: 31,
            expected: 32,
        };
        assert_eq!(
            e.to_string(),
            "maps/x.map:7: row has 31 characters, expected 32"
        );
        assert_eq!(e.line(), Some(7));
        assert_eq!(e.source_name(), Some("maps/x.map"));
    }

    #[test]
    fn programmatic_shape_error_has_no_line() {
        let e = GridError::BadShape {
            source_name: "<grid>".into(),
            line: 0,
            width: 0,
            height: 3,
            problem: "empty".into(),
        };
        assert_eq!(e.line(), None);
    }
}
