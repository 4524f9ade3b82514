//! Experiment `fidelity`: every number the seeds publish that HNAV can compute, beside ours, in
//! one table (`docs/experiments/fidelity.md`). It runs the code that computes each number (the
//! other experiments' measurements, the neural map, the tick harness of the conflict
//! experiments); it copies no output.
//!
//! Each row has a status: *reproduced* (ours equals the published value, or a statistical
//! published value lies in our 95 % interval), *reproduced under a stated reading* (the same,
//! but only with a choice the source leaves open, named in the row), or *differs* (why, in one
//! sentence, and where the longer explanation is). Wall-time rows depend on the machine; they
//! are listed but a test never holds them to their status.
//!
//! | module | rows |
//! |---|---|
//! | [`chapter3`] | dissertation (seed 000) Tables 3-3, 3-5, 3-7, 3-8 and 3-9 |
//! | [`chapter2`] | dissertation (seed 000) Tables 2-1, 2-2 and Figs. 2-16/2-18 |
//! | [`seeds`] | seed 001's Figs. 4 and 5, seed 002's Table 3.1, seed 003's Tables 1 and 2, seed 004's rule base |

use std::fmt::Write as _;

use serde::Serialize;

use super::stats::Interval;
use super::{Options, Report};

pub mod chapter2;
pub mod chapter3;
pub mod seeds;

/// The experiment's name on the command line.
pub const NAME: &str = "fidelity";

/// Where the full run writes its table, relative to the repository.
pub const DOC: &str = "docs/experiments/fidelity.md";

/// How a published number compares with ours.
#[derive(Clone, PartialEq, Debug, Serialize)]
#[serde(tag = "status", rename_all = "kebab-case")]
pub enum Status {
    /// Ours equals it (or it lies in our 95 % interval).
    Reproduced,
    /// Ours equals it under a reading of the source that it leaves open.
    ReproducedUnderReading {
        /// The reading.
        reading: String,
    },
    /// Ours does not; why, and where the longer explanation is (a path under `docs/`, or a
    /// source file).
    Differs {
        /// One sentence.
        why: String,
        /// The longer explanation.
        link: String,
    },
}

impl Status {
    /// The status's name, as the table and the JSON spell it.
    pub fn name(&self) -> &'static str {
        match self {
            Status::Reproduced => "reproduced",
            Status::ReproducedUnderReading { .. } => "reproduced under a stated reading",
            Status::Differs { .. } => "differs",
        }
    }

    /// A reading's status.
    pub fn reading(reading: &str) -> Status {
        Status::ReproducedUnderReading {
            reading: reading.to_string(),
        }
    }

    /// A difference's status.
    pub fn differs(why: &str, link: &str) -> Status {
        Status::Differs {
            why: why.to_string(),
            link: link.to_string(),
        }
    }

    /// `matches` decides between `if_equal` and the difference.
    pub fn of(matches: bool, if_equal: Status, why: &str, link: &str) -> Status {
        if matches {
            if_equal
        } else {
            Status::differs(why, link)
        }
    }
}

/// One published number beside ours.
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct Row {
    /// A stable id, e.g. `000/table-3-8/task-1/hnav-steps`: what the test holds to its status.
    pub id: String,
    /// Seed, table or figure, row, in words.
    pub source: String,
    /// The published value, as printed.
    pub published: String,
    /// Ours (with its 95 % interval where it is statistical).
    pub ours: String,
    /// The ratio ours / published, or whether they match.
    pub comparison: String,
    /// Whether the value depends on the machine (a wall time): listed, never held by a test.
    pub timing: bool,
    /// How they compare.
    pub status: Status,
}

impl Row {
    /// A row; `timing` false.
    pub fn new(
        id: &str,
        source: &str,
        published: String,
        ours: String,
        comparison: String,
        status: Status,
    ) -> Row {
        Row {
            id: id.to_string(),
            source: source.to_string(),
            published,
            ours,
            comparison,
            timing: false,
            status,
        }
    }

    /// The same row, marked as a wall time.
    pub fn timing(self) -> Row {
        Row {
            timing: true,
            ..self
        }
    }
}

