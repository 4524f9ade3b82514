//! `hnav-bench latency`: how long a sample takes from one thread to another over raw iceoryx2,
//! the HNAV transport, a Unix domain socket, TCP loopback, and the in-process floors (a
//! crossbeam channel and a bare futex wake-up).
//!
//! Method (modelled on iceoryx2's own `benchmark-publish-subscribe`, see
//! `shared/reference/iceoryx2-0.10.md` B.2):
//!
//! - Two threads of one process, each creating its own ports (iceoryx2 `ipc` ports are
//!   `!Send`), pinned to CPUs 0 and 1 when the machine has two, started together.
//! - Ping-pong: Ping stamps the time (ns since a shared [`Instant`](std::time::Instant)) into a
//!   [`Stamp`] header and sends; Pong records `now - stamp` (one-way) and echoes; Ping records
//!   `now - send time` (round trip). One run gives both directions of a point.
//! - Warm-up iterations are discarded, then every one of N iterations is kept: no trimming, no
//!   outlier removal. N is 100,000 per point up to 64 KiB, 10,000 at 1 and 4 MiB (a socket
//!   round trip of 4 MiB takes milliseconds) and 1,000 at 40 MiB; `--quick` takes a twentieth
//!   ([`Options::iterations_for`]). The output says how many each point has.
//! - Payload: a `[u8]` slice service of `size` bytes with the [`Stamp`] user header. It is not
//!   filled per iteration: we measure transfer, not memset.
//! - Modes: [`Mode::Poll`] spins on `receive`; [`Mode::Event`] also notifies and the receiver
//!   blocks until woken: raw iceoryx2 in a WaitSet, HNAV on its one receiver
//!   (`SingleWaiter`; in the general `Waiter` for the opt-in `hnav-waitset` row), sockets in
//!   `read` (`recv` for the opt-in `uds-dgram`), crossbeam in `recv`, the futex in
//!   `FUTEX_WAIT`.
//!
//! Results: `DIR/latency.csv` (every point, dora-benchmark's columns then p99.9 and max),
//! `DIR/latency.md` (the same as a markdown table) and `DIR/latency.svg` (one-way p50 and p99
//! against size, [`plot`]).

mod bridge;
pub mod csv;
mod hnav;
mod inproc;
pub mod peers;
mod pingpong;
pub mod plot;
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

use hnav::Wait;
use pingpong::{run_pair, Role, Samples};

/// Iterations run before measuring: connections, page faults and caches settle.
pub const WARMUP: usize = 1_000;
/// Measured iterations per small point with `--quick`.
pub const ITERATIONS_QUICK: usize = 5_000;
/// Measured iterations per small point of a full run.
pub const ITERATIONS_FULL: usize = 100_000;
/// One MiB.
pub const MIB: usize = 1024 * 1024;
/// Payload sizes measured by default: from a bare stamp to a 40 MiB point cloud, through a
/// small message, a page, a 64 KiB image tile, 1 MiB, and a 1024×1024 `f32` map snapshot.
pub const DEFAULT_SIZES: [usize; 7] = [8, 64, 4096, 65_536, MIB, 4 * MIB, 40 * MIB];

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
    /// A `crossbeam-channel` pair inside one process, moving the payload buffer: the floor
    /// of any handover between threads.
    Crossbeam,
    /// A bare futex wake-up inside one process, no payload: the floor of any blocking
    /// notification.
    Futex,
    /// Zenoh pub/sub over loopback TCP, measured by `bench/peers/zenoh` ([`peers`]).
    Zenoh,
    /// Zenoh with its shared-memory transport, measured by `bench/peers/zenoh`.
    ZenohShm,
    /// dora-rs nodes (node to node over Zenoh, shared memory from 4 KiB), measured by
    /// `bench/peers/dora`.
    Dora,
    /// HNAV between hosts: iceoryx2 → `hnav-bridge` → Zenoh (loopback TCP) → `hnav-bridge` →
    /// iceoryx2, with neural-map payloads (`latency::bridge`). Measured only when named
    /// (`--only hnav-bridge`), at sizes that are whole `f32` maps up to 4 MiB.
    HnavBridge,
    /// The HNAV transport with the receiver in the general `Waiter` (iceoryx2's `WaitSet`), as a
    /// process with several event sources waits; the `hnav` row's receiver waits on its one
    /// source directly (`SingleWaiter`). Event mode only, measured only when named.
    HnavWaitSet,
    /// A Unix datagram socket pair, blocking `recv`: the floor of a wake-up by datagram, which
    /// is how an iceoryx2 event wakes its listener. Measured only when named, up to 64 B.
    UdsDgram,
}

impl TransportKind {
    /// Every transport `hnav-bench latency` measures itself, in the order it measures them.
    pub const ALL: [TransportKind; 6] = [
        Self::Iceoryx2,
        Self::Hnav,
        Self::Uds,
        Self::Tcp,
        Self::Crossbeam,
        Self::Futex,
    ];

