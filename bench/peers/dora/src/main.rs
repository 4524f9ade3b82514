//! `hnav-peer-dora`: dora-rs node-to-node latency measured with the method of HNAV's own
//! latency suite (`hnav-bench latency`, `bench/src/latency/` in the main workspace), written as
//! rows of HNAV's `latency.csv` so `hnav-bench latency --peers FILE` can show dora beside
//! iceoryx2.
//!
//! One binary, two dora nodes (`dataflow.yml`): `hnav-peer-dora ping` and `hnav-peer-dora pong`.
//!
//! - Ping sends, for each size, warm-up + N messages on `data`: a 16-byte header (`stamp_ns`
//!   u64 LE, CLOCK_MONOTONIC ns, then `seq` u64 LE) followed by `size` payload bytes, written
//!   straight into a dora sample (`send_output_raw`: shared memory at and above dora's
//!   zero-copy threshold). It waits for each echo and records the round trip.
//! - Pong records one-way = now − stamp (both processes read the same system-wide
//!   CLOCK_MONOTONIC) and echoes a message of the same length carrying the received header.
//! - After the last echo of a size, Ping sends `control` = "flush"; Pong answers on `samples`
//!   with every one-way latency of that size (u64 LE), and Ping drops the warm-up ones.
//!   Every step is causally ordered (each message is sent only after the one it answers
//!   arrived), so dora's per-input scheduling cannot reorder anything.
//! - Ping writes the CSV (`HNAV_DORA_OUT`). Both sides check `seq`: a lost or reordered
//!   message fails the run, and a missing echo fails it after a timeout.
//!
//! Configuration comes from the environment (the nodes inherit `dora run`'s):
//! `HNAV_DORA_OUT` (CSV path, required by ping), `HNAV_DORA_QUICK=yes` (N = 5,000),
//! `HNAV_DORA_SIZES` (comma separated payload bytes).

// HNAV's own summary statistics, compiled in from the workspace so that a peer row and an
// HNAV row are summarised by the same code (this project stays outside the workspace, so it
// cannot depend on hnav-bench without building iceoryx2 and the rest).
#[allow(dead_code)]
#[path = "../../../src/latency/stats.rs"]
mod stats;

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, ensure, Context, Result};
use dora_node_api::dora_core::config::DataId;
use dora_node_api::{DoraNode, Event, EventStream, MetadataParameters};
use tracing_subscriber::filter::Targets;

use stats::Summary;

/// HNAV's CSV header (`bench/src/latency/csv.rs`): dora-benchmark's columns, then the tail.
const HEADER: &str =
    "date,language,platform,name,size_bytes,avg_us,p50_us,p90_us,p99_us,n,p999_us,max_us";
/// Measured iterations per small point, as HNAV: full run and `--quick`.
const ITERATIONS_FULL: usize = 100_000;
const ITERATIONS_QUICK: usize = 5_000;
/// Warm-up iterations per small point, discarded.
const WARMUP: usize = 1_000;
const MIB: usize = 1024 * 1024;
/// HNAV's default sizes: 8 B to a 40 MiB point cloud.
const DEFAULT_SIZES: [usize; 7] = [8, 64, 4096, 65_536, MIB, 4 * MIB, 40 * MIB];
/// The stamp header in front of every payload: `stamp_ns` and `seq`, u64 LE each.
const HEADER_LEN: usize = 16;
/// The dora version this is built against; run.sh installs the same CLI/daemon.
const DORA_VERSION: &str = "1.1.0";
/// How long Ping waits for any one answer before it declares the message lost (see
/// [`Watchdog`]).
const ANSWER_TIMEOUT: Duration = Duration::from_secs(20);
/// The `control` message that asks Pong for the one-way samples of the size just measured.
const FLUSH: &[u8] = b"flush";

/// Iterations at `size`, HNAV's `Options::iterations_for`: all up to 64 KiB, a tenth from
/// 1 MiB, a hundredth from 16 MiB, never fewer than 10.
fn iterations_for(iterations: usize, size: usize) -> usize {
    let divisor = match size {
        s if s >= 16 * MIB => 100,
        s if s >= MIB => 10,
        _ => 1,
    };
    (iterations / divisor).max(10)
}