/// `ours / published` to three digits.
pub fn ratio(ours: f64, published: f64) -> String {
    format!("{:.3}", ours / published)
}

/// "match" or "no match".
pub fn matched(m: bool) -> String {
    if m { "match" } else { "no match" }.to_string()
}

/// A value and its 95 % interval.
pub fn with_interval(value: f64, ci: Option<Interval>, scale: f64) -> String {
    match ci {
        Some(ci) => format!(
            "{:.1} [{:.1}, {:.1}]",
            scale * value,
            scale * ci.lo,
            scale * ci.hi
        ),
        None => format!("{:.1}", scale * value),
    }
}

/// Whether `published` lies in `ci` (scaled).
pub fn inside(published: f64, ci: Option<Interval>, scale: f64) -> bool {
    ci.is_some_and(|ci| scale * ci.lo <= published && published <= scale * ci.hi)
}

/// Every row, in source order.
pub fn rows(options: Options) -> anyhow::Result<Vec<Row>> {
    let mut rows = chapter2::rows()?;
    rows.extend(chapter3::rows(options)?);
    rows.extend(seeds::rows(options)?);
    Ok(rows)
}

/// Runs the experiment; the full run also writes [`DOC`].
pub fn run(options: Options) -> anyhow::Result<Report> {
    let rows = rows(options)?;
    let markdown = render(&rows, options);
    if !options.quick {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(DOC);
        std::fs::write(&path, &markdown)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
    }
    Ok(Report {
        name: NAME,
        quick: options.quick,
        seed: options.seed,
        markdown,
        data: serde_json::json!({ "rows": rows }),
    })
}

fn counts(rows: &[Row]) -> [(usize, &'static str); 3] {
    let n = |name: &str| rows.iter().filter(|r| r.status.name() == name).count();
    [
        (n("reproduced"), "reproduced"),
        (
            n("reproduced under a stated reading"),
            "reproduced under a stated reading",
        ),
        (n("differs"), "differ"),
    ]
}

fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// The table, with the counts per status and the command in its first lines.
pub fn render(rows: &[Row], options: Options) -> String {
    let mut s = String::new();
    let [a, b, c] = counts(rows);
    let _ = writeln!(
        s,
        "# Fidelity: every number the seeds publish, beside ours\n"
    );
    let _ = writeln!(
        s,
        "{} rows: **{} {}**, **{} {}**, **{} {}**.\n",
        rows.len(),
        a.0,
        a.1,
        b.0,
        b.1,
        c.0,
        c.1
    );
    let quick = if options.quick { " --quick" } else { "" };
    let _ = writeln!(s, "Made by `cargo run --release -p hnav-bench -- experiment fidelity{quick} --seed {}` (the full run writes this file; `--json` prints the rows). Generated: edit `bench/src/experiment/fidelity/`, not this file. Which works the seeds are: [sources](../reference/sources.md).\n", options.seed);
    let _ = writeln!(s, "Every row is computed by running the code: the other experiments' measurements ([pso.md](pso.md), [hnav-vs-astar.md](hnav-vs-astar.md), [ga-fuzzy.md](ga-fuzzy.md), `hnav-bench seed002`), the neural map and path constructor, and the tick harness of the conflict experiments (`bench/src/tick.rs`). *Reproduced*: equal, or a statistical published value inside our 95 % interval. *Reproduced under a stated reading*: the same, with a choice the source leaves open (named). *Differs*: why, and where it is explained. Rows marked (time) are wall times on this machine: listed, never held by the test (`bench/tests/fidelity.rs`).\n");
    let _ = writeln!(
        s,
        "| source | published | ours | ours / published or match | status |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for r in rows {
        let status = match &r.status {
            Status::Reproduced => "reproduced".to_string(),
            Status::ReproducedUnderReading { reading } => {
                format!("reproduced under a stated reading: {reading}")
            }
            Status::Differs { why, link } => format!("differs: {why} ([why]({link}))"),
        };
        let _ = writeln!(
            s,
            "| {}{} | {} | {} | {} | {} |",
            cell(&r.source),
            if r.timing { " (time)" } else { "" },
            cell(&r.published),
            cell(&r.ours),
            cell(&r.comparison),
            cell(&status)
        );
    }
    s
}
