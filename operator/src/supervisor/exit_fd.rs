//! A file descriptor that becomes readable the instant a child process exits.
//!
//! The supervisor already sleeps in its [`Waiter`](hnav_runtime::transport::Waiter) (iceoryx2's
//! `WaitSet` underneath) for lifecycle messages; a child's exit must wake that same wait, or the supervisor would have
//! to poll `waitpid` on a timer (late by up to a tick, and awake for nothing in between).
//! The WaitSet multiplexes anything that is [`SynchronousMultiplexing`], so an [`ExitFd`]
//! implements that trait around one of two descriptors:
//!
//! * **pidfd** (Linux ≥ 5.3, [`WatchMode::Pidfd`]): `pidfd_open(2)` on the child. The kernel
//!   marks it readable when the process has exited (zombie or reaped). Nothing else runs.
//! * **waiter thread** ([`WatchMode::WaiterThread`], the fallback when `pidfd_open` returns
//!   `ENOSYS`): a pipe whose write end belongs to one small thread blocked in
//!   `waitid(P_PID, pid, WEXITED | WNOWAIT)`. When the child exits the thread returns and
//!   closes the write end, so the read end reports end-of-file, i.e. readable. `WNOWAIT`
//!   leaves the child waitable, so reaping (and its exit status) stays with
//!   [`Child::try_reap`](super::child::Child::try_reap). The thread blocks in the kernel; it
//!   does not poll. A SIGCHLD handler or `signalfd` was not chosen because both need
//!   process-wide signal state that a library must not take over.
//!
//! Both stay readable once the child has exited (the pipe keeps reporting end-of-file, the
//! pidfd keeps reporting the exit): level-triggered, so a wake-up is never lost, but a
//! waiter attachment must be dropped once its child is handled or every wait returns at once.

use std::io;
use std::os::fd::{BorrowedFd, FromRawFd, IntoRawFd, OwnedFd, RawFd};
use std::time::{Duration, Instant};

use iceoryx2_bb_posix::file_descriptor::{FileDescriptor, FileDescriptorBased};
use iceoryx2_bb_posix::file_descriptor_set::SynchronousMultiplexing;
use nix::errno::Errno;
use nix::sys::wait::{waitid, Id, WaitPidFlag};
use nix::unistd::Pid;

/// How an [`ExitFd`] learns about the exit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WatchMode {
    /// A pidfd if the kernel has `pidfd_open`, else a waiter thread.
    Auto,
    /// Only a pidfd; fails if the kernel has none.
    Pidfd,
    /// A pipe closed by a thread blocked in `waitid` (the fallback; selectable for tests).
    WaiterThread,
}

/// Readable once the watched child has exited; a [`Waiter`](hnav_runtime::transport::Waiter) watches
/// it through [`Child::watch`](super::child::Child::watch).
#[derive(Debug)]
pub struct ExitFd {
    fd: FileDescriptor,
    mode: WatchMode,
}

impl ExitFd {
    /// Starts watching `pid`, which must be an unreaped child of this process.
    ///
    /// `mode` [`WatchMode::Auto`] falls back to the waiter thread only on `ENOSYS`; other
    /// `pidfd_open` errors (out of descriptors, say) are returned.
    pub fn watch(pid: u32, mode: WatchMode) -> io::Result<Self> {
        match mode {
            WatchMode::Pidfd => Self::pidfd(pid),
            WatchMode::WaiterThread => Self::waiter_thread(pid),
            WatchMode::Auto => match Self::pidfd(pid) {
                Err(e) if e.raw_os_error() == Some(libc::ENOSYS) => {
                    tracing::debug!(pid, "no pidfd_open on this kernel; using a waiter thread");
                    Self::waiter_thread(pid)
                }
                other => other,
            },
        }
    }

    /// The mechanism in use: [`WatchMode::Pidfd`] or [`WatchMode::WaiterThread`].
    pub fn mode(&self) -> WatchMode {
        self.mode
    }

    /// The raw descriptor, for `poll(2)`-style multiplexing outside iceoryx2. It stays owned
    /// by this value.
    pub fn as_raw_fd(&self) -> RawFd {
        // SAFETY: the value is only read, not stored beyond the caller's use; the descriptor
        // stays owned (and closed) by `self.fd`.
        unsafe { self.fd.native_handle() }
    }

    /// A second descriptor for the same exit (`dup`), so that a waiter can watch it while
    /// the [`Child`](super::child::Child) it came from is moved or replaced.
    pub fn try_clone(&self) -> io::Result<Self> {
        // SAFETY: `as_raw_fd` is open for as long as `self` lives, and the borrow ends here.
        let fd = unsafe { BorrowedFd::borrow_raw(self.as_raw_fd()) }.try_clone_to_owned()?;
        // SAFETY: `into_raw_fd` released ownership of the fresh descriptor, which this value
        // now takes.
        let fd = unsafe { FileDescriptor::new_unchecked(fd.into_raw_fd()) };
        Ok(Self {
            fd,
            mode: self.mode,
        })
    }

    /// Whether the child has exited, without blocking.
    pub fn is_ready(&self) -> bool {
        matches!(poll_readable(&[self.as_raw_fd()], Some(Duration::ZERO)), Ok(r) if r[0])
    }