/// Warm-up at `size`, HNAV's `Options::warmup_for`: scaled like the measured ones, at least 1.
fn warmup_for(iterations: usize, size: usize) -> usize {
    let warmup = WARMUP.min(iterations);
    let scale = iterations_for(iterations, size) as f64 / iterations.max(1) as f64;
    ((warmup as f64 * scale).ceil() as usize).max(1)
}

/// CLOCK_MONOTONIC in ns: one clock for every process of the host, so Pong can subtract
/// Ping's stamp.
#[inline]
fn now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; CLOCK_MONOTONIC always exists on Linux.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    debug_assert_eq!(rc, 0);
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

fn write_header(buf: &mut [u8], stamp_ns: u64, seq: u64) {
    buf[..8].copy_from_slice(&stamp_ns.to_le_bytes());
    buf[8..HEADER_LEN].copy_from_slice(&seq.to_le_bytes());
}

fn read_header(buf: &[u8]) -> Result<(u64, u64)> {
    ensure!(
        buf.len() >= HEADER_LEN,
        "message of {} bytes has no {HEADER_LEN}-byte header",
        buf.len()
    );
    let stamp = u64::from_le_bytes(buf[..8].try_into().expect("8 bytes"));
    let seq = u64::from_le_bytes(buf[8..HEADER_LEN].try_into().expect("8 bytes"));
    Ok((stamp, seq))
}

/// The bytes of an input: dora delivers `send_output_raw` payloads as an Arrow `UInt8`
/// array, borrowed here without a copy.
fn bytes_of(data: &dora_node_api::DoraArray) -> Result<&[u8]> {
    <&[u8]>::try_from(data).map_err(|e| anyhow!("input is not a UInt8 array: {e}"))
}

/// Pins the calling thread (only it: dora's and zenoh's threads already exist and stay
/// unpinned) to `cpu`, as HNAV pins its two sides to CPUs 0 and 1 when there are two.
fn pin_to(cpu: usize) -> bool {
    if std::thread::available_parallelism().map_or(1, |n| n.get()) < 2 {
        return false;
    }
    // SAFETY: a zeroed cpu_set_t is a valid empty set; CPU_SET writes within it; pid 0 is
    // the calling thread.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) == 0
    }
}

/// Switches dora's log level (its log lines go to stderr, which `dora run` shows).
type LogLevel = tracing_subscriber::reload::Handle<Targets, tracing_subscriber::Registry>;

/// Prints dora's log lines to stderr: warnings always; during `init`, also the node API's
/// debug lines, which say which path each output settled on ("startup handshake complete;
/// output takes the direct zenoh path", or a warning that it stays on the daemon path).
/// [`quiet_after_init`] drops back to warnings, because at debug level the node API logs
/// three lines per message.
fn init_logging() -> Option<LogLevel> {
    use tracing_subscriber::prelude::*;
    let (filter, handle) = tracing_subscriber::reload::Layer::new(
        Targets::new()
            .with_target("dora_node_api", tracing::Level::DEBUG)
            .with_default(tracing::Level::WARN),
    );
    let layer = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_ansi(false)
        .event_format(Plain);
    tracing_subscriber::registry()
        .with(filter)
        .with(layer)
        .try_init()
        .ok()
        .map(|()| handle)
}

/// `LEVEL target: message fields`, one line: without the span context, which for dora's
/// `init` is the whole node configuration.
struct Plain;

impl<S, N> tracing_subscriber::fmt::FormatEvent<S, N> for Plain
where
    S: tracing::Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>,
    N: for<'a> tracing_subscriber::fmt::FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &tracing_subscriber::fmt::FmtContext<'_, S, N>,
        mut writer: tracing_subscriber::fmt::format::Writer<'_>,
        event: &tracing::Event<'_>,
    ) -> std::fmt::Result {
        let meta = event.metadata();
        write!(writer, "{} {}: ", meta.level(), meta.target())?;
        ctx.field_format().format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}

fn quiet_after_init(log: &Option<LogLevel>) {
    if let Some(handle) = log {
        let _ = handle.modify(|f| *f = Targets::new().with_default(tracing::Level::WARN));
    }
}

