//! CSV output in dora-benchmark's latency schema.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};

use super::Point;

/// dora-benchmark's header line, exactly as it writes it.
pub const DORA_HEADER: &str =
    "date,language,platform,name,size_bytes,avg_us,p50_us,p90_us,p99_us,n";

/// Our header: dora-benchmark's columns first, so its scripts read the file unchanged, then
/// the tail of the distribution.
pub const HEADER: &str =
    "date,language,platform,name,size_bytes,avg_us,p50_us,p90_us,p99_us,n,p999_us,max_us";

/// What is the same for every row of one benchmark run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunInfo {
    /// UTC start of the run, ISO 8601 (`2025-01-31T12:00:00Z`).
    pub date: String,
    /// Always `Rust` here; the column exists so other languages' results can share a file.
    pub language: String,
    /// `<os>-<arch>-<n>cpu`, e.g. `linux-x86_64-2cpu`.
    pub platform: String,
}

impl RunInfo {
    /// The info of a run starting now on this machine.
    pub fn now() -> Self {
        Self {
            date: chrono::Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, true),
            language: "Rust".to_string(),
            platform: platform(),
        }
    }
}

/// `<os>-<arch>-<n>cpu` of this machine.
pub fn platform() -> String {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!(
        "{}-{}-{cpus}cpu",
        std::env::consts::OS,
        std::env::consts::ARCH
    )
}

/// One CSV line (no newline) for `point`; times in µs with 3 decimals.
pub fn format_row(info: &RunInfo, point: &Point) -> String {
    let s = &point.summary;
    format!(
        "{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{},{:.3},{:.3}",
        info.date,
        info.language,
        info.platform,
        point.name(),
        point.size,
        s.mean_us(),
        s.p50_us(),
        s.p90_us(),
        s.p99_us(),
        s.n,
        s.p999_us(),
        s.max_us()
    )
}

/// Writes `points` to `path` (header first), replacing the file.
pub fn write(path: &Path, info: &RunInfo, points: &[Point]) -> Result<()> {
    let mut text = String::with_capacity(HEADER.len() + 1 + points.len() * 96);
    text.push_str(HEADER);
    text.push('\n');
    for p in points {
        text.push_str(&format_row(info, p));
        text.push('\n');
    }
    std::fs::File::create(path)
        .and_then(|mut f| f.write_all(text.as_bytes()))
        .with_context(|| format!("write {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::latency::{Direction, Mode, Summary, TransportKind};

    fn point() -> Point {
        Point {
            transport: TransportKind::Hnav,
            mode: Mode::Event,
            direction: Direction::OneWay,
            size: 4_194_304,
            summary: Summary {
                n: 10_000,
                mean_ns: 31_234.567_8,
                p50_ns: 30_100,
                p90_ns: 35_007,
                p99_ns: 61_440,
                p999_ns: 65_000,
                max_ns: 70_000,
            },
        }
    }

    #[test]
    fn header_starts_with_dora_benchmarks() {
        assert_eq!(
            DORA_HEADER,
            "date,language,platform,name,size_bytes,avg_us,p50_us,p90_us,p99_us,n"
        );
        assert!(HEADER.starts_with(&format!("{DORA_HEADER},")));
    }

    #[test]
    fn a_row_parses_back() {
        let info = RunInfo {
            date: "2025-01-31T12:00:00Z".into(),
            language: "Rust".into(),
            platform: "linux-x86_64-2cpu".into(),
        };
        let row = format_row(&info, &point());
        let cols: Vec<&str> = row.split(',').collect();
        assert_eq!(cols.len(), HEADER.split(',').count());
        assert_eq!(
            cols,
            [
                "2025-01-31T12:00:00Z",
                "Rust",
                "linux-x86_64-2cpu",
                "hnav/event/oneway",
                "4194304",
                "31.235",
                "30.100",
                "35.007",
                "61.440",
                "10000",
                "65.000",
                "70.000"
            ]
        );
        let avg: f64 = cols[5].parse().unwrap();
        assert!((avg - 31.235).abs() < 1e-9);
    }

    #[test]
    fn written_file_starts_with_the_header() {
        let dir = std::env::temp_dir().join(format!("hnav-bench-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("latency.csv");
        write(&path, &RunInfo::now(), &[point(), point()]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0], HEADER);
        assert!(lines[1].ends_with(
            ",hnav/event/oneway,4194304,31.235,30.100,35.007,61.440,10000,65.000,70.000"
        ));
    }

    #[test]
    fn platform_names_os_arch_and_cpus() {
        let p = platform();
        assert!(p.starts_with(std::env::consts::OS), "{p}");
        assert!(p.ends_with("cpu"), "{p}");
    }
}
