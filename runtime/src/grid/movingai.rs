//! MovingAI `.map` reader and writer.
//!
//! Format (Sturtevant 2012, <https://movingai.com/benchmarks/formats.html>):
//!
//! ```text
//! type octile
//! height 4
//! width 4
//! map
//! ....
//! .@@.
//! .@@.
//! ....
//! ```
//!
//! * The header lines `type`, `height`, `width` may come in any order (LaCAM's loader accepts
//!   that too); only `type octile` is accepted; blank header lines are skipped; `map` ends it.
//! * Then exactly `height` rows of exactly `width` characters from `. G S W T @ O`.
//! * A trailing CR on any line is dropped, so CRLF files read like LF files. Blank lines after
//!   the last row are ignored; anything else there is an error.
//! * The writer always produces the canonical LF form above, so for every LF file that reads
//!   successfully `write_map(&read_map(text)?) == text` (given a final newline).
//!
//! Errors name the file and the 1-based line ([`GridError`]); nothing here panics on any input.

use std::path::Path;

use super::error::{Dimension, GridError};
use super::tile::Tile;
use super::Grid;

/// Reads a `.map` from text. `source_name` (a path, or `"<inline>"`) is used in errors only.
pub fn read_map(text: &str, source_name: &str) -> Result<Grid, GridError> {
    let mut lines = numbered_lines(text);
    let mut last_line = 0;
    let mut height: Option<u32> = None;
    let mut width: Option<u32> = None;
    let map_line = loop {
        let Some((line, raw)) = lines.next() else {
            return Err(GridError::TruncatedHeader {
                source_name: source_name.into(),
                line: last_line + 1,
            });
        };
        last_line = line;
        let trimmed = raw.trim();
        let (key, value) = match trimmed.split_once(char::is_whitespace) {
            Some((k, v)) => (k, v.trim()),
            None => (trimmed, ""),
        };
        match key {
            "" => continue,
            "map" if value.is_empty() => break line,
            "type" if value == "octile" => {}
            "type" => {
                return Err(GridError::UnsupportedType {
                    source_name: source_name.into(),
                    line,
                    found: value.into(),
                })
            }
            "height" => {
                height = Some(parse_dimension(
                    value,
                    Dimension::Height,
                    height,
                    source_name,
                    line,
                )?)
            }
            "width" => {
                width = Some(parse_dimension(
                    value,
                    Dimension::Width,
                    width,
                    source_name,
                    line,
                )?)
            }
            _ => {
                return Err(GridError::BadHeaderLine {
                    source_name: source_name.into(),
                    line,
                    text: raw.into(),
                })
            }
        }
    };
    let missing = |which| GridError::MissingDimension {
        source_name: source_name.into(),
        line: map_line,
        which,
    };
    let height = height.ok_or_else(|| missing(Dimension::Height))?;
    let width = width.ok_or_else(|| missing(Dimension::Width))?;
    let cells = Grid::checked_len(width, height, source_name, map_line)?;

    // Never trust the header for the allocation size: the text bounds the real cell count.
    let mut tiles = Vec::with_capacity(cells.min(text.len()));
    let mut rows_read = 0u32;
    while rows_read < height {
        let Some((line, row)) = lines.next() else {
            return Err(GridError::TooFewRows {
                source_name: source_name.into(),
                line: last_line + 1,
                found: rows_read,
                expected: height,
            });
        };
        last_line = line;
        push_row(&mut tiles, row, width, source_name, line)?;
        rows_read += 1;
    }
    if let Some((line, _)) = lines.find(|(_, l)| !l.trim().is_empty()) {
        return Err(GridError::TooManyRows {
            source_name: source_name.into(),
            line,
            expected: height,
        });
    }
    Grid::from_tiles(width, height, tiles)
}

/// Reads a `.map` file; errors carry the path as given.
pub fn read_map_file(path: impl AsRef<Path>) -> Result<Grid, GridError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| GridError::Io {
        source_name: name.clone(),
        message: format!("cannot read map file: {e}"),
    })?;
    read_map(&text, &name)
}

impl Grid {
    /// Builds a grid from bare MovingAI rows given in code (row `i` is reported as line
    /// `i + 1` of `<rows>`), e.g. `Grid::from_rows(&["..@", "..."])`.
    pub fn from_rows(rows: &[&str]) -> Result<Grid, GridError> {
        read_map_rows(rows.iter().enumerate().map(|(i, r)| (i + 1, *r)), "<rows>")
    }
}