/// Which buffers are shared memory: the address ranges of this process's `/dev/shm`
/// mappings, re-read from `/proc/self/maps` only when an address is in none of them (a new
/// segment, or a heap buffer). Tells, per message, whether dora used its zenoh SHM pool.
#[derive(Default)]
struct ShmRanges(Vec<(usize, usize)>);

impl ShmRanges {
    fn contains(&mut self, ptr: *const u8) -> bool {
        let addr = ptr as usize;
        let known = |r: &[(usize, usize)]| r.iter().any(|&(lo, hi)| (lo..hi).contains(&addr));
        if known(&self.0) {
            return true;
        }
        self.0 = shm_mappings();
        known(&self.0)
    }
}

fn shm_mappings() -> Vec<(usize, usize)> {
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap_or_default();
    maps.lines()
        .filter_map(|line| {
            let mut cols = line.split_whitespace();
            let (lo, hi) = cols.next()?.split_once('-')?;
            let path = cols.nth(4)?;
            path.starts_with("/dev/shm/").then_some(())?;
            Some((
                usize::from_str_radix(lo, 16).ok()?,
                usize::from_str_radix(hi, 16).ok()?,
            ))
        })
        .collect()
}

/// `<os>-<arch>-<n>cpu`, as HNAV.
fn platform() -> String {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!(
        "{}-{}-{cpus}cpu",
        std::env::consts::OS,
        std::env::consts::ARCH
    )
}

/// The current UTC time as ISO 8601 seconds (`2026-12-03T07:00:00Z`).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_iso(secs)
}

