//! The commit bell: one write wakes every agent of a run.
//!
//! An iceoryx2 0.10 event is one Unix datagram socket per listener, so a notifier wakes N
//! listeners with N `sendto` calls, and each woken listener reads its datagram back: at 128
//! agents the coordinator's commit fan-out took 1.3 ms of its time per round
//! (`hnav-bench fanout`), 2.4 times what one `FUTEX_WAKE` of 128 waiters costs. A futex
//! cannot join the `epoll` set an agent also waits on for odometry and lifecycle events. An
//! eventfd can, and one write to it wakes every epoll instance that watches it
//! edge-triggered: that is the bell, within a few percent of the futex in the same benchmark.
//!
//! **How it is shared.** The supervisor creates the eventfd before it spawns anyone, leaves
//! it inheritable and names its number in [`BELL_ENV`] for the coordinator and the agents
//! (restarted ones too: the supervisor keeps it open for the whole run). A process started by
//! hand has no bell and works as before.
//!
//! **Who rings, who listens.** The coordinator publishes a commit, rings, and notifies by
//! datagram only the commit listeners that are not named [`BELL_LISTENER`]
//! ([`Sender::ringing`](super::Sender::ringing)): viewers, observers, the Python
//! client and a bell-less agent still get theirs. An agent with a bell names its commit
//! listener so and watches the bell with its own epoll instance ([`BellWatch`]); its listener
//! still reports a coordinator that appears or dies (iceoryx2 sends those events itself).
//!
//! **Why no wake-up is lost.** Nobody reads the eventfd's counter (reading would reset it for
//! every watcher): each watcher's private epoll watches it edge-triggered, and every write
//! is an edge for every watcher. The watcher's epoll descriptor joins the process's
//! [`Waiter`](super::Waiter) (level-triggered, as iceoryx2's `WaitSet` is); the waiter
//! consumes the edge ([`BellWatch::take`]) when it reports it, before the loop drains its
//! commit subscriber. A commit is published before its ring, so whatever the consumed edge
//! stood for is in the subscriber; a ring after the consumption leaves a new edge, and the
//! next wait returns at once.

use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};
use std::sync::atomic::{AtomicBool, Ordering};

use iceoryx2_bb_posix::file_descriptor::{FileDescriptor, FileDescriptorBased};
use iceoryx2_bb_posix::file_descriptor_set::SynchronousMultiplexing;

use super::TransportError;

/// The environment variable that names the bell's inherited descriptor.
pub const BELL_ENV: &str = "HNAV_BELL_FD";

/// The name of a commit listener that the bell wakes instead of a datagram.
pub const BELL_LISTENER: &str = "bell";

/// A run's commit bell: an eventfd shared by inheritance (see the module docs).
#[derive(Debug)]
pub struct Bell {
    fd: OwnedFd,
}

impl Bell {
    /// Creates a bell that the processes spawned from here inherit (the supervisor's).
    pub fn create() -> Result<Self, TransportError> {
        // SAFETY: eventfd(2) with valid flags; the result is checked before use. Not
        // EFD_CLOEXEC: the children must inherit it.
        let fd = unsafe { libc::eventfd(0, libc::EFD_NONBLOCK) };
        if fd < 0 {
            return Err(bell_error("create", std::io::Error::last_os_error()));
        }
        // SAFETY: `fd` was just returned by eventfd(2) and is owned by nobody else.
        Ok(Self {
            fd: unsafe { OwnedFd::from_raw_fd(fd) },
        })
    }

    /// The bell this process inherited, if [`BELL_ENV`] names one; an error when it names
    /// something that is not an open eventfd (a process must not wait on a stranger's
    /// descriptor, nor silently go without the bell it was given).
    ///
    /// A process takes its bell once: the descriptor then belongs to that [`Bell`], and a
    /// second call is an error rather than a second owner of the same descriptor.
    pub fn from_env() -> Result<Option<Self>, TransportError> {
        static TAKEN: AtomicBool = AtomicBool::new(false);
        let Some(value) = std::env::var_os(BELL_ENV) else {
            return Ok(None);
        };
        if TAKEN.swap(true, Ordering::AcqRel) {
            return Err(bell_error(
                "inherit",
                std::io::Error::other("this process has taken its bell already"),
            ));
        }
        Self::inherit(&value).map(Some)
    }

