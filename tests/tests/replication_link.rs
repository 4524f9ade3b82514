//! Three Raft replicas talking over the HNAV transport (`raft/<i>` slice topics), each on its
//! own thread with its own iceoryx2 node and `Waiter`, as three coordinator processes would:
//! they elect a leader, commit the same records, and when the leader stops the other two
//! elect a new one and go on. The in-memory cluster of `hnav_coordinator::replication`'s unit
//! tests checks the failure semantics; this checks the wire.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use hnav_coordinator::replication::{RaftLink, Replica, ReplicaConfig, Role};
use hnav_runtime::transport::{RunId, Transport, Wake};
use hnav_tests::TestRun;

/// One tick of Raft's clock: elections after 10 to 20 ticks, 100–200 ms.
const TICK: Duration = Duration::from_millis(10);
const LIMIT: Duration = Duration::from_secs(60);

/// What the test sees of one replica thread.
#[derive(Default)]
struct Shared {
    role: Option<Role>,
    committed: Vec<Vec<u8>>,
    dropped: usize,
}

struct ReplicaThread {
    id: u64,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<(), String>>>,
}

impl ReplicaThread {
    fn start(run: &RunId, id: u64, n: u64, proposals: Arc<Mutex<VecDeque<Vec<u8>>>>) -> Self {
        let shared = Arc::new(Mutex::new(Shared::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (run, s, st) = (run.clone(), shared.clone(), stop.clone());
        let thread = std::thread::spawn(move || replica_loop(&run, id, n, &proposals, &s, &st));
        ReplicaThread {
            id,
            shared,
            stop,
            thread: Some(thread),
        }
    }

    fn role(&self) -> Option<Role> {
        self.shared.lock().unwrap().role
    }

    fn committed(&self) -> Vec<Vec<u8>> {
        self.shared.lock().unwrap().committed.clone()
    }

    fn stop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let result = t.join().expect("the replica thread panicked");
            assert_eq!(result, Ok(()), "replica {}", self.id);
        }
    }
}

impl Drop for ReplicaThread {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The loop a coordinator replica would run: wait on the inbox and the tick, step what came
/// in, tick on time, propose while leading, send what Raft released.
fn replica_loop(
    run: &RunId,
    id: u64,
    n: u64,
    proposals: &Mutex<VecDeque<Vec<u8>>>,
    shared: &Mutex<Shared>,
    stop: &AtomicBool,
) -> Result<(), String> {
    let e = |e: &dyn std::fmt::Display| format!("replica {id}: {e}");
    let transport = Transport::builder(run)
        .node_name(&format!("replica-{id}"))
        .handle_signals(false)
        .create()
        .map_err(|x| e(&x))?;
    let config = ReplicaConfig::cluster(id, n);
    let link = RaftLink::open(&transport, id, &config.voters).map_err(|x| e(&x))?;
    let mut replica = Replica::new(&config).map_err(|x| e(&x))?;
    let waiter = transport.waiter().map_err(|x| e(&x))?;
    let _inbox = waiter.attach(link.inbox()).map_err(|x| e(&x))?;
    let _tick = waiter.attach_interval(TICK).map_err(|x| e(&x))?;
    let mut next_tick = Instant::now() + TICK;
    while !stop.load(Ordering::Relaxed) {
        if waiter.wait(Some(next_tick)).map_err(|x| e(&x))? == Wake::Stop {
            break;
        }
        let mut failed = None;
        let inbox = link
            .receive(|m| {
                if let Err(x) = replica.step(m) {
                    failed.get_or_insert(x);
                }
            })
            .map_err(|x| e(&x))?;
        if let Some(x) = failed {
            return Err(e(&x));
        }
        if Instant::now() >= next_tick {
            replica.tick().map_err(|x| e(&x))?;
            next_tick += TICK;
        }
        if replica.role() == Role::Leader {
            let next = proposals.lock().unwrap().pop_front();
            if let Some(record) = next {
                replica.propose(&record).map_err(|x| e(&x))?;
            }
        }
        for m in replica.take_messages() {
            link.send(&m).map_err(|x| e(&x))?;
        }
        let mut s = shared.lock().unwrap();
        s.role = Some(replica.role());
        s.dropped += inbox.dropped;
        s.committed.extend(replica.take_committed().map(|c| c.data));
    }
    Ok(())
}

/// Waits (bounded) until `ok` holds, polling the threads' shared state every tick.
fn wait_for(what: &str, mut ok: impl FnMut() -> bool) {
    let end = Instant::now() + LIMIT;
    while !ok() {
        assert!(Instant::now() < end, "{what}: not within {LIMIT:?}");
        std::thread::sleep(TICK);
    }
}

fn leader(replicas: &[ReplicaThread]) -> Option<usize> {
    let leaders: Vec<usize> = (0..replicas.len())
        .filter(|&i| replicas[i].thread.is_some() && replicas[i].role() == Some(Role::Leader))
        .collect();
    match leaders[..] {
        [l] => Some(l),
        _ => None,
    }
}

fn record(i: u32) -> Vec<u8> {
    format!("round {i}").into_bytes()
}

#[test]
fn three_replicas_agree_over_the_transport_and_survive_losing_their_leader() {
    let run = TestRun::new("raftlink");
    let proposals = Arc::new(Mutex::new(VecDeque::new()));
    let mut replicas: Vec<ReplicaThread> = (1..=3)
        .map(|id| ReplicaThread::start(&run.run, id, 3, proposals.clone()))
        .collect();
    wait_for("a leader", || leader(&replicas).is_some());
    proposals.lock().unwrap().extend((1..=10).map(record));
    let first: Vec<_> = (1..=10).map(record).collect();
    wait_for("10 records on all three", || {
        replicas.iter().all(|r| r.committed() == first)
    });

    let old = leader(&replicas).expect("still one leader");
    replicas[old].stop();
    wait_for("a new leader", || {
        leader(&replicas).is_some_and(|l| l != old)
    });
    proposals.lock().unwrap().extend((11..=15).map(record));
    let all: Vec<_> = (1..=15).map(record).collect();
    wait_for("15 records on the two left", || {
        (0..3)
            .filter(|&i| i != old)
            .all(|i| replicas[i].committed() == all)
    });
    for r in &mut replicas {
        if r.thread.is_some() {
            r.stop();
        }
        assert_eq!(r.shared.lock().unwrap().dropped, 0, "replica {}", r.id);
    }
}

#[test]
fn a_message_to_no_other_voter_and_one_over_the_topic_size_are_errors() {
    use hnav_coordinator::replication::{ReplicaError, MAX_MESSAGE_BYTES};
    use raft::eraftpb::{Entry, Message};
    let run = TestRun::new("raftlinkbad");
    let transport = Transport::builder(&run.run)
        .node_name("replica-1")
        .handle_signals(false)
        .create()
        .unwrap();
    let link = RaftLink::open(&transport, 1, &[1, 2, 3]).unwrap();
    let mut m = Message {
        from: 1,
        ..Message::default()
    };
    for to in [1, 9] {
        m.to = to;
        let e = link.send(&m).unwrap_err();
        assert!(matches!(e, ReplicaError::Encode(_)), "{e}");
        assert!(e.to_string().contains("no other voter"), "{e}");
    }
    m.to = 2;
    let big = Entry {
        data: vec![7u8; MAX_MESSAGE_BYTES].into(),
        ..Entry::default()
    };
    m.entries = vec![big].into();
    let e = link.send(&m).unwrap_err();
    assert!(e.to_string().contains("over the topic's"), "{e}");
    // A well-formed one goes out.
    m.entries.clear();
    link.send(&m).unwrap();
}
