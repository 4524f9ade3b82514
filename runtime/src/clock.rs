//! One clock every process of a machine agrees on.
//!
//! `std::time::Instant` cannot be compared across processes, and the wall clock can jump.
//! `CLOCK_MONOTONIC` is shared by every process of one host and never jumps, so a time taken
//! by the supervisor (a fault's signal, a restart) and one taken by an observer (the `Down`
//! it received, a restarted agent's first candidate) can be subtracted: that is how the chaos
//! campaign measures detection and recovery.

/// Nanoseconds of `CLOCK_MONOTONIC`: comparable between the processes of one host.
pub fn monotonic_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call, and
    // CLOCK_MONOTONIC is supported on every Linux; the call cannot fail with these arguments.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    (ts.tv_sec as u64) * 1_000_000_000 + ts.tv_nsec as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_runs_forward_with_instant() {
        let a = monotonic_ns();
        std::thread::sleep(std::time::Duration::from_millis(2));
        let b = monotonic_ns();
        assert!(b >= a + 2_000_000, "{a} -> {b}");
    }
}
