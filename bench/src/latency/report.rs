//! The human-readable report: a table of every point, then the ratios the performance issue
//! aims at: HNAV within 10 % of raw iceoryx2; its one-way at 1 MiB and more within 2× of
//! 64 B; and every other transport against HNAV (event one-way p50 and p99).

use std::fmt::Write as _;

use super::{Direction, Mode, Point, Report, TransportKind, MIB};

/// The aim for HNAV over raw iceoryx2 (avg and p50): at most 10 % slower.
pub const HNAV_OVER_RAW_AIM: f64 = 1.10;
/// The aim for HNAV's largest over smallest one-way latency.
pub const LARGE_OVER_SMALL_AIM: f64 = 2.0;

/// `64 B`, `16 KiB`, `4 MiB`.
pub fn fmt_size(bytes: usize) -> String {
    const KIB: usize = 1024;
    const MIB: usize = 1024 * KIB;
    if bytes >= MIB && bytes.is_multiple_of(MIB) {
        format!("{} MiB", bytes / MIB)
    } else if bytes >= KIB && bytes.is_multiple_of(KIB) {
        format!("{} KiB", bytes / KIB)
    } else {
        format!("{bytes} B")
    }
}

/// The column heads of a point's row.
const COLUMNS: [&str; 10] = [
    "name", "size", "avg_us", "p50_us", "p90_us", "p99_us", "p99.9_us", "max_us", "n", "",
];

/// A point's cells, in [`COLUMNS`]' order (without the last, empty one).
fn cells(p: &Point) -> [String; 9] {
    let s = &p.summary;
    [
        p.name(),
        fmt_size(p.size),
        format!("{:.3}", s.mean_us()),
        format!("{:.3}", s.p50_us()),
        format!("{:.3}", s.p90_us()),
        format!("{:.3}", s.p99_us()),
        format!("{:.3}", s.p999_us()),
        format!("{:.3}", s.max_us()),
        s.n.to_string(),
    ]
}

fn table(out: &mut String, points: &[Point]) {
    if points.is_empty() {
        return;
    }
    let row = |out: &mut String, c: &[String]| {
        let _ = writeln!(
            out,
            "{:<26} {:>8} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11} {:>7}",
            c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8]
        );
    };
    let _ = writeln!(out);
    row(out, &COLUMNS.map(String::from));
    for p in points {
        row(out, &cells(p));
    }
}

fn find(points: &[Point], t: TransportKind, m: Mode, d: Direction, size: usize) -> Option<&Point> {
    points
        .iter()
        .find(|p| p.transport == t && p.mode == m && p.direction == d && p.size == size)
}

fn verdict(ratio: f64, aim: f64) -> &'static str {
    if ratio <= aim {
        "ok"
    } else {
        "OVER"
    }
}

/// `a / b` of two nanosecond figures, 0 taken as 1 ns.
fn ratio(a: u64, b: u64) -> f64 {
    a.max(1) as f64 / b.max(1) as f64
}

/// HNAV / raw iceoryx2 for every point measured on both.
fn hnav_over_raw(out: &mut String, points: &[Point]) {
    let pairs: Vec<(&Point, &Point)> = points
        .iter()
        .filter(|p| p.transport == TransportKind::Hnav)
        .filter_map(|h| {
            find(points, TransportKind::Iceoryx2, h.mode, h.direction, h.size).map(|r| (h, r))
        })
        .collect();
    if pairs.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\nhnav / iceoryx2 (aim: avg and p50 <= {HNAV_OVER_RAW_AIM:.2})"
    );
    let _ = writeln!(
        out,
        "{:<18} {:>8} {:>8} {:>8} {:>8}",
        "point", "size", "avg", "p50", "p99"
    );
    for (h, r) in pairs {
        let avg = h.summary.mean_ns / r.summary.mean_ns;
        let p50 = ratio(h.summary.p50_ns, r.summary.p50_ns);
        let p99 = ratio(h.summary.p99_ns, r.summary.p99_ns);
        let _ = writeln!(
            out,
            "{:<18} {:>8} {:>8.3} {:>8.3} {:>8.3}  {}",
            format!("{}/{}", h.mode.name(), h.direction.name()),
            fmt_size(h.size),
            avg,
            p50,
            p99,
            verdict(avg.max(p50), HNAV_OVER_RAW_AIM)
        );
    }
}

