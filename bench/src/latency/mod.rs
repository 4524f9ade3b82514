//! `hnav-bench latency`: how long a sample takes from one thread to another over raw iceoryx2,
//! the HNAV transport, a Unix domain socket and TCP loopback.
//!
//! Method (modelled on iceoryx2's own `benchmark-publish-subscribe`, see
//! `shared/reference/iceoryx2-0.10.md` B.2):
//!
//! - Two threads of one process, each creating its own ports (iceoryx2 `ipc` ports are
//!   `!Send`), pinned to CPUs 0 and 1 when the machine has two, started together.
//! - Ping-pong: Ping stamps the time (ns since a shared [`Instant`](std::time::Instant)) into a
//!   [`Stamp`] header and sends; Pong records `now - stamp` (one-way) and echoes; Ping records
//!   `now - send time` (round trip). One run gives both directions of a point.
//! - 1,000 warm-up iterations are discarded, then every one of N iterations is kept
//!   (N = 10,000 with `--quick`, 100,000 otherwise): no trimming, no outlier removal.
//! - Payload: a `[u8]` slice service of `size` bytes with the [`Stamp`] user header. It is not
//!   filled per iteration: we measure transfer, not memset.
//! - Modes: [`Mode::Poll`] spins on `receive`; [`Mode::Event`] also notifies and the receiver
//!   blocks until woken: raw iceoryx2 in a WaitSet, HNAV in its `Waiter`.
//!
//! Results: `DIR/latency.csv` (iceoryx2 and hnav) and `DIR/latency-sockets.csv` (uds, tcp).

pub mod csv;
mod hnav;
mod pingpong;
mod raw;
pub mod report;
mod sockets;
pub mod stats;

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use iceoryx2::prelude::ZeroCopySend;

use hnav_runtime::transport::{purge_run, Delivery, Qos, RunId};

pub use csv::RunInfo;
pub use stats::Summary;

use pingpong::{run_pair, Role, Samples};

/// Iterations run before measuring: connections, page faults and caches settle.
pub const WARMUP: usize = 1_000;
/// Measured iterations with `--quick`.
pub const ITERATIONS_QUICK: usize = 10_000;
/// Measured iterations of a full run.
pub const ITERATIONS_FULL: usize = 100_000;
/// Payload sizes measured by default: a small message and a 1024×1024 `f32` map snapshot.
pub const DEFAULT_SIZES: [usize; 2] = [64, 4_194_304];

/// The user header of every benchmark sample.
#[derive(Debug, Default, Clone, Copy, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::bench::Stamp")]
pub struct Stamp {
    /// Send time, ns since the ping-pong's shared epoch.
    pub stamp_ns: u64,
    /// Iteration number, checked by both sides so a lost sample fails the run.
    pub seq: u64,
}

/// The QoS of every benchmark service, on both raw iceoryx2 and HNAV: one publisher and one
/// subscriber per direction, a one-sample buffer and no history, as in iceoryx2's benchmark.
/// Kept minimal because the publisher preallocates `subscribers × (buffer + borrowed) + ...`
/// chunks of `size` bytes, which at 4 MiB is real memory.
pub const BENCH_QOS: Qos = Qos {
    max_publishers: 1,
    max_subscribers: 1,
    buffer: 1,
    history: 0,
    delivery: Delivery::LatestOnly,
};

/// What carries the samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TransportKind {
    /// iceoryx2 0.10 used directly.
    Iceoryx2,
    /// `hnav_runtime::transport` (iceoryx2 underneath).
    Hnav,
    /// A `std::os::unix::net::UnixStream` pair.
    Uds,
    /// `std::net::TcpStream` over 127.0.0.1.
    Tcp,
}

impl TransportKind {
    /// Every transport, in the order they are measured.
    pub const ALL: [TransportKind; 4] = [Self::Iceoryx2, Self::Hnav, Self::Uds, Self::Tcp];

