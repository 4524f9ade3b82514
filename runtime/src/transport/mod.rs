//! Typed, run-scoped transport over iceoryx2 shared memory.
//!
//! iceoryx2 gives us zero-copy publish-subscribe and events; this module adds the conventions
//! every HNAV process must agree on, so that no process can get them subtly wrong:
//!
//! - **Run scoping** ([`RunId`]): every service is named `hnav/<run-id>/<topic>` and every run
//!   gets its own iceoryx2 [`Config`](iceoryx2::config::Config) prefix, so two runs (or two
//!   parallel tests) on one machine never see each other's services or shared-memory files.
//! - **Event-driven receive** ([`Sender`], [`Receiver`]): a publisher is paired with a notifier on
//!   an event service of the same name, and a subscriber with a listener, so every receiving loop
//!   blocks instead of polling. The event service also reports publishers that appear, leave
//!   cleanly or die ([`Wakeup`]).
//! - **One wait** ([`Waiter`], [`Wake`]): the only place a process blocks, on its receivers, an
//!   interval and a deadline; it guarantees the drain order, tells a paused process from a
//!   stopped one and bounds iceoryx2's lost wake-up. A loop with exactly one receiver waits
//!   on that receiver's own descriptor instead ([`SingleWaiter`]), with the same [`Wake`]s
//!   and one system call fewer per wake-up.
//! - **One wake-up for the whole swarm** ([`Bell`]): the coordinator wakes every agent with one
//!   eventfd write instead of one datagram per agent.
//! - **In-place slices** ([`SliceSender`], [`SliceReceiver`]): the neural-map snapshot is loaned
//!   from shared memory and written there directly; no intermediate `Vec`.
//! - **QoS from the swarm size** ([`Qos`]): iceoryx2's defaults allow two publishers per service;
//!   HNAV sizes every service from the agent count.
//! - **One directory per user** ([`ipc_root`]): iceoryx2 keeps node and service files in
//!   `/tmp/iceoryx2/` for root and `/tmp/iceoryx2-<uid>/` for other users (or
//!   `$HNAV_IPC_ROOT`), so several users can run on one machine; a directory this process
//!   may not use is a clear error before any file is created.
//! - **Liveness** ([`Transport::nodes`], [`Transport::cleanup_dead_nodes`], [`purge_run`]):
//!   list a run's processes, detect dead ones, remove what they left behind.
//!
//! ```no_run
//! use hnav_runtime::msg::Candidate;
//! use hnav_runtime::transport::{Qos, RunId, Transport};
//!
//! # fn main() -> Result<(), hnav_runtime::transport::TransportError> {
//! let run = RunId::new("demo-1")?;
//! let transport = Transport::builder(&run).node_name("agent-0").create()?;
//! let tx = transport.sender::<Candidate>("candidates", Qos::reliable(4))?;
//! tx.send(Candidate { agent: 0, ..Candidate::default() })?;
//! # Ok(()) }
//! ```

mod bell;
mod channel;
mod error;
mod node;
mod nodes;
mod qos;
mod run;
mod single;
mod slice;
mod waiter;

pub use bell::{Bell, BellWatch, BELL_ENV, BELL_LISTENER};
pub use channel::{Drained, PublisherId, Receiver, Sender, Wakeup};
pub use error::TransportError;
pub use node::{Transport, TransportBuilder};
pub use nodes::{CleanupReport, NodeInfo, NodeLiveness};
pub use qos::{Delivery, Qos};
pub use run::{
    ipc_root, is_domain_name, purge_run, run_config, run_iceoryx2_files, run_shm_files,
    PurgeOnDrop, RunId, DOMAIN_ENV, IPC_ROOT_ENV,
};
pub use single::SingleWaiter;
pub use slice::{SliceLoan, SliceReceiver, SliceSender};
pub use waiter::{stop_requested, Attachment, AttachmentId, Waiter, Wake};

/// The iceoryx2 service variant HNAV uses between processes.
pub type Ipc = iceoryx2::prelude::ipc::Service;

/// Event ids on every HNAV event service.
pub mod event_id {
    /// A sample was published.
    pub const DATA: usize = 1;
    /// A notifier (publisher side) was created.
    pub const PEER_UP: usize = 2;
    /// A notifier was dropped cleanly.
    pub const PEER_LEFT: usize = 3;
    /// A notifier's process died and its node was cleaned up.
    pub const PEER_DEAD: usize = 4;
    /// The largest id in use (the event services are created with it).
    pub const MAX: usize = 7;
}
