//! The HNAV transport (`hnav_runtime::transport`): slice sender and receiver, measured with
//! the same ping-pong as [raw iceoryx2](super::raw). In event mode the receiver waits as an
//! HNAV process with one event source does, on the receiver itself (`SingleWaiter`); the
//! opt-in `hnav-waitset` row waits in the transport's general `Waiter` (iceoryx2's `WaitSet`)
//! instead, as a process with several sources does.

use std::time::Instant;

use anyhow::Result;

use hnav_runtime::transport::{RunId, SliceReceiver, SliceSender, Transport};

use super::pingpong::{PingPong, Role, ABORT_POLL};
use super::{Mode, Stamp, BENCH_QOS};

/// One side's ports; the transport (node) is declared last so it is dropped last.
struct Ports {
    tx: SliceSender<u8, Stamp>,
    rx: SliceReceiver<u8, Stamp>,
    transport: Transport,
}

fn open(run: &RunId, prefix: &str, role: Role, size: usize) -> Result<Ports> {
    let (tx_topic, rx_topic) = role.topics();
    let transport = Transport::builder(run)
        .node_name(role.node_name())
        // Ctrl-C must stop a busy-polling benchmark; iceoryx2's handler would only set a flag.
        .handle_signals(false)
        .create()?;
    let tx =
        transport.slice_sender::<u8, Stamp>(&format!("{prefix}/{tx_topic}"), size, BENCH_QOS)?;
    let rx = transport.slice_receiver::<u8, Stamp>(&format!("{prefix}/{rx_topic}"), BENCH_QOS)?;
    Ok(Ports { tx, rx, transport })
}

/// Which of the transport's waits the event-mode receiver blocks in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Wait {
    /// `Transport::single_waiter`: `ppoll` on the receiver's listener.
    Single,
    /// `Transport::waiter`: iceoryx2's `WaitSet` with the receiver attached.
    WaitSet,
}

/// Plays `role` of an HNAV ping-pong of `size`-byte samples on topics `<prefix>/{a2b,b2a}`.
///
/// The sender always notifies (that is built into [`SliceSender`]); in poll mode nobody waits
/// for the notification, so after the first one iceoryx2 coalesces the rest into an atomic
/// bit-set update without a syscall.
pub(crate) fn side(
    pp: &PingPong,
    role: Role,
    run: &RunId,
    prefix: &str,
    size: usize,
    mode: Mode,
    wait: Wait,
) -> Result<Vec<u64>> {
    let ports = pp.setup(role, || open(run, prefix, role, size))?;
    let send = |stamp: Stamp| -> Result<()> {
        let mut loan = ports.tx.loan(size)?;
        *loan.header_mut() = stamp;
        // SAFETY: `u8` has no invalid bit patterns, and the chunk is shared memory that the OS
        // mapped zero-filled and that only ever held bytes of earlier samples, so every byte
        // is initialised. Not filling it is deliberate: we measure transfer, not memset.
        unsafe { loan.assume_init_and_send() }?;
        Ok(())
    };
    let receive = || -> Result<Option<Stamp>> { Ok(ports.rx.receive()?.map(|s| *s.user_header())) };

    match mode {
        Mode::Poll => pp.run(role, send, || loop {
            // The benchmark's explicit polling mode; nothing else in HNAV polls.
            if let Some(stamp) = receive()? {
                return Ok(stamp);
            }
            pp.check()?;
        }),
        Mode::Event => {
            // The processes' own waits, re-check included: what a sample costs in HNAV.
            let single = ports.transport.single_waiter(&ports.rx);
            let waitset = match wait {
                Wait::Single => None,
                Wait::WaitSet => Some(ports.transport.waiter()?),
            };
            let _attached = waitset.as_ref().map(|w| w.attach(&ports.rx)).transpose()?;
            pp.run(role, send, || loop {
                let deadline = Some(Instant::now() + ABORT_POLL);
                match &waitset {
                    Some(w) => w.wait(deadline)?,
                    None => single.wait(deadline)?,
                };
                // Drains the listener; a wake-up may also be "publisher appeared", hence the
                // loop when no sample is there.
                ports.rx.take_wakeup()?;
                if let Some(stamp) = receive()? {
                    return Ok(stamp);
                }
                pp.check()?;
            })
        }
    }
}