    /// The peers measured by their own programs under `bench/peers/`, whose rows
    /// `--peers` reads ([`peers`]): they need toolchains the workspace build does not pay for.
    pub const PEERS: [TransportKind; 3] = [Self::Zenoh, Self::ZenohShm, Self::Dora];

    /// Measured here, but only when named in `--only`: they start Zenoh sessions and
    /// threads of their own, which the default suite does not pay for.
    pub const OPT_IN: [TransportKind; 3] = [Self::HnavBridge, Self::HnavWaitSet, Self::UdsDgram];

    /// The name used in output (`iceoryx2`, `hnav`, `uds`, `tcp`, `crossbeam`, `futex`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Iceoryx2 => "iceoryx2",
            Self::Hnav => "hnav",
            Self::Uds => "uds",
            Self::Tcp => "tcp",
            Self::Crossbeam => "crossbeam",
            Self::Futex => "futex",
            Self::Zenoh => "zenoh",
            Self::ZenohShm => "zenoh-shm",
            Self::Dora => "dora",
            Self::HnavBridge => "hnav-bridge",
            Self::HnavWaitSet => "hnav-waitset",
            Self::UdsDgram => "uds-dgram",
        }
    }

    /// The modes it is measured in: sockets and the futex only block.
    pub fn modes(self) -> &'static [Mode] {
        match self {
            Self::Iceoryx2 | Self::Hnav | Self::Crossbeam => &[Mode::Poll, Mode::Event],
            Self::Uds
            | Self::Tcp
            | Self::Futex
            | Self::Zenoh
            | Self::ZenohShm
            | Self::Dora
            | Self::HnavBridge
            | Self::HnavWaitSet
            | Self::UdsDgram => &[Mode::Event],
        }
    }

    /// Whether it is measured at `size`: the futex moves no payload, so it is measured once,
    /// at the smallest sizes (up to 64 B), as the wake-up reference.
    pub fn measures(self, size: usize) -> bool {
        match self {
            Self::Futex | Self::UdsDgram => size <= 64,
            Self::HnavBridge => size.is_multiple_of(4) && size <= 4 << 20,
            _ => true,
        }
    }
}

impl core::str::FromStr for TransportKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let all = Self::ALL.into_iter().chain(Self::PEERS).chain(Self::OPT_IN);
        all.clone().find(|t| t.name() == s).ok_or_else(|| {
            let names: Vec<&str> = all.map(|t| t.name()).collect();
            format!(
                "unknown transport {s:?} (expected one of {})",
                names.join(", ")
            )
        })
    }
}

/// How the receiver learns that a sample arrived.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Mode {
    /// Busy-loop on `receive` (the benchmark's explicit polling mode).
    Poll,
    /// Block until woken: an iceoryx2 WaitSet (raw), the HNAV `SingleWaiter` or `Waiter`, or a
    /// blocking socket read.
    Event,
}

impl core::str::FromStr for Mode {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "poll" => Ok(Self::Poll),
            "event" => Ok(Self::Event),
            _ => Err(format!("unknown mode {s:?} (expected poll or event)")),
        }
    }
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
    /// Measured iterations per point up to 64 KiB; larger sizes get fewer
    /// ([`Options::iterations_for`]).
    pub iterations: usize,
    /// Discarded warm-up iterations per small point.
    pub warmup: usize,
    /// Payload sizes in bytes.
    pub sizes: Vec<usize>,
    /// Transports to measure; empty means all.
    pub only: Vec<TransportKind>,
    /// Modes to measure; empty means both.
    pub modes: Vec<Mode>,
    /// CSV files of peer rows (`bench/peers/*/run.sh`) to report beside ours.
    pub peers: Vec<PathBuf>,
    /// Output directory (created if missing).
    pub out: PathBuf,
}

impl Options {
    /// The standard options: all transports, the default sizes, quick or full iterations.
    pub fn new(quick: bool, out: PathBuf) -> Self {
        let iterations = if quick {
            ITERATIONS_QUICK
        } else {
            ITERATIONS_FULL
        };
        Self {
            iterations,
            warmup: WARMUP.min(iterations),
            sizes: DEFAULT_SIZES.to_vec(),
            only: Vec::new(),
            modes: Vec::new(),
            peers: Vec::new(),
            out,
        }
    }

    /// Measured iterations at `size`: all of them up to 64 KiB, a tenth from 1 MiB, a
    /// hundredth from 16 MiB — a socket moves 4 MiB in about a millisecond and 40 MiB in ten,
    /// and a full run must stay within minutes. Never fewer than 10.
    pub fn iterations_for(&self, size: usize) -> usize {
        let divisor = match size {
            s if s >= 16 * MIB => 100,
            s if s >= MIB => 10,
            _ => 1,
        };
        (self.iterations / divisor).max(10)
    }