    /// Blocks until the child has exited or `timeout` passed (`None`: no limit); returns
    /// whether it exited.
    pub fn wait(&self, timeout: Option<Duration>) -> bool {
        let deadline = timeout.map(|t| Instant::now() + t);
        loop {
            let left = deadline.map(|d| d.saturating_duration_since(Instant::now()));
            match poll_readable(&[self.as_raw_fd()], left) {
                Ok(r) if r[0] => return true,
                Ok(_) if left == Some(Duration::ZERO) => return false,
                Ok(_) => {}
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => {
                    tracing::warn!(error = %e, "poll on a child's exit descriptor failed");
                    return false;
                }
            }
        }
    }

    fn pidfd(pid: u32) -> io::Result<Self> {
        let pid =
            libc::pid_t::try_from(pid).map_err(|_| io::Error::from_raw_os_error(libc::ESRCH))?;
        // SAFETY: pidfd_open takes a pid and a flags word and returns a new descriptor or -1;
        // it reads no memory of ours.
        let ret = unsafe { libc::syscall(libc::SYS_pidfd_open, pid, 0 as libc::c_uint) };
        if ret < 0 {
            return Err(io::Error::last_os_error());
        }
        let raw = RawFd::try_from(ret).map_err(|_| io::Error::other("pidfd out of range"))?;
        // SAFETY: `raw` was just returned by pidfd_open, is open, and nothing else owns it.
        let fd = unsafe { FileDescriptor::new_unchecked(raw) };
        Ok(Self {
            fd,
            mode: WatchMode::Pidfd,
        })
    }

    fn waiter_thread(pid: u32) -> io::Result<Self> {
        let child = Pid::from_raw(
            libc::pid_t::try_from(pid).map_err(|_| io::Error::from_raw_os_error(libc::ESRCH))?,
        );
        let mut ends = [0 as libc::c_int; 2];
        // SAFETY: `ends` is a valid array of two c_ints for pipe2 to fill.
        if unsafe { libc::pipe2(ends.as_mut_ptr(), libc::O_CLOEXEC) } != 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: pipe2 succeeded, so both are fresh open descriptors owned by nobody else.
        let (read, write) =
            unsafe { (OwnedFd::from_raw_fd(ends[0]), OwnedFd::from_raw_fd(ends[1])) };
        std::thread::Builder::new()
            .name(format!("hnav-exit-{pid}"))
            .spawn(move || {
                let _write = write; // closed when the child has exited: the read end sees EOF
                                    // Returns once the child exited, or once it is not our child any more
                                    // (ECHILD: already reaped): either way there is nothing left to wait for.
                let flags = WaitPidFlag::WEXITED | WaitPidFlag::WNOWAIT;
                while let Err(Errno::EINTR) = waitid(Id::Pid(child), flags) {}
            })?;
        let raw = read.into_raw_fd();
        // SAFETY: `into_raw_fd` released ownership of `raw`, which this value now takes.
        let fd = unsafe { FileDescriptor::new_unchecked(raw) };
        Ok(Self {
            fd,
            mode: WatchMode::WaiterThread,
        })
    }
}

impl FileDescriptorBased for ExitFd {
    fn file_descriptor(&self) -> &FileDescriptor {
        &self.fd
    }
}

impl SynchronousMultiplexing for ExitFd {}

/// `poll(2)` for readability on `fds`, up to `timeout` (`None`: forever). Returns one flag per
/// descriptor (hang-up and error count as readable: the waiter pipe reports EOF as a hang-up).
/// Timeouts are rounded up to whole milliseconds so a short remainder never spins.
pub(crate) fn poll_readable(fds: &[RawFd], timeout: Option<Duration>) -> io::Result<Vec<bool>> {
    let mut pfds: Vec<libc::pollfd> = fds
        .iter()
        .map(|&fd| libc::pollfd {
            fd,
            events: libc::POLLIN,
            revents: 0,
        })
        .collect();
    let ms = match timeout {
        None => -1,
        Some(t) => {
            let ms = t.as_micros().div_ceil(1000);
            libc::c_int::try_from(ms).unwrap_or(libc::c_int::MAX)
        }
    };
    let nfds = libc::nfds_t::try_from(pfds.len())
        .map_err(|_| io::Error::from_raw_os_error(libc::EINVAL))?;
    // SAFETY: `pfds` is a valid, exclusively borrowed array of `nfds` pollfd structs.
    let ret = unsafe { libc::poll(pfds.as_mut_ptr(), nfds, ms) };
    if ret < 0 {
        return Err(io::Error::last_os_error());
    }
    let ready = libc::POLLIN | libc::POLLHUP | libc::POLLERR | libc::POLLNVAL;
    Ok(pfds.iter().map(|p| p.revents & ready != 0).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::transport::{PurgeOnDrop, RunId, Transport, Wake};

    #[test]
    fn a_child_exit_descriptor_wakes_the_waiter() {
        let run = PurgeOnDrop(RunId::unique("waitfd"));
        let t = Transport::builder(&run.0)
            .handle_signals(false)
            .create()
            .unwrap();
        let waiter = t.waiter().unwrap().with_recheck(None);
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let exit = ExitFd::watch(child.id(), WatchMode::Auto).unwrap();
        let _attached = waiter.attach_fd(&exit).unwrap();
        let deadline = Instant::now() + Duration::from_secs(30);
        assert_eq!(waiter.wait(Some(deadline)).unwrap(), Wake::Data);
        assert!(child.wait().unwrap().success());
    }
}