    /// Takes over the descriptor `value` names, once it is known to be an open eventfd.
    fn inherit(value: &std::ffi::OsStr) -> Result<Self, TransportError> {
        let fd: RawFd = value
            .to_str()
            .and_then(|v| v.parse().ok())
            .filter(|&fd| fd >= 0)
            .ok_or_else(|| {
                bell_error(
                    "inherit",
                    std::io::Error::other(format!("{BELL_ENV}={value:?} is not a descriptor")),
                )
            })?;
        let link = std::fs::read_link(format!("/proc/self/fd/{fd}"))
            .map_err(|e| bell_error("inherit", e))?;
        if link.as_os_str() != "anon_inode:[eventfd]" {
            return Err(bell_error(
                "open inherited",
                std::io::Error::other(format!(
                    "{BELL_ENV}={fd} is {}, not an eventfd",
                    link.display()
                )),
            ));
        }
        // SAFETY: the descriptor is open (its /proc link exists) and this process takes it
        // over once: the supervisor gave it for this purpose only.
        let fd = unsafe { OwnedFd::from_raw_fd(fd) };
        // The agent's own children (none today) need not inherit it.
        // SAFETY: fcntl(2) on an open descriptor this value owns.
        unsafe { libc::fcntl(fd.as_raw_fd(), libc::F_SETFD, libc::FD_CLOEXEC) };
        Ok(Self { fd })
    }

    /// A second handle on the same eventfd (a `dup`, closed on exec): rings of either wake the
    /// watchers of both.
    pub fn try_clone(&self) -> Result<Self, TransportError> {
        let fd = self.fd.try_clone().map_err(|e| bell_error("clone", e))?;
        Ok(Self { fd })
    }

    /// The descriptor number to put in a child's [`BELL_ENV`].
    pub fn env_value(&self) -> String {
        self.fd.as_raw_fd().to_string()
    }

    /// Wakes every watcher. Never blocks: a counter near its limit (after 2^64 - 2 rings)
    /// would refuse the write, and the watchers' edges from earlier rings are still pending.
    pub fn ring(&self) -> Result<(), TransportError> {
        let one: u64 = 1;
        // SAFETY: writes the 8 bytes of a live local to an eventfd this value owns.
        let w = unsafe { libc::write(self.fd.as_raw_fd(), (&one as *const u64).cast(), 8) };
        if w == 8 {
            return Ok(());
        }
        let e = std::io::Error::last_os_error();
        match e.raw_os_error() {
            Some(libc::EAGAIN) => Ok(()),
            _ => Err(bell_error("ring", e)),
        }
    }

    /// The watcher of a process that only listens (an agent): it keeps the bell's descriptor
    /// open as long as it watches.
    pub fn into_watch(self) -> Result<BellWatch, TransportError> {
        let mut watch = self.watch()?;
        watch._bell = Some(self);
        Ok(watch)
    }

    /// A new watcher of this bell for one process's [`Waiter`](super::Waiter).
    pub fn watch(&self) -> Result<BellWatch, TransportError> {
        // SAFETY: epoll_create1(2) with a valid flag; checked below.
        let raw = unsafe { libc::epoll_create1(libc::EPOLL_CLOEXEC) };
        if raw < 0 {
            return Err(bell_error("watch", std::io::Error::last_os_error()));
        }
        // SAFETY: `raw` was just returned by epoll_create1(2) and is owned by nobody else.
        let epoll = unsafe { OwnedFd::from_raw_fd(raw) };
        let mut ev = libc::epoll_event {
            events: (libc::EPOLLIN | libc::EPOLLET) as u32,
            u64: 0,
        };
        // SAFETY: both descriptors are open; `ev` is a live local the kernel copies.
        let r = unsafe {
            libc::epoll_ctl(
                epoll.as_raw_fd(),
                libc::EPOLL_CTL_ADD,
                self.fd.as_raw_fd(),
                &mut ev,
            )
        };
        if r != 0 {
            return Err(bell_error("watch", std::io::Error::last_os_error()));
        }
        let handle = FileDescriptor::non_owning_new(epoll.as_raw_fd()).ok_or_else(|| {
            bell_error("watch", std::io::Error::other("invalid epoll descriptor"))
        })?;
        Ok(BellWatch {
            epoll,
            handle,
            _bell: None,
        })
    }
}

/// One process's view of the bell: a private epoll instance, readable while a ring is not yet
/// taken. Attach it with [`Waiter::attach_bell`](super::Waiter::attach_bell).
#[derive(Debug)]
pub struct BellWatch {
    epoll: OwnedFd,
    /// The same descriptor, not owning, as iceoryx2's `WaitSet` wants it.
    handle: FileDescriptor,
    /// The bell itself, when the watch owns it ([`Bell::into_watch`]).
    _bell: Option<Bell>,
}

