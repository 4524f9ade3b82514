//! A test-only fault layer: every sample that arrives from another host waits a random
//! delay before the bridge takes it in, as if the link were that much slower.
//!
//! This kernel has no `netem`, so the multi-host tests make loss with nftables and delay
//! here. Set [`DELAY_ENV`] (`MEAN_MS:JITTER_MS`, e.g. `5:2` for 3 to 7 ms, uniform) in a
//! bridge's environment; the supervisor passes its own environment on. Each sample's delay
//! is drawn on its own, but no sample overtakes an earlier one (a delayed TCP link does not
//! reorder either), so a delay below the previous sample's release is raised to it.

use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::Sender;
use hnav_runtime::hash::SplitMix64;

/// The environment variable that turns the delay on: `MEAN_MS:JITTER_MS`.
pub const DELAY_ENV: &str = "HNAV_BRIDGE_DELAY_MS";

/// A delay of `mean` ± `jitter`, uniform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Delay {
    /// The mean.
    pub mean: Duration,
    /// The largest deviation from it.
    pub jitter: Duration,
}

impl Delay {
    /// Parses `MEAN_MS:JITTER_MS` (`5:2`) or `MEAN_MS` (no jitter).
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = || format!("{DELAY_ENV}={text:?}: expected MEAN_MS:JITTER_MS, e.g. 5:2");
        let (mean, jitter) = text.split_once(':').unwrap_or((text, "0"));
        let ms = |s: &str| -> Result<f64, String> {
            let v: f64 = s.trim().parse().map_err(|_| bad())?;
            if v.is_finite() && (0.0..=10_000.0).contains(&v) {
                Ok(v)
            } else {
                Err(bad())
            }
        };
        let (mean, jitter) = (ms(mean)?, ms(jitter)?);
        if jitter > mean {
            return Err(format!("{DELAY_ENV}={text:?}: the jitter exceeds the mean"));
        }
        Ok(Self {
            mean: Duration::from_secs_f64(mean / 1e3),
            jitter: Duration::from_secs_f64(jitter / 1e3),
        })
    }

    /// The delay the environment asks for, if any.
    pub fn from_env() -> Result<Option<Self>, String> {
        match std::env::var(DELAY_ENV) {
            Ok(v) if !v.trim().is_empty() => Self::parse(&v).map(Some),
            _ => Ok(None),
        }
    }

    /// One draw, from `rng`.
    fn draw(&self, rng: &mut SplitMix64) -> Duration {
        let span = 2 * self.jitter.as_micros() as u64;
        let low = self.mean.saturating_sub(self.jitter);
        low + Duration::from_micros(if span == 0 { 0 } else { rng.below(span + 1) })
    }
}

/// A thread between the Zenoh callbacks and the bridge's inbox that holds each item for its
/// delay. Ends when every sender into it is dropped.
pub(crate) struct DelayLine {
    thread: Option<JoinHandle<()>>,
}

impl DelayLine {
    /// Starts the thread; returns it and the sender the callbacks put into (with the time of
    /// arrival). What it releases goes to `out`, and `release` runs after each.
    pub(crate) fn start<T: Send + 'static>(
        delay: Delay,
        out: Sender<T>,
        release: impl Fn() + Send + 'static,
    ) -> (Self, Sender<(Instant, T)>) {
        let (tx, rx) = crossbeam_channel::bounded::<(Instant, T)>(4096);
        let thread = std::thread::Builder::new()
            .name("bridge-delay".into())
            .spawn(move || {
                let mut rng = SplitMix64::new(u64::from(std::process::id()));
                let mut last = Instant::now();
                for (arrived, item) in rx {
                    let at = (arrived + delay.draw(&mut rng)).max(last);
                    last = at;
                    std::thread::sleep(at.saturating_duration_since(Instant::now()));
                    if out.send(item).is_err() {
                        return;
                    }
                    release();
                }
            })
            .ok();
        (Self { thread }, tx)
    }
}

impl Drop for DelayLine {
    fn drop(&mut self) {
        // Its senders are gone by now (the subscribers are dropped first), so it ends.
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_delay_parses_and_bad_ones_are_refused() {
        let d = Delay::parse("5:2").unwrap();
        assert_eq!(d.mean, Duration::from_millis(5));
        assert_eq!(d.jitter, Duration::from_millis(2));
        assert_eq!(Delay::parse("3").unwrap().jitter, Duration::ZERO);
        assert!(Delay::parse("2:5").unwrap_err().contains("jitter exceeds"));
        assert!(Delay::parse("x:1")
            .unwrap_err()
            .contains("MEAN_MS:JITTER_MS"));
        assert!(Delay::parse("-1").is_err());
    }

    #[test]
    fn items_wait_their_delay_and_keep_their_order() {
        let (out, got) = crossbeam_channel::unbounded();
        let delay = Delay::parse("5:2").unwrap();
        let (line, tx) = DelayLine::start(delay, out, || {});
        let t0 = Instant::now();
        for i in 0..50 {
            tx.send((Instant::now(), i)).unwrap();
        }
        drop(tx);
        drop(line);
        let items: Vec<i32> = got.try_iter().collect();
        assert_eq!(items, (0..50).collect::<Vec<_>>());
        assert!(
            t0.elapsed() >= Duration::from_millis(3),
            "{:?}",
            t0.elapsed()
        );
    }
}
