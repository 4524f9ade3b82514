//! Rows measured by the peers' own programs (`bench/peers/zenoh`, `bench/peers/dora`), read
//! back so that one table, one plot and one set of ratios hold every transport.
//!
//! The peers live in cargo projects of their own because their dependency trees (Zenoh's
//! async runtime and transports, dora's daemon API and Arrow) would double the workspace's
//! build; each one's `run.sh` writes a CSV with exactly [`csv::HEADER`](super::csv::HEADER),
//! measured by the same method (two pinned sides, a 16-byte stamp header, the same sizes and
//! sample counts, nothing trimmed).

use std::path::Path;

use anyhow::{bail, Context, Result};

use super::csv::HEADER;
use super::{Direction, Mode, Point, Summary, TransportKind};

/// The points of the peer CSV file at `path`. A malformed file is an error naming the file,
/// the line and what is wrong; so is a row of a transport `hnav-bench` measures itself.
pub fn read(path: &Path) -> Result<Vec<Point>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("read {}", path.display()))?;
    parse(&text).map_err(|(line, what)| anyhow::anyhow!("{}:{line}: {what}", path.display()))
}

/// The points of a peer CSV text; an error is `(line number, what is wrong)`.
pub fn parse(text: &str) -> Result<Vec<Point>, (usize, String)> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    match lines.next() {
        Some((_, h)) if h.trim_end() == HEADER => {}
        Some((n, h)) => return Err((n, format!("header {h:?}, expected {HEADER:?}"))),
        None => return Err((1, "empty file, expected the header".into())),
    }
    lines
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(n, l)| row(l).map_err(|e| (n, e.to_string())))
        .collect()
}

fn row(line: &str) -> Result<Point> {
    let cols: Vec<&str> = line.trim_end().split(',').collect();
    let want = HEADER.split(',').count();
    if cols.len() != want {
        bail!("{} columns, expected {want}", cols.len());
    }
    let (transport, mode, direction) = name(cols[3])?;
    let size: usize = cols[4]
        .parse()
        .with_context(|| format!("size_bytes {:?} is not a byte count", cols[4]))?;
    let us = |i: usize| -> Result<f64> {
        let v: f64 = cols[i]
            .parse()
            .with_context(|| format!("column {i} ({:?}) is not a number", cols[i]))?;
        if !v.is_finite() || v < 0.0 {
            bail!("column {i} ({v}) is not a latency in µs");
        }
        Ok(v)
    };
    let ns = |i: usize| -> Result<u64> { Ok((us(i)? * 1e3).round() as u64) };
    let n: u64 = cols[9]
        .parse()
        .with_context(|| format!("n {:?} is not a sample count", cols[9]))?;
    let summary = Summary {
        n,
        mean_ns: us(5)? * 1e3,
        p50_ns: ns(6)?,
        p90_ns: ns(7)?,
        p99_ns: ns(8)?,
        p999_ns: ns(10)?,
        max_ns: ns(11)?,
    };
    let ordered = [
        summary.p50_ns,
        summary.p90_ns,
        summary.p99_ns,
        summary.p999_ns,
        summary.max_ns,
    ];
    if n == 0 || size == 0 || ordered.windows(2).any(|w| w[0] > w[1]) {
        bail!("n and size must be positive and p50 <= p90 <= p99 <= p99.9 <= max");
    }
    Ok(Point {
        transport,
        mode,
        direction,
        size,
        summary,
    })
}

/// `<transport>/<mode>/<direction>` of a peer.
fn name(s: &str) -> Result<(TransportKind, Mode, Direction)> {
    let parts: Vec<&str> = s.split('/').collect();
    let [t, m, d] = parts[..] else {
        bail!("name {s:?} is not <transport>/<mode>/<direction>");
    };
    let transport: TransportKind = t.parse().map_err(anyhow::Error::msg)?;
    if !TransportKind::PEERS.contains(&transport) {
        bail!("{t} is measured by hnav-bench itself, not by a peer");
    }
    let mode: Mode = m.parse().map_err(anyhow::Error::msg)?;
    let direction = match d {
        "oneway" => Direction::OneWay,
        "roundtrip" => Direction::RoundTrip,
        _ => bail!("direction {d:?}, expected oneway or roundtrip"),
    };
    Ok((transport, mode, direction))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROW: &str =
        "2026-12-03T07:00:00Z,Rust,linux-x86_64-2cpu,zenoh/event/oneway,64,30.5,29.1,33.0,60.2,100000,90.0,400.0";

    #[test]
    fn a_peer_row_reads_back_in_nanoseconds() {
        let points = parse(&format!("{HEADER}\n{ROW}\n")).unwrap();
        assert_eq!(points.len(), 1);
        let p = &points[0];
        assert_eq!(
            (p.transport, p.mode, p.direction, p.size),
            (TransportKind::Zenoh, Mode::Event, Direction::OneWay, 64)
        );
        assert_eq!((p.summary.p50_ns, p.summary.max_ns), (29_100, 400_000));
        assert_eq!(p.summary.n, 100_000);
    }

    #[test]
    fn bad_files_name_the_line_and_the_fault() {
        let cases = [
            ("date,name\n", 1, "header"),
            (
                &*format!("{HEADER}\n{}", ROW.replace("zenoh/", "hnav/")),
                2,
                "itself",
            ),
            (
                &*format!("{HEADER}\n{}", ROW.replace(",64,", ",x,")),
                2,
                "byte count",
            ),
            (
                &*format!("{HEADER}\n\n{}", ROW.replace("29.1", "35.0")),
                3,
                "p50 <= p90",
            ),
            (
                &*format!("{HEADER}\n{}", ROW.replace("/oneway", "/sideways")),
                2,
                "direction",
            ),
            (&*format!("{HEADER}\n{},1", ROW), 2, "columns"),
            ("", 1, "empty"),
        ];
        for (text, line, what) in cases {
            let (n, e) = parse(text).unwrap_err();
            assert_eq!(n, line, "{e}");
            assert!(e.contains(what), "{e:?} should say {what:?}");
        }
    }

    #[test]
    fn the_file_is_named_in_the_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("peers-zenoh.csv");
        std::fs::write(&path, "nonsense\n").unwrap();
        let e = read(&path).unwrap_err().to_string();
        assert!(e.contains("peers-zenoh.csv:1:"), "{e}");
    }
}
