//! Raw iceoryx2: the baseline HNAV's transport is compared against, written the way
//! iceoryx2's own `benchmark-publish-subscribe` is, with the same QoS HNAV uses.

use anyhow::{Context, Result};
use iceoryx2::node::Node;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::{
    ipc, AllocationStrategy, BackpressureStrategy, CallbackProgression, EventId, NodeBuilder,
    NodeName, SignalHandlingMode, WaitSetBuilder,
};

use hnav_runtime::transport::{event_id, run_config, Delivery, RunId};

use super::pingpong::{PingPong, Role, ABORT_POLL};
use super::{Mode, Stamp, BENCH_QOS};

type Ipc = ipc::Service;

/// One side's ports. The event half exists only in event mode.
struct Ports {
    publisher: Publisher<Ipc, [u8], Stamp>,
    subscriber: Subscriber<Ipc, [u8], Stamp>,
    events: Option<(Notifier<Ipc>, Listener<Ipc>)>,
    // Declared last so the node outlives its ports (fields drop in declaration order).
    _node: Node<Ipc>,
}

fn open(run: &RunId, prefix: &str, role: Role, size: usize, mode: Mode) -> Result<Ports> {
    let qos = BENCH_QOS;
    let (tx_topic, rx_topic) = role.topics();
    let node = NodeBuilder::new()
        .name(&NodeName::new(role.node_name()).context("node name")?)
        // The same per-run prefix HNAV uses, so both live under identical iceoryx2 conventions
        // and `purge_run` cleans up after both.
        .config(&run_config(run))
        // Ctrl-C must stop a busy-polling benchmark; iceoryx2's handler would only set a flag.
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<Ipc>()
        .context("create node")?;

    let pubsub = |topic: &str| -> Result<_> {
        let name = run.service_name(&format!("{prefix}/{topic}"))?;
        let service = node
            .service_builder(&name)
            .publish_subscribe::<[u8]>()
            .user_header::<Stamp>()
            .max_publishers(qos.max_publishers)
            .max_subscribers(qos.max_subscribers)
            .max_nodes(qos.max_nodes())
            .subscriber_max_buffer_size(qos.buffer)
            .history_size(qos.history)
            .enable_safe_overflow(qos.delivery == Delivery::LatestOnly)
            .open_or_create()
            .map_err(|e| anyhow::anyhow!("open {name}: {e:?}"))?;
        Ok((name, service))
    };
    let (tx_name, tx_service) = pubsub(tx_topic)?;
    let (rx_name, rx_service) = pubsub(rx_topic)?;
    let publisher = tx_service
        .publisher_builder()
        .initial_max_slice_len(size)
        .allocation_strategy(AllocationStrategy::Static)
        .backpressure_strategy(BackpressureStrategy::DiscardData)
        .create()
        .map_err(|e| anyhow::anyhow!("create publisher: {e:?}"))?;
    let subscriber = rx_service
        .subscriber_builder()
        .buffer_size(qos.buffer)
        .create()
        .map_err(|e| anyhow::anyhow!("create subscriber: {e:?}"))?;

    let events = match mode {
        Mode::Poll => None,
        Mode::Event => {
            // Same service name as the data, the pattern iceoryx2's examples use and HNAV's
            // transport follows; same limits and event ids as HNAV's event services.
            let event = |name| {
                node.service_builder(name)
                    .event()
                    .max_notifiers(qos.max_publishers)
                    .max_listeners(qos.max_subscribers)
                    .max_nodes(qos.max_nodes())
                    .event_id_max_value(event_id::MAX)
                    .open_or_create()
                    .map_err(|e| anyhow::anyhow!("open event service: {e:?}"))
            };
            let notifier = event(&tx_name)?
                .notifier_builder()
                .default_event_id(EventId::new(event_id::DATA))
                .create()
                .map_err(|e| anyhow::anyhow!("create notifier: {e:?}"))?;
            let listener = event(&rx_name)?
                .listener_builder()
                .create()
                .map_err(|e| anyhow::anyhow!("create listener: {e:?}"))?;
            Some((notifier, listener))
        }
    };
    Ok(Ports {
        publisher,
        subscriber,
        events,
        _node: node,
    })
}

/// Plays `role` of a raw iceoryx2 ping-pong of `size`-byte samples; services are named
/// `hnav/<run>/<prefix>/{a2b,b2a}`.
pub(crate) fn side(
    pp: &PingPong,
    role: Role,
    run: &RunId,
    prefix: &str,
    size: usize,
    mode: Mode,
) -> Result<Vec<u64>> {
    let ports = pp.setup(role, || open(run, prefix, role, size, mode))?;
    let send = |stamp: Stamp| -> Result<()> {
        let mut sample = ports
            .publisher
            .loan_slice_uninit(size)
            .map_err(|e| anyhow::anyhow!("loan: {e:?}"))?;
        *sample.user_header_mut() = stamp;
        // SAFETY: `u8` has no invalid bit patterns, and the chunk is shared memory that the OS
        // mapped zero-filled and that only ever held bytes of earlier samples, so every byte
        // is initialised. Not filling it is deliberate: we measure transfer, not memset
        // (exactly as iceoryx2's own benchmark does).
        let sample = unsafe { sample.assume_init() };
        sample.send().map_err(|e| anyhow::anyhow!("send: {e:?}"))?;
        if let Some((notifier, _)) = &ports.events {
            notifier
                .notify()
                .map_err(|e| anyhow::anyhow!("notify: {e:?}"))?;
        }
        Ok(())
    };
    let receive = || -> Result<Option<Stamp>> {
        let sample = ports
            .subscriber
            .receive()
            .map_err(|e| anyhow::anyhow!("receive: {e:?}"))?;
        Ok(sample.map(|s| *s.user_header()))
    };

    match &ports.events {
        None => pp.run(role, send, || loop {
            // The explicit polling mode: spin on `receive` like upstream's benchmark.
            if let Some(stamp) = receive()? {
                return Ok(stamp);
            }
            pp.check()?;
        }),
        Some((_, listener)) => {
            let waitset = WaitSetBuilder::new()
                .signal_handling_mode(SignalHandlingMode::Disabled)
                .create::<Ipc>()
                .map_err(|e| anyhow::anyhow!("create waitset: {e:?}"))?;
            let _guard = waitset
                .attach_notification(listener)
                .map_err(|e| anyhow::anyhow!("attach listener: {e:?}"))?;
            pp.run(role, send, || loop {
                waitset
                    .wait_and_process_once_with_timeout(
                        |_| CallbackProgression::Continue,
                        ABORT_POLL,
                    )
                    .map_err(|e| anyhow::anyhow!("wait: {e:?}"))?;
                // Drain the notification, or the listener stays readable and the next wait
                // returns at once.
                listener
                    .try_wait(|_| {})
                    .map_err(|e| anyhow::anyhow!("drain listener: {e:?}"))?;
                if let Some(stamp) = receive()? {
                    return Ok(stamp);
                }
                pp.check()?;
            })
        }
    }
}
