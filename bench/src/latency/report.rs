//! The human-readable report: tables of every point, then the ratios the HNAV issue aims at
//! (HNAV within 10 % of raw iceoryx2; 4 MiB one-way within 2× of 64 B one-way).

use std::fmt::Write as _;

use super::{Direction, Mode, Point, Report, TransportKind};

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

fn table(out: &mut String, title: &str, points: &[Point]) {
    if points.is_empty() {
        return;
    }
    let _ = writeln!(out, "\n{title}");
    let _ = writeln!(
        out,
        "{:<26} {:>8} {:>12} {:>12} {:>12} {:>12} {:>8}",
        "name", "size", "avg_us", "p50_us", "p90_us", "p99_us", "n"
    );
    for p in points {
        let s = &p.summary;
        let _ = writeln!(
            out,
            "{:<26} {:>8} {:>12.3} {:>12.3} {:>12.3} {:>12.3} {:>8}",
            p.name(),
            fmt_size(p.size),
            s.mean_us(),
            s.p50_us(),
            s.p90_us(),
            s.p99_us(),
            s.n
        );
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
    let _ = writeln!(out, "\nhnav / iceoryx2 (aim: <= {HNAV_OVER_RAW_AIM:.2})");
    let _ = writeln!(
        out,
        "{:<18} {:>8} {:>8} {:>8}",
        "point", "size", "avg", "p50"
    );
    for (h, r) in pairs {
        let avg = h.summary.mean_ns / r.summary.mean_ns;
        let p50 = h.summary.p50_ns as f64 / r.summary.p50_ns.max(1) as f64;
        let _ = writeln!(
            out,
            "{:<18} {:>8} {:>8.3} {:>8.3}  {}",
            format!("{}/{}", h.mode.name(), h.direction.name()),
            fmt_size(h.size),
            avg,
            p50,
            verdict(avg.max(p50), HNAV_OVER_RAW_AIM)
        );
    }
}

/// HNAV one-way at the largest size over the smallest, per mode.
fn large_over_small(out: &mut String, points: &[Point]) {
    let sizes = points.iter().map(|p| p.size);
    let (Some(small), Some(large)) = (sizes.clone().min(), sizes.max()) else {
        return;
    };
    if small == large {
        return;
    }
    let mut header = false;
    for mode in [Mode::Poll, Mode::Event] {
        let one = |size| find(points, TransportKind::Hnav, mode, Direction::OneWay, size);
        let (Some(s), Some(l)) = (one(small), one(large)) else {
            continue;
        };
        if !header {
            let _ = writeln!(
                out,
                "\nhnav one-way {} / {} (aim: <= {LARGE_OVER_SMALL_AIM:.1})",
                fmt_size(large),
                fmt_size(small)
            );
            let _ = writeln!(out, "{:<18} {:>8} {:>8}", "mode", "avg", "p50");
            header = true;
        }
        let avg = l.summary.mean_ns / s.summary.mean_ns;
        let p50 = l.summary.p50_ns as f64 / s.summary.p50_ns.max(1) as f64;
        let _ = writeln!(
            out,
            "{:<18} {:>8.3} {:>8.3}  {}",
            mode.name(),
            avg,
            p50,
            verdict(avg.max(p50), LARGE_OVER_SMALL_AIM)
        );
    }
}

impl Report {
    /// The tables and ratios as printed by `hnav-bench latency`.
    pub fn render(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "latency ({}, {}, {} iterations per point, threads {})",
            self.info.platform,
            self.info.date,
            self.iterations,
            if self.pinned {
                "pinned to CPUs 0 and 1"
            } else {
                "not pinned (1 CPU)"
            }
        );
        table(&mut out, "shared memory (latency.csv)", &self.shm);
        table(&mut out, "sockets (latency-sockets.csv)", &self.sockets);
        hnav_over_raw(&mut out, &self.shm);
        large_over_small(&mut out, &self.shm);
        if !self.files.is_empty() {
            let _ = writeln!(out);
            for f in &self.files {
                let _ = writeln!(out, "wrote {}", f.display());
            }
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