/// Seconds since the Unix epoch as ISO 8601 UTC (days to civil date: H. Hinnant's algorithm).
fn utc_iso(secs: u64) -> String {
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// What Ping measures, from the environment.
struct Config {
    out: PathBuf,
    quick: bool,
    sizes: Vec<usize>,
}

impl Config {
    fn from_env() -> Result<Self> {
        let out = std::env::var_os("HNAV_DORA_OUT")
            .map(PathBuf::from)
            .context("HNAV_DORA_OUT (the CSV file to write) is not set")?;
        let quick = match std::env::var("HNAV_DORA_QUICK").as_deref() {
            Ok("yes") => true,
            Ok("no") | Ok("") | Err(_) => false,
            Ok(other) => bail!("HNAV_DORA_QUICK={other:?}: expected yes or no"),
        };
        let sizes = match std::env::var("HNAV_DORA_SIZES") {
            Ok(s) if !s.trim().is_empty() => s
                .split(',')
                .map(|v| {
                    v.trim()
                        .parse::<usize>()
                        .with_context(|| format!("HNAV_DORA_SIZES: {v:?} is not a byte count"))
                })
                .collect::<Result<Vec<_>>>()?,
            _ => DEFAULT_SIZES.to_vec(),
        };
        ensure!(
            !sizes.is_empty() && !sizes.contains(&0),
            "HNAV_DORA_SIZES must be a non-empty list of positive byte counts"
        );
        Ok(Self { out, quick, sizes })
    }
}

/// One measured row.
struct Row {
    name: &'static str,
    size: usize,
    summary: Summary,
}

/// The next input event, failing on a stop or anything unexpected. Blocks without a
/// timeout: dora's `recv_timeout` arms a `futures-timer` delay per call (a wake-up of the
/// timer thread), which would be part of every measured round trip; the [`Watchdog`] catches
/// a lost message instead.
fn next_input(
    events: &mut EventStream,
    waiting_for: &str,
) -> Result<(DataId, dora_node_api::DoraArray)> {
    loop {
        match events.recv() {
            Some(Event::Input { id, data, .. }) => return Ok((id, data)),
            Some(Event::Error(e)) => bail!("while waiting for {waiting_for}: {e}"),
            Some(Event::Stop(cause)) => {
                bail!("stopped ({cause:?}) while waiting for {waiting_for}")
            }
            Some(Event::InputClosed { id }) => {
                bail!("input {id} closed while waiting for {waiting_for}")
            }
            Some(Event::NodeFailed {
                error,
                source_node_id,
                ..
            }) => {
                bail!("node {source_node_id} failed while waiting for {waiting_for}: {error}")
            }
            Some(_) => continue,
            None => bail!("event stream closed while waiting for {waiting_for}"),
        }
    }
}

/// Fails the run when Ping hears nothing back for [`ANSWER_TIMEOUT`]: a lost message would
/// otherwise block `recv` forever. The hot path only stores two relaxed atomics.
#[derive(Clone, Default)]
struct Watchdog(Arc<(AtomicU64, AtomicU64)>);

impl Watchdog {
    /// Starts the watching thread (call before pinning, so it is not pinned).
    fn start() -> Self {
        let dog = Self::default();
        let watched = dog.clone();
        std::thread::spawn(move || {
            let (mut last, mut since) = (u64::MAX, Instant::now());
            loop {
                std::thread::sleep(Duration::from_millis(500));
                let (size, seq) = (watched.0 .0.load(Relaxed), watched.0 .1.load(Relaxed));
                let now = size.wrapping_mul(1_000_003) ^ seq;
                if now != last {
                    (last, since) = (now, Instant::now());
                } else if since.elapsed() >= ANSWER_TIMEOUT {
                    eprintln!(
                        "Error: no answer from pong for {} s at size {size} B, message {seq} \
                         (a message was lost)",
                        ANSWER_TIMEOUT.as_secs()
                    );
                    std::process::exit(1);
                }
            }
        });
        dog
    }

    /// Ping is now waiting on message `seq` of `size` bytes.
    #[inline]
    fn at(&self, size: usize, seq: u64) {
        self.0 .0.store(size as u64, Relaxed);
        self.0 .1.store(seq, Relaxed);
    }
}

fn ping(log: Option<LogLevel>) -> Result<()> {
    let cfg = Config::from_env()?;
    // Before pinning: the CPU count is the process's, not the pinned thread's.
    let (date, platform) = (utc_now(), platform());
    let (mut node, mut events) = DoraNode::init_from_env().map_err(|e| anyhow!("{e:?}"))?;
    quiet_after_init(&log);
    let watchdog = Watchdog::start();
    let pinned = pin_to(0);
    let threshold = node.zero_copy_threshold();
    let (data_out, control_out) = (
        DataId::from("data".to_owned()),
        DataId::from("control".to_owned()),
    );
    let iterations = if cfg.quick {
        ITERATIONS_QUICK
    } else {
        ITERATIONS_FULL
    };
    let started = Instant::now();
    let mut rows = Vec::new();
    let mut paths = Vec::new();
    let mut shm = ShmRanges::default();
    for &size in &cfg.sizes {
        let (w, n) = (
            warmup_for(iterations, size),
            iterations_for(iterations, size),
        );
        eprintln!("measuring dora/event {size} B: {n} + {w} warm-up round trips");
        let len = HEADER_LEN + size;
        // Every message at or above dora's zero-copy threshold is checked to be written into
        // shared memory (a range compare); below it only the first one (reading
        // /proc/self/maps costs tens of µs).
        let check_all = len >= threshold;
        let (mut checked, mut in_shm) = (0u64, 0u64);
        let mut roundtrip = Vec::with_capacity(n);
        for i in 0..w + n {
            let seq = i as u64;
            watchdog.at(size, seq);
            let sent = now_ns();
            // dora's zero-copy send: at and above the threshold the sample is allocated from
            // the node's zenoh SHM pool and we write the header straight into it. The payload
            // is not filled: we measure transfer, not memset (as HNAV does).
            node.send_output_raw(
                data_out.clone(),
                MetadataParameters::default(),
                len,
                |buf| {
                    write_header(buf, sent, seq);
                    if check_all || i == 0 {
                        checked += 1;
                        in_shm += u64::from(shm.contains(buf.as_ptr()));
                    }
                },
            )
            .map_err(|e| anyhow!("send {size} B #{seq}: {e:?}"))?;
            let (id, data) = next_input(&mut events, &format!("echo {seq} of {size} B"))?;
            let back = now_ns();
            ensure!(
                id.as_str() == "echo",
                "expected the echo {seq} of {size} B, got input {id}"
            );
            let bytes = bytes_of(&data)?;
            let (_, echo_seq) = read_header(bytes)?;
            if echo_seq != seq {
                bail!("ping expected echo {seq} of {size} B, got {echo_seq} (a message was lost)");
            }
            ensure!(
                bytes.len() == len,
                "echo of {} bytes, expected {len}",
                bytes.len()
            );
            if i >= w {
                roundtrip.push(back - sent);
            }
        }
        node.send_output_bytes(
            control_out.clone(),
            MetadataParameters::default(),
            FLUSH.len(),
            FLUSH,
        )
        .map_err(|e| anyhow!("send flush: {e:?}"))?;
        watchdog.at(size, u64::MAX);
        let (id, data) = next_input(&mut events, &format!("the one-way samples of {size} B"))?;
        ensure!(
            id.as_str() == "samples",
            "expected the one-way samples, got input {id}"
        );
        let bytes = bytes_of(&data)?;
        ensure!(
            bytes.len() % 8 == 0 && bytes.len() >= 16,
            "samples message of {} bytes",
            bytes.len()
        );
        let mut oneway: Vec<u64> = bytes
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        // Pong's first two values: how many messages it checked and how many of those it
        // received in shared memory.
        let (pong_checked, pong_shm) = (oneway[0], oneway[1]);
        let mut oneway = oneway.split_off(2);
        ensure!(
            oneway.len() == w + n,
            "pong reports {} one-way samples of {size} B, expected {}",
            oneway.len(),
            w + n
        );
        let oneway = oneway.split_off(w);
        paths.push(format!(
            "{size} B: ping wrote {in_shm} of {checked} checked messages into shared memory, \
             pong received {pong_shm} of {pong_checked} checked in shared memory"
        ));
        rows.push(Row {
            name: "dora/event/oneway",
            size,
            summary: Summary::from_ns(&oneway)?,
        });
        rows.push(Row {
            name: "dora/event/roundtrip",
            size,
            summary: Summary::from_ns(&roundtrip)?,
        });
    }

    let mut csv = String::from(HEADER);
    csv.push('\n');
    for r in &rows {
        let s = &r.summary;
        csv.push_str(&format!(
            "{date},Rust,{platform},{},{},{:.3},{:.3},{:.3},{:.3},{},{:.3},{:.3}\n",
            r.name,
            r.size,
            s.mean_us(),
            s.p50_us(),
            s.p90_us(),
            s.p99_us(),
            s.n,
            s.p999_us(),
            s.max_us()
        ));
    }
    if let Some(dir) = cfg.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("create {}", dir.display()))?;
    }
    std::fs::write(&cfg.out, csv).with_context(|| format!("write {}", cfg.out.display()))?;
    let mut err = std::io::stderr().lock();
    writeln!(
        err,
        "dora {DORA_VERSION} latency, {platform}, {date} ({}), main threads {}pinned, \
         zero-copy threshold {threshold} B, {:.1} s",
        if cfg.quick { "quick" } else { "full" },
        if pinned { "" } else { "not " },
        started.elapsed().as_secs_f64()
    )?;
    for p in &paths {
        writeln!(err, "  {p}")?;
    }
    writeln!(err, "wrote {}", cfg.out.display())?;
    Ok(())
}