/// Builds a grid from bare MovingAI rows (no header), e.g. the inline `rows = [...]` of a
/// scenario. Each row comes with the line number to report for it; the first row sets the
/// width. An empty list is a [`GridError::BadShape`] at line 0 (the caller knows better).
pub fn read_map_rows<'a, I>(rows: I, source_name: &str) -> Result<Grid, GridError>
where
    I: IntoIterator<Item = (usize, &'a str)>,
{
    let mut tiles = Vec::new();
    let mut width: Option<u32> = None;
    let mut height = 0u32;
    for (line, row) in rows {
        let row = row.strip_suffix('\r').unwrap_or(row);
        let w = match width {
            Some(w) => w,
            None => {
                let n = u32::try_from(row.chars().count()).unwrap_or(u32::MAX);
                Grid::checked_len(n, 1, source_name, line)?;
                width = Some(n);
                n
            }
        };
        push_row(&mut tiles, row, w, source_name, line)?;
        height = height.saturating_add(1);
        Grid::checked_len(w, height, source_name, line)?;
    }
    let Some(width) = width else {
        return Err(GridError::BadShape {
            source_name: source_name.into(),
            line: 0,
            width: 0,
            height: 0,
            problem: "no rows".into(),
        });
    };
    Grid::from_tiles(width, height, tiles)
}

/// Writes the canonical `.map` text (LF line ends, final newline).
pub fn write_map(grid: &Grid) -> String {
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    let mut out = String::with_capacity(40 + (w + 1) * h);
    out.push_str(&format!("type octile\nheight {h}\nwidth {w}\nmap\n"));
    for row in grid.tiles().chunks(w) {
        out.extend(row.iter().map(|t| t.to_char()));
        out.push('\n');
    }
    out
}

/// Writes a grid to a `.map` file.
pub fn write_map_file(grid: &Grid, path: impl AsRef<Path>) -> Result<(), GridError> {
    let path = path.as_ref();
    std::fs::write(path, write_map(grid)).map_err(|e| GridError::Io {
        source_name: path.display().to_string(),
        message: format!("cannot write map file: {e}"),
    })
}

/// Lines numbered from 1, with one trailing CR removed (CRLF tolerance).
pub(crate) fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
}

fn parse_dimension(
    value: &str,
    which: Dimension,
    previous: Option<u32>,
    source_name: &str,
    line: usize,
) -> Result<u32, GridError> {
    let bad = |problem: &str| GridError::BadDimension {
        source_name: source_name.into(),
        line,
        which,
        value: value.into(),
        problem: problem.into(),
    };
    if previous.is_some() {
        return Err(bad("given twice"));
    }
    if value.is_empty() {
        return Err(bad("missing value"));
    }
    match value.parse::<u32>() {
        Ok(0) => Err(bad("must be at least 1")),
        Ok(n) => Ok(n),
        Err(_) => Err(bad("not a positive integer")),
    }
}