    /// Warm-up iterations at `size`, scaled like the measured ones.
    pub fn warmup_for(&self, size: usize) -> usize {
        (self.warmup * self.iterations_for(size))
            .div_ceil(self.iterations.max(1))
            .max(1)
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
    /// Measured iterations per small point (see [`Options::iterations_for`]).
    pub iterations: usize,
    /// Whether the two threads were pinned to CPUs 0 and 1.
    pub pinned: bool,
    /// Every point, by size, mode, direction and transport.
    pub points: Vec<Point>,
    /// The files written (CSV, markdown, SVG).
    pub files: Vec<PathBuf>,
    /// How long the measurements took.
    pub elapsed: std::time::Duration,
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
    // Read the peers' rows first: a bad file fails before minutes of measuring.
    let mut peer_points = Vec::new();
    for path in &opts.peers {
        peer_points.extend(peers::read(path)?);
    }
    let info = RunInfo::now();
    let run = RunId::unique("bench");
    let started = std::time::Instant::now();
    let measured = measure_all(opts, &run);
    let elapsed = started.elapsed();
    // Remove whatever the run left in /dev/shm, also after a failure.
    let purged = purge_run(&run);
    let mut points = measured?;
    purged.context("purge the benchmark's iceoryx2 resources")?;
    points.extend(peer_points);

    points.sort_by_key(|p| (p.size, p.mode, p.direction, p.transport));
    let csv_path = opts.out.join("latency.csv");
    csv::write(&csv_path, &info, &points)?;
    let md_path = opts.out.join("latency.md");
    let mut report = Report {
        info,
        iterations: opts.iterations,
        pinned: pingpong::pinning_possible(),
        points,
        files: vec![csv_path],
        elapsed,
    };
    std::fs::write(&md_path, report.markdown())
        .with_context(|| format!("write {}", md_path.display()))?;
    report.files.push(md_path);
    let svg_path = opts.out.join("latency.svg");
    plot::write_svg(&svg_path, &report.points)?;
    report.files.push(svg_path);
    Ok(report)
}

fn measure_all(opts: &Options, run: &RunId) -> Result<Vec<Point>> {
    let mut points = Vec::new();
    if let Some(t) = opts.only.iter().find(|t| TransportKind::PEERS.contains(t)) {
        bail!(
            "{} is measured by bench/peers/, not here: pass its rows with --peers",
            t.name()
        );
    }
    let transports: Vec<_> = TransportKind::ALL
        .into_iter()
        .filter(|&t| opts.selected(t))
        .chain(
            TransportKind::OPT_IN
                .into_iter()
                .filter(|t| opts.only.contains(t)),
        )
        .collect();
    let modes = [Mode::Poll, Mode::Event]
        .into_iter()
        .filter(|m| opts.modes.is_empty() || opts.modes.contains(m));
    for &size in &opts.sizes {
        for mode in modes.clone() {
            for &t in &transports {
                if t.modes().contains(&mode) && t.measures(size) {
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
    let (w, n) = (opts.warmup_for(size), opts.iterations_for(size));
    hnav_runtime::errln!("measuring {what}: {n} + {w} warm-up round trips");
    // Every point gets its own services, so nothing of one run can leak into the next.
    let prefix = format!("{}/{}/{size}", transport.name(), mode.name());
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
            |pp| hnav::side(pp, Role::Ping, run, &prefix, size, mode, Wait::Single),
            |pp| hnav::side(pp, Role::Pong, run, &prefix, size, mode, Wait::Single),
        ),
        TransportKind::HnavWaitSet => run_pair(
            w,
            n,
            |pp| hnav::side(pp, Role::Ping, run, &prefix, size, mode, Wait::WaitSet),
            |pp| hnav::side(pp, Role::Pong, run, &prefix, size, mode, Wait::WaitSet),
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
        TransportKind::UdsDgram => {
            let (a, b) = sockets::uds_dgram_pair()?;
            run_pair(
                w,
                n,
                move |pp| sockets::dgram_side(pp, Role::Ping, a, size),
                move |pp| sockets::dgram_side(pp, Role::Pong, b, size),
            )
        }
        TransportKind::Crossbeam => {
            let (a, b) = inproc::crossbeam_pair();
            run_pair(
                w,
                n,
                move |pp| inproc::crossbeam_side(pp, Role::Ping, a, size, mode),
                move |pp| inproc::crossbeam_side(pp, Role::Pong, b, size, mode),
            )
        }
        TransportKind::Futex => {
            let pair = inproc::FutexPair::default();
            run_pair(
                w,
                n,
                |pp| inproc::futex_side(pp, Role::Ping, &pair),
                |pp| inproc::futex_side(pp, Role::Pong, &pair),
            )
        }
        TransportKind::HnavBridge => bridge::measure(run, &prefix, size, w, n),
        TransportKind::Zenoh | TransportKind::ZenohShm | TransportKind::Dora => {
            bail!("{} is measured by bench/peers/, not here", transport.name())
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