fn pong(log: Option<LogLevel>) -> Result<()> {
    let (mut node, mut events) = DoraNode::init_from_env().map_err(|e| anyhow!("{e:?}"))?;
    quiet_after_init(&log);
    pin_to(1);
    let threshold = node.zero_copy_threshold();
    let (echo_out, samples_out) = (
        DataId::from("echo".to_owned()),
        DataId::from("samples".to_owned()),
    );
    // Slots 0 and 1: messages checked for shared memory and how many were, then one one-way
    // latency per message, warm-up included (Ping drops those).
    let fresh = || {
        let mut v = Vec::with_capacity(ITERATIONS_FULL + WARMUP + 2);
        v.extend([0, 0]);
        v
    };
    let mut oneway: Vec<u64> = fresh();
    let mut shm = ShmRanges::default();
    let mut expected: u64 = 0;
    let mut len = 0;
    while let Some(event) = events.recv() {
        let (id, data) = match event {
            Event::Input { id, data, .. } => (id, data),
            Event::Stop(_) => break,
            Event::Error(e) => bail!("dora error: {e}"),
            _ => continue,
        };
        match id.as_str() {
            "data" => {
                let arrived = now_ns();
                let bytes = bytes_of(&data)?;
                let (stamp, seq) = read_header(bytes)?;
                if seq != expected {
                    bail!("pong expected message {expected}, got {seq} (a message was lost)");
                }
                if seq == 0 {
                    len = bytes.len();
                } else {
                    ensure!(
                        bytes.len() == len,
                        "message {seq} has {} bytes, expected {len}",
                        bytes.len()
                    );
                }
                oneway.push(arrived.saturating_sub(stamp));
                expected += 1;
                let mut header = [0u8; HEADER_LEN];
                header.copy_from_slice(&bytes[..HEADER_LEN]);
                if len >= threshold || seq == 0 {
                    oneway[0] += 1;
                    oneway[1] += u64::from(shm.contains(bytes.as_ptr()));
                }
                // Release the received sample before echoing, so its SHM chunk returns to
                // Ping's pool.
                drop(data);
                // The echo: a message of the same length carrying the received header,
                // written into a fresh sample; the payload is not copied (HNAV's own pong
                // does the same: it loans a new sample and writes only the header).
                node.send_output_raw(
                    echo_out.clone(),
                    MetadataParameters::default(),
                    len,
                    |buf| buf[..HEADER_LEN].copy_from_slice(&header),
                )
                .map_err(|e| anyhow!("echo #{seq}: {e:?}"))?;
            }
            "control" => {
                ensure!(bytes_of(&data)? == FLUSH, "unknown control message");
                let out = std::mem::replace(&mut oneway, fresh());
                node.send_output_raw(
                    samples_out.clone(),
                    MetadataParameters::default(),
                    out.len() * 8,
                    |buf| {
                        for (c, v) in buf.chunks_exact_mut(8).zip(&out) {
                            c.copy_from_slice(&v.to_le_bytes());
                        }
                    },
                )
                .map_err(|e| anyhow!("send samples: {e:?}"))?;
                expected = 0;
            }
            other => bail!("unexpected input {other}"),
        }
    }
    Ok(())
}

