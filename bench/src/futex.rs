//! The bare Linux futex: the least a blocking wake-up can cost, used by the benchmarks as the
//! floor the other mechanisms are read against (`latency`'s `futex` rows, `fanout`'s).
//!
//! Private futexes (`FUTEX_PRIVATE_FLAG`): both sides are threads of one process.

use std::sync::atomic::AtomicU32;
use std::time::Duration;

/// `FUTEX_WAIT` on `word` while it holds `expected`, at most `timeout`. Returns when the word
/// moved, a wake-up came, the timeout passed or a signal arrived: the caller looks again.
pub fn wait(word: &AtomicU32, expected: u32, timeout: Duration) -> std::io::Result<()> {
    let timeout = libc::timespec {
        tv_sec: timeout.as_secs() as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: `word` is a live, aligned 32-bit atomic for the whole call (borrowed), the
    // timeout points at a local `timespec`, and FUTEX_WAIT_PRIVATE reads the word only.
    let r = unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAIT | libc::FUTEX_PRIVATE_FLAG,
            expected,
            &timeout as *const libc::timespec,
        )
    };
    if r == -1 {
        let e = std::io::Error::last_os_error();
        // EAGAIN: the word had already moved; EINTR/ETIMEDOUT: look again.
        match e.raw_os_error() {
            Some(libc::EAGAIN | libc::EINTR | libc::ETIMEDOUT) => {}
            _ => return Err(e),
        }
    }
    Ok(())
}

/// `FUTEX_WAKE` up to `waiters` threads blocked on `word` (`i32::MAX`: all of them).
pub fn wake(word: &AtomicU32, waiters: i32) {
    // SAFETY: `word` is a live, aligned 32-bit atomic; FUTEX_WAKE_PRIVATE does not access
    // memory beyond looking up the waiters of its address.
    unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAKE | libc::FUTEX_PRIVATE_FLAG,
            waiters,
        );
    }
}