    /// The name used in output (`iceoryx2`, `hnav`, `uds`, `tcp`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Iceoryx2 => "iceoryx2",
            Self::Hnav => "hnav",
            Self::Uds => "uds",
            Self::Tcp => "tcp",
        }
    }

    /// Whether this is a shared-memory transport (rows in `latency.csv`) or a socket.
    pub fn is_shared_memory(self) -> bool {
        matches!(self, Self::Iceoryx2 | Self::Hnav)
    }

    /// The modes it is measured in: sockets only block.
    pub fn modes(self) -> &'static [Mode] {
        if self.is_shared_memory() {
            &[Mode::Poll, Mode::Event]
        } else {
            &[Mode::Event]
        }
    }
}

impl core::str::FromStr for TransportKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| format!("unknown transport {s:?} (expected iceoryx2, hnav, uds or tcp)"))
    }
}

/// How the receiver learns that a sample arrived.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Mode {
    /// Busy-loop on `receive` (the benchmark's explicit polling mode).
    Poll,
    /// Block until woken: an iceoryx2 WaitSet (raw) or the HNAV `Waiter`, or a blocking socket read.
    Event,
}

impl Mode {
    /// `poll` or `event`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Poll => "poll",
            Self::Event => "event",
        }
    }
}

/// Which latency a point reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Direction {
    /// Send to receive.
    OneWay,
    /// Send to the echo's receive.
    RoundTrip,
}

impl Direction {
    /// `oneway` or `roundtrip`.
    pub fn name(self) -> &'static str {
        match self {
            Self::OneWay => "oneway",
            Self::RoundTrip => "roundtrip",
        }
    }
}

/// One measured point: a transport, mode, direction and size, and its statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// The transport.
    pub transport: TransportKind,
    /// The mode.
    pub mode: Mode,
    /// The direction.
    pub direction: Direction,
    /// Payload bytes (without the 16-byte header).
    pub size: usize,
    /// The statistics of the kept samples.
    pub summary: Summary,
}

impl Point {
    /// `<transport>/<mode>/<direction>`, the CSV `name` column.
    pub fn name(&self) -> String {
        format!(
            "{}/{}/{}",
            self.transport.name(),
            self.mode.name(),
            self.direction.name()
        )
    }
}

/// What to measure and where to write it.
#[derive(Debug, Clone)]
pub struct Options {
    /// Measured iterations per point.
    pub iterations: usize,
    /// Discarded warm-up iterations per point.
    pub warmup: usize,
    /// Payload sizes in bytes.
    pub sizes: Vec<usize>,
    /// Transports to measure; empty means all.
    pub only: Vec<TransportKind>,
    /// Output directory (created if missing).
    pub out: PathBuf,
}

impl Options {
    /// The standard options: all transports, the default sizes, quick or full iterations.
    pub fn new(quick: bool, out: PathBuf) -> Self {
        Self {
            iterations: if quick {
                ITERATIONS_QUICK
            } else {
                ITERATIONS_FULL
            },
            warmup: WARMUP,
            sizes: DEFAULT_SIZES.to_vec(),
            only: Vec::new(),
            out,
        }
    }

    fn selected(&self, t: TransportKind) -> bool {
        self.only.is_empty() || self.only.contains(&t)
    }
}

/// The outcome of a benchmark run.
#[derive(Debug, Clone)]
pub struct Report {
    /// Date, language, platform.
    pub info: RunInfo,
    /// Measured iterations per point.
    pub iterations: usize,
    /// Whether the two threads were pinned to CPUs 0 and 1.
    pub pinned: bool,
    /// iceoryx2 and hnav points (`latency.csv`).
    pub shm: Vec<Point>,
    /// uds and tcp points (`latency-sockets.csv`).
    pub sockets: Vec<Point>,
    /// The CSV files written.
    pub files: Vec<PathBuf>,
}