fn main() -> Result<()> {
    let log = init_logging();
    match std::env::args().nth(1).as_deref() {
        Some("ping") => ping(log),
        Some("pong") => pong(log),
        _ => bail!("usage: hnav-peer-dora ping|pong (run as a dora node, see dataflow.yml)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iterations_follow_hnav() {
        let q = ITERATIONS_QUICK;
        assert_eq!(
            [8, 65_536, MIB, 4 * MIB, 40 * MIB].map(|s| iterations_for(q, s)),
            [5000, 5000, 500, 500, 50]
        );
        assert_eq!(
            [8, MIB, 40 * MIB].map(|s| warmup_for(q, s)),
            [1000, 100, 10]
        );
        let f = ITERATIONS_FULL;
        assert_eq!(
            [8, MIB, 40 * MIB].map(|s| iterations_for(f, s)),
            [100_000, 10_000, 1_000]
        );
        assert_eq!(
            [8, MIB, 40 * MIB].map(|s| warmup_for(f, s)),
            [1000, 100, 10]
        );
        assert_eq!(iterations_for(500, 40 * MIB), 10);
    }

    #[test]
    fn dates_are_iso_utc() {
        assert_eq!(utc_iso(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_iso(1_796_281_200), "2026-12-03T07:00:00Z");
        assert_eq!(utc_iso(951_782_400), "2000-02-29T00:00:00Z");
    }

    #[test]
    fn header_round_trips() {
        let mut buf = [0u8; 24];
        write_header(&mut buf, 123_456_789, 42);
        assert_eq!(read_header(&buf).unwrap(), (123_456_789, 42));
        assert!(read_header(&buf[..15]).is_err());
    }

    #[test]
    fn monotonic_clock_moves_forward() {
        let a = now_ns();
        let b = now_ns();
        assert!(b >= a && a > 0);
    }
}