/// HNAV one-way at every size of 1 MiB and more over 64 B (or the smallest size), per mode.
fn large_over_small(out: &mut String, points: &[Point]) {
    let mut sizes: Vec<usize> = points.iter().map(|p| p.size).collect();
    sizes.sort_unstable();
    sizes.dedup();
    let Some(&small) = sizes.iter().find(|&&s| s == 64).or(sizes.first()) else {
        return;
    };
    let large: Vec<usize> = sizes
        .into_iter()
        .filter(|&s| s >= MIB && s > small)
        .collect();
    let mut header = false;
    for mode in [Mode::Poll, Mode::Event] {
        let one = |size| find(points, TransportKind::Hnav, mode, Direction::OneWay, size);
        let Some(s) = one(small) else {
            continue;
        };
        for &size in &large {
            let Some(l) = one(size) else {
                continue;
            };
            if !header {
                let _ = writeln!(
                    out,
                    "\nhnav one-way, large / {} (aim: <= {LARGE_OVER_SMALL_AIM:.1})",
                    fmt_size(small)
                );
                let _ = writeln!(out, "{:<8} {:>8} {:>8} {:>8}", "mode", "size", "avg", "p50");
                header = true;
            }
            let avg = l.summary.mean_ns / s.summary.mean_ns;
            let p50 = ratio(l.summary.p50_ns, s.summary.p50_ns);
            let _ = writeln!(
                out,
                "{:<8} {:>8} {:>8.3} {:>8.3}  {}",
                mode.name(),
                fmt_size(size),
                avg,
                p50,
                verdict(avg.max(p50), LARGE_OVER_SMALL_AIM)
            );
        }
    }
}

/// Every other transport's one-way p50 and p99 over HNAV's, in event mode (the only mode
/// every transport has), per size: above 1 means HNAV is ahead.
fn others_over_hnav(out: &mut String, points: &[Point]) {
    let rows: Vec<(&Point, &Point)> = points
        .iter()
        .filter(|p| p.transport != TransportKind::Hnav)
        .filter(|p| p.mode == Mode::Event && p.direction == Direction::OneWay)
        .filter_map(|o| {
            find(
                points,
                TransportKind::Hnav,
                Mode::Event,
                Direction::OneWay,
                o.size,
            )
            .map(|h| (o, h))
        })
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\nevent one-way, other / hnav (above 1: hnav is ahead; below 1 at 64 B for the \
         floors and the socket wake-up, see the README)"
    );
    let _ = writeln!(
        out,
        "{:<12} {:>8} {:>8} {:>8}",
        "transport", "size", "p50", "p99"
    );
    for (o, h) in rows {
        let _ = writeln!(
            out,
            "{:<12} {:>8} {:>8.3} {:>8.3}",
            o.transport.name(),
            fmt_size(o.size),
            ratio(o.summary.p50_ns, h.summary.p50_ns),
            ratio(o.summary.p99_ns, h.summary.p99_ns)
        );
    }
}

impl Report {
    /// The first line: machine, date, iterations, pinning, duration.
    fn heading(&self) -> String {
        format!(
            "latency ({}, {}, {} samples a point up to 64 KiB, a tenth from 1 MiB, a hundredth \
             from 16 MiB (column n); threads {}; measured in {:.0} s)",
            self.info.platform,
            self.info.date,
            self.iterations,
            if self.pinned {
                "pinned to CPUs 0 and 1"
            } else {
                "not pinned (1 CPU)"
            },
            self.elapsed.as_secs_f64()
        )
    }

    /// The tables and ratios as printed by `hnav-bench latency`.
    pub fn render(&self) -> String {
        let mut out = self.heading();
        out.push('\n');
        table(&mut out, &self.points);
        hnav_over_raw(&mut out, &self.points);
        large_over_small(&mut out, &self.points);
        others_over_hnav(&mut out, &self.points);
        if !self.files.is_empty() {
            let _ = writeln!(out);
            for f in &self.files {
                let _ = writeln!(out, "wrote {}", f.display());
            }
        }
        out
    }

    /// Every point as a markdown table (`latency.md`).
    pub fn markdown(&self) -> String {
        let mut out = format!("{}\n\n", self.heading());
        let heads = &COLUMNS[..9];
        let _ = writeln!(out, "| {} |", heads.join(" | "));
        let _ = writeln!(
            out,
            "|{}",
            heads
                .iter()
                .enumerate()
                .map(|(i, _)| if i < 2 { "---|" } else { "---:|" })
                .collect::<String>()
        );
        for p in &self.points {
            let _ = writeln!(out, "| {} |", cells(p).join(" | "));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_shown_in_binary_units() {
        assert_eq!(fmt_size(64), "64 B");
        assert_eq!(fmt_size(16 * 1024), "16 KiB");
        assert_eq!(fmt_size(4_194_304), "4 MiB");
        assert_eq!(fmt_size(1000), "1000 B");
    }
}