/// Appends one row's tiles after checking its width and characters.
fn push_row(
    tiles: &mut Vec<Tile>,
    row: &str,
    width: u32,
    source_name: &str,
    line: usize,
) -> Result<(), GridError> {
    let found = row.chars().count();
    if found != width as usize {
        return Err(GridError::RowWidth {
            source_name: source_name.into(),
            line,
            found,
            expected: width,
        });
    }
    for (i, ch) in row.chars().enumerate() {
        let tile = Tile::from_char(ch).ok_or_else(|| GridError::UnknownChar {
            source_name: source_name.into(),
            line,
            column: i + 1,
            ch,
        })?;
        tiles.push(tile);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Cell;

    const LOOP: &str = "type octile\nheight 4\nwidth 4\nmap\n....\n.@@.\n.@@.\n....\n";

    #[test]
    fn reads_lacam_loop_fixture() {
        let g = read_map(LOOP, "loop.map").unwrap();
        assert_eq!((g.width(), g.height()), (4, 4));
        assert_eq!(g.blocked_count(), 4);
        assert!(g.is_blocked(Cell::new(1, 1)));
        assert!(!g.is_blocked(Cell::new(0, 1)));
        assert_eq!(write_map(&g), LOOP);
    }

    #[test]
    fn width_before_height_and_crlf() {
        let text = "type octile\r\nwidth 3\r\nheight 2\r\nmap\r\nT.S\r\nG@O\r\n";
        let g = read_map(text, "crlf.map").unwrap();
        assert_eq!((g.width(), g.height()), (3, 2));
        assert_eq!(g.tile(Cell::new(2, 0)), Some(Tile::Swamp));
        assert_eq!(
            write_map(&g),
            text.replace("\r\n", "\n")
                .replace("width 3\nheight 2", "height 2\nwidth 3")
        );
    }

    #[test]
    fn header_errors() {
        let e = read_map("type octile\nheight 4\n", "t.map").unwrap_err();
        assert_eq!(
            e,
            GridError::TruncatedHeader {
                source_name: "t.map".into(),
                line: 3
            }
        );
        let e = read_map("type octile\nheight x\nwidth 2\nmap\n", "t.map").unwrap_err();
        assert!(
            matches!(
                e,
                GridError::BadDimension {
                    line: 2,
                    which: Dimension::Height,
                    ..
                }
            ),
            "{e}"
        );
        let e = read_map("type octile\nheight 0\nwidth 2\nmap\n", "t.map").unwrap_err();
        assert!(matches!(e, GridError::BadDimension { line: 2, .. }), "{e}");
        let e = read_map("type octile\nwidth 2\nwidth 2\nmap\n", "t.map").unwrap_err();
        assert!(
            matches!(
                e,
                GridError::BadDimension {
                    line: 3,
                    which: Dimension::Width,
                    ..
                }
            ),
            "{e}"
        );
        let e = read_map("type octile\nheight 2\nmap\n..\n..\n", "t.map").unwrap_err();
        assert!(
            matches!(
                e,
                GridError::MissingDimension {
                    line: 3,
                    which: Dimension::Width,
                    ..
                }
            ),
            "{e}"
        );
        let e = read_map("type hex\nheight 2\nwidth 2\nmap\n", "t.map").unwrap_err();
        assert!(
            matches!(e, GridError::UnsupportedType { line: 1, .. }),
            "{e}"
        );
        let e = read_map("type octile\nsize 2\n", "t.map").unwrap_err();
        assert!(matches!(e, GridError::BadHeaderLine { line: 2, .. }), "{e}");
        let e = read_map("type octile\nheight 100000\nwidth 100000\nmap\n", "t.map").unwrap_err();
        assert!(matches!(e, GridError::BadShape { line: 4, .. }), "{e}");
        let e = read_map("", "t.map").unwrap_err();
        assert!(
            matches!(e, GridError::TruncatedHeader { line: 1, .. }),
            "{e}"
        );
    }

    #[test]
    fn row_errors() {
        let e = read_map("type octile\nheight 2\nwidth 3\nmap\n...\n..\n", "x.map").unwrap_err();
        assert_eq!(e.to_string(), "x.map:6: row has 2 characters, expected 3");
        let e = read_map("type octile\nheight 2\nwidth 3\nmap\n...\n.x.\n", "x.map").unwrap_err();
        assert_eq!(
            e,
            GridError::UnknownChar {
                source_name: "x.map".into(),
                line: 6,
                column: 2,
                ch: 'x'
            }
        );
        let e = read_map("type octile\nheight 3\nwidth 3\nmap\n...\n...\n", "x.map").unwrap_err();
        assert!(
            matches!(
                e,
                GridError::TooFewRows {
                    line: 7,
                    found: 2,
                    expected: 3,
                    ..
                }
            ),
            "{e}"
        );
        let e = read_map("type octile\nheight 1\nwidth 3\nmap\n...\n\n...\n", "x.map").unwrap_err();
        assert!(
            matches!(
                e,
                GridError::TooManyRows {
                    line: 7,
                    expected: 1,
                    ..
                }
            ),
            "{e}"
        );
        // Trailing blank lines are fine.
        assert!(read_map("type octile\nheight 1\nwidth 3\nmap\n...\n\n\n", "x.map").is_ok());
    }

    #[test]
    fn inline_rows() {
        let g = read_map_rows([(3, "..@"), (4, "...")], "s.toml").unwrap();
        assert_eq!((g.width(), g.height()), (3, 2));
        let e = read_map_rows([(3, "..@"), (4, "....")], "s.toml").unwrap_err();
        assert!(
            matches!(
                e,
                GridError::RowWidth {
                    line: 4,
                    found: 4,
                    expected: 3,
                    ..
                }
            ),
            "{e}"
        );
        let e = read_map_rows([(3, "")], "s.toml").unwrap_err();
        assert!(matches!(e, GridError::BadShape { line: 3, .. }), "{e}");
        assert!(read_map_rows(std::iter::empty(), "s.toml").is_err());
    }

    #[test]
    fn file_io_errors_name_the_path() {
        let e = read_map_file("/nonexistent/dir/x.map").unwrap_err();
        assert!(matches!(e, GridError::Io { .. }));
        assert!(e.to_string().starts_with("/nonexistent/dir/x.map: "), "{e}");
    }
}
