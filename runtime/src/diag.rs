//! Printing that never panics: the one way HNAV's binaries write to stdout and stderr.
//!
//! `println!` and `eprintln!` panic when the write fails, and a process's output is a file
//! in the run directory (`DIR/logs/<node>.log`): on a full disk every process would die with
//! exit code 101 while trying to say why it stops, and its log would stay empty. The macros
//! here ([`outln!`](crate::outln), [`out!`](crate::out), [`errln!`](crate::errln)) and the
//! `tracing` writer ([`StderrWriter`]) drop a failed write instead, count it
//! ([`failed_writes`]) and remember whether the disk was full ([`no_space_seen`]), so that
//! [`process_main`](crate::launch::process_main) can still exit with
//! [`EXIT_NO_SPACE`](crate::launch::EXIT_NO_SPACE) when its error could not be printed.

use std::error::Error;
use std::fmt;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

static FAILED_WRITES: AtomicU64 = AtomicU64::new(0);
static NO_SPACE: AtomicBool = AtomicBool::new(false);

/// Which standard stream to write to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// Standard output: results (tables, JSON).
    Stdout,
    /// Standard error: diagnostics.
    Stderr,
}

/// Writes `args` (and a newline if `newline`) to `stream` in one write; returns whether it
/// was written. A failure is counted, never raised.
pub fn write(stream: Stream, args: fmt::Arguments<'_>, newline: bool) -> bool {
    let mut text = fmt::format(args);
    if newline {
        text.push('\n');
    }
    let result = match stream {
        Stream::Stdout => {
            let mut out = io::stdout().lock();
            out.write_all(text.as_bytes()).and_then(|()| out.flush())
        }
        Stream::Stderr => io::stderr().lock().write_all(text.as_bytes()),
    };
    match result {
        Ok(()) => true,
        Err(e) => {
            record_failure(&e);
            false
        }
    }
}

fn record_failure(e: &io::Error) {
    FAILED_WRITES.fetch_add(1, Ordering::Relaxed);
    if is_no_space_io(e) {
        NO_SPACE.store(true, Ordering::Relaxed);
    }
}

/// Writes that failed since the process started.
pub fn failed_writes() -> u64 {
    FAILED_WRITES.load(Ordering::Relaxed)
}

/// Whether a write to stdout or stderr failed because the disk was full.
pub fn no_space_seen() -> bool {
    NO_SPACE.load(Ordering::Relaxed)
}

/// Whether `e` is "no space left on device" (ENOSPC, or EDQUOT: a full quota is as final).
pub fn is_no_space_io(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::StorageFull | io::ErrorKind::QuotaExceeded
    )
}

/// Whether `e` or any error in its `source()` chain is "no space left on device".
pub fn is_no_space(e: &(dyn Error + 'static)) -> bool {
    let mut next = Some(e);
    while let Some(err) = next {
        if err.downcast_ref::<io::Error>().is_some_and(is_no_space_io) {
            return true;
        }
        next = err.source();
    }
    false
}

/// The stderr writer of the `tracing` subscriber ([`crate::logging::init`]): a failed write
/// is counted and reported as written, so the subscriber neither panics nor reports it.
#[derive(Clone, Copy, Debug, Default)]
pub struct StderrWriter;

impl Write for StderrWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if let Err(e) = io::stderr().lock().write_all(buf) {
            record_failure(&e);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// `println!` that never panics: a failed write to stdout is counted and dropped.
#[macro_export]
macro_rules! outln {
    () => {
        {
            $crate::diag::write($crate::diag::Stream::Stdout, format_args!(""), true);
        }
    };
    ($($arg:tt)*) => {
        {
            $crate::diag::write($crate::diag::Stream::Stdout, format_args!($($arg)*), true);
        }
    };
}

/// `print!` that never panics: a failed write to stdout is counted and dropped.
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        {
            $crate::diag::write($crate::diag::Stream::Stdout, format_args!($($arg)*), false);
        }
    };
}

/// `eprintln!` that never panics: a failed write to stderr is counted and dropped.
#[macro_export]
macro_rules! errln {
    () => {
        {
            $crate::diag::write($crate::diag::Stream::Stderr, format_args!(""), true);
        }
    };
    ($($arg:tt)*) => {
        {
            $crate::diag::write($crate::diag::Stream::Stderr, format_args!($($arg)*), true);
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("writing the thing")]
    struct Outer(#[source] io::Error);

    #[test]
    fn no_space_is_found_anywhere_in_the_chain() {
        let full = io::Error::from_raw_os_error(28);
        assert!(is_no_space_io(&full));
        let outer = Outer(full);
        assert!(is_no_space(&outer));
        let boxed: Box<dyn Error> = Box::new(outer);
        assert!(is_no_space(boxed.as_ref()));
        let other = Outer(io::Error::from_raw_os_error(13));
        assert!(!is_no_space(&other));
    }
}