/// Measures every selected point, writes the CSV files and returns the results.
///
/// Points are measured size by size and mode by mode, raw iceoryx2 right before HNAV, so the
/// pair compared in a ratio ran under the same machine conditions.
pub fn run(opts: &Options) -> Result<Report> {
    if opts.sizes.is_empty() || opts.sizes.contains(&0) {
        bail!("sizes must be a non-empty list of positive byte counts");
    }
    std::fs::create_dir_all(&opts.out).with_context(|| format!("create {}", opts.out.display()))?;
    let info = RunInfo::now();
    let run = RunId::unique("bench");
    let measured = measure_all(opts, &run);
    // Remove whatever the run left in /dev/shm, also after a failure.
    let purged = purge_run(&run);
    let mut points = measured?;
    purged.context("purge the benchmark's iceoryx2 resources")?;

    points.sort_by_key(|p| (p.size, p.mode, p.direction, p.transport));
    let (shm, sockets): (Vec<Point>, Vec<Point>) = points
        .into_iter()
        .partition(|p| p.transport.is_shared_memory());
    let mut files = Vec::new();
    for (file, rows) in [("latency.csv", &shm), ("latency-sockets.csv", &sockets)] {
        if !rows.is_empty() {
            let path = opts.out.join(file);
            csv::write(&path, &info, rows)?;
            files.push(path);
        }
    }
    Ok(Report {
        info,
        iterations: opts.iterations,
        pinned: pingpong::pinning_possible(),
        shm,
        sockets,
        files,
    })
}

fn measure_all(opts: &Options, run: &RunId) -> Result<Vec<Point>> {
    let mut points = Vec::new();
    let transports = TransportKind::ALL.into_iter().filter(|&t| opts.selected(t));
    let shm: Vec<_> = transports
        .clone()
        .filter(|t| t.is_shared_memory())
        .collect();
    let sockets: Vec<_> = transports.filter(|t| !t.is_shared_memory()).collect();
    for &size in &opts.sizes {
        for mode in [Mode::Poll, Mode::Event] {
            for &t in shm.iter().chain(&sockets) {
                if t.modes().contains(&mode) {
                    points.extend(measure(opts, run, t, mode, size)?);
                }
            }
        }
    }
    Ok(points)
}

/// Runs one ping-pong and returns its one-way and round-trip points.
fn measure(
    opts: &Options,
    run: &RunId,
    transport: TransportKind,
    mode: Mode,
    size: usize,
) -> Result<[Point; 2]> {
    let what = format!("{}/{} {size} B", transport.name(), mode.name());
    hnav_runtime::errln!(
        "measuring {what}: {} + {} warm-up round trips",
        opts.iterations,
        opts.warmup
    );
    // Every point gets its own services, so nothing of one run can leak into the next.
    let prefix = format!("{}/{}/{size}", transport.name(), mode.name());
    let (w, n) = (opts.warmup, opts.iterations);
    let samples: Samples = match transport {
        TransportKind::Iceoryx2 => run_pair(
            w,
            n,
            |pp| raw::side(pp, Role::Ping, run, &prefix, size, mode),
            |pp| raw::side(pp, Role::Pong, run, &prefix, size, mode),
        ),
        TransportKind::Hnav => run_pair(
            w,
            n,
            |pp| hnav::side(pp, Role::Ping, run, &prefix, size, mode),
            |pp| hnav::side(pp, Role::Pong, run, &prefix, size, mode),
        ),
        TransportKind::Uds => {
            let (a, b) = sockets::uds_pair()?;
            run_pair(
                w,
                n,
                move |pp| sockets::side(pp, Role::Ping, a, size),
                move |pp| sockets::side(pp, Role::Pong, b, size),
            )
        }
        TransportKind::Tcp => {
            let (a, b) = sockets::tcp_pair()?;
            run_pair(
                w,
                n,
                move |pp| sockets::side(pp, Role::Ping, a, size),
                move |pp| sockets::side(pp, Role::Pong, b, size),
            )
        }
    }
    .with_context(|| format!("ping-pong {what}"))?;
    let point = |direction, ns: &[u64]| -> Result<Point> {
        Ok(Point {
            transport,
            mode,
            direction,
            size,
            summary: Summary::from_ns(ns)?,
        })
    };
    Ok([
        point(Direction::OneWay, &samples.oneway)?,
        point(Direction::RoundTrip, &samples.roundtrip)?,
    ])
}