impl BellWatch {
    /// Consumes the pending ring, if any; whether there was one. The waiter calls it for
    /// every wake-up it reports from the bell, so a loop does not have to.
    pub fn take(&self) -> bool {
        take_ring(self.epoll.as_raw_fd())
    }

    /// The raw descriptor of the private epoll instance.
    pub(crate) fn raw_fd(&self) -> RawFd {
        self.epoll.as_raw_fd()
    }
}

impl FileDescriptorBased for BellWatch {
    fn file_descriptor(&self) -> &FileDescriptor {
        &self.handle
    }
}

impl SynchronousMultiplexing for BellWatch {}

/// Consumes the pending edge of the bell watch whose epoll descriptor is `epoll`; whether
/// there was one.
pub(crate) fn take_ring(epoll: RawFd) -> bool {
    let mut ev = [libc::epoll_event { events: 0, u64: 0 }; 1];
    // SAFETY: `ev` is a live buffer of one event for the whole call; timeout 0 never blocks.
    // A closed `epoll` only makes the call fail (EBADF), read as "no ring".
    let got = unsafe { libc::epoll_wait(epoll, ev.as_mut_ptr(), 1, 0) };
    got > 0
}

fn bell_error(op: &'static str, source: std::io::Error) -> TransportError {
    TransportError::Bell { op, source }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_ring_is_one_edge_for_every_watcher_and_is_taken_once() {
        let bell = Bell::create().unwrap();
        let watches: Vec<_> = (0..4).map(|_| bell.watch().unwrap()).collect();
        assert!(watches.iter().all(|w| !w.take()), "no ring yet");
        bell.ring().unwrap();
        assert!(
            watches.iter().all(|w| w.take()),
            "every watcher sees the ring"
        );
        assert!(watches.iter().all(|w| !w.take()), "and takes it once");
        // Two rings before a take are one pending edge; a ring after the take is a new one.
        bell.ring().unwrap();
        bell.ring().unwrap();
        assert!(watches[0].take());
        assert!(!watches[0].take());
        bell.ring().unwrap();
        assert!(watches[0].take());
    }

    #[test]
    fn only_an_open_eventfd_is_inherited() {
        use std::ffi::OsStr;
        for bad in ["", "x", "-1"] {
            let e = Bell::inherit(OsStr::new(bad)).unwrap_err().to_string();
            assert!(e.contains("is not a descriptor"), "{bad:?}: {e}");
        }
        // stdin: a pipe or /dev/null, never an eventfd.
        let e = Bell::inherit(OsStr::new("0")).unwrap_err().to_string();
        assert!(e.contains("not an eventfd"), "{e}");
        let bell = Bell::create().unwrap();
        // SAFETY: dup(2) of an open descriptor; the copy is handed to `inherit`, which owns it.
        let copy = unsafe { libc::dup(bell.fd.as_raw_fd()) };
        let inherited = Bell::inherit(OsStr::new(&copy.to_string())).unwrap();
        let watch = bell.watch().unwrap();
        inherited.ring().unwrap();
        assert!(watch.take(), "the inherited bell rings the same eventfd");
    }

    /// A ringing sender wakes a bell receiver by the bell only (no datagram: its listener
    /// has no data event) and a plain receiver by its datagram; both get the sample.
    #[test]
    fn a_ringing_send_sends_datagrams_only_to_plain_listeners() {
        use crate::transport::{PurgeOnDrop, Qos, RunId, Transport};
        let run = PurgeOnDrop(RunId::unique("bellsend"));
        let t = Transport::builder(&run.0)
            .handle_signals(false)
            .create()
            .unwrap();
        let qos = Qos::reliable(2);
        let agent = t.bell_receiver::<u64>("commit", qos).unwrap();
        let viewer = t.receiver::<u64>("commit", qos).unwrap();
        let bell = Bell::create().unwrap();
        let watch = bell.watch().unwrap();
        let tx = t.sender::<u64>("commit", qos).unwrap().ringing(bell);
        // The sender's appearance reaches both listeners (iceoryx2's own event).
        assert!(agent.take_wakeup().unwrap().peer_up);
        assert!(viewer.take_wakeup().unwrap().peer_up);
        tx.send(7).unwrap();
        assert!(watch.take(), "the bell rang");
        assert!(
            !agent.take_wakeup().unwrap().data,
            "no datagram to a bell listener"
        );
        assert!(
            viewer.take_wakeup().unwrap().data,
            "a datagram to a plain listener"
        );
        let mut got = (0, 0);
        agent.drain(|&v| got.0 = v).unwrap();
        viewer.drain(|&v| got.1 = v).unwrap();
        assert_eq!(got, (7, 7));
    }
}
