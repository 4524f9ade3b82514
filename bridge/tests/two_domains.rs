//! Two `hnav-bridge` processes, one per iceoryx2 domain (`HNAV_DOMAIN`), joined only by Zenoh
//! over loopback TCP: two "hosts" of one run on one machine. What one host's processes
//! publish reaches the other's subscribers, in order and once; nothing a bridge brought in
//! goes back out; a payload that fails its check on arrival is dropped and counted.
//!
//! In its own test binary because it spawns processes.

use std::io::{BufRead, BufReader};
use std::net::{Ipv4Addr, TcpListener};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use hnav_runtime::msg::{
    Candidate, Commit, CommitHeader, Decision, Lifecycle, MapHeader, Role, Verdict, Wire,
};
use hnav_runtime::topics;
use hnav_runtime::transport::{purge_run, Receiver, RunId, SliceReceiver, Transport};

const AGENTS: usize = 2;
/// Bound on every wait; a healthy exchange takes milliseconds.
const TIMEOUT: Duration = Duration::from_secs(30);

/// A running bridge and the lines of its stdout.
struct Bridge {
    child: Child,
    lines: mpsc::Receiver<String>,
}

/// The bridges and the run's shared memory in both domains, removed however the test ends.
struct Hosts {
    bridges: Vec<Bridge>,
    runs: Vec<RunId>,
}

impl Drop for Hosts {
    fn drop(&mut self) {
        for b in &mut self.bridges {
            let _ = b.child.kill();
            let _ = b.child.wait();
        }
        for r in &self.runs {
            let _ = purge_run(r);
        }
    }
}

fn free_port() -> u16 {
    let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    l.local_addr().unwrap().port()
}

/// Starts the bridge of `domain` and waits for its `ready` line.
fn start(run: &RunId, domain: &str, args: &[&str]) -> Bridge {
    let mut child = Command::new(env!("CARGO_BIN_EXE_hnav-bridge"))
        .args(["--run", run.as_str(), "--agents", &AGENTS.to_string()])
        .args(args)
        .env("HNAV_DOMAIN", domain)
        .stdout(Stdio::piped())
        .spawn()
        .expect("hnav-bridge starts");
    let stdout = child.stdout.take().unwrap();
    let (tx, lines) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    assert_eq!(lines.recv_timeout(TIMEOUT).as_deref(), Ok("ready"));
    Bridge { child, lines }
}

/// SIGTERM, then the counts line it prints as it exits, as `key -> value`.
fn stop(b: &mut Bridge) -> std::collections::BTreeMap<String, u64> {
    let pid = nix::unistd::Pid::from_raw(b.child.id() as i32);
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM).unwrap();
    let line = b.lines.recv_timeout(TIMEOUT).expect("the counts line");
    assert!(b.child.wait().unwrap().success(), "{line}");
    line.split(' ')
        .filter_map(|kv| kv.split_once('='))
        .map(|(k, v)| (k.to_string(), v.parse().unwrap()))
        .collect()
}

/// Takes samples of `rx` until `enough` says so; fails after [`TIMEOUT`].
fn collect<T: Wire>(t: &Transport, rx: &Receiver<T>, enough: impl Fn(&[T]) -> bool) -> Vec<T> {
    let waiter = t.waiter().unwrap();
    let _a = waiter.attach(rx).unwrap();
    let deadline = Instant::now() + TIMEOUT;
    let mut got = Vec::new();
    loop {
        rx.drain_pending(|v| got.push(*v)).unwrap();
        if enough(&got) {
            return got;
        }
        assert!(Instant::now() < deadline, "only {got:?} within {TIMEOUT:?}");
        waiter.wait(Some(deadline)).unwrap();
    }
}

/// The commits `rx` receives until `enough` of them came, each held as a [`Commit`].
fn collect_commits(
    t: &Transport,
    rx: &SliceReceiver<Decision, CommitHeader>,
    enough: usize,
) -> Vec<Commit> {
    let waiter = t.waiter().unwrap();
    let _a = waiter.attach(rx).unwrap();
    let deadline = Instant::now() + TIMEOUT;
    let mut got = Vec::new();
    loop {
        rx.drain_pending(|h, d| {
            let mut c = Commit::default();
            c.set(hnav_runtime::msg::CommitView::new(h, d));
            got.push(c);
        })
        .unwrap();
        if got.len() >= enough {
            return got;
        }
        assert!(Instant::now() < deadline, "only {got:?} within {TIMEOUT:?}");
        waiter.wait(Some(deadline)).unwrap();
    }
}

fn candidate(round: u64, agent: u32) -> Candidate {
    Candidate {
        round,
        agent,
        speed: 1.0,
        priority: 1.0,
        ..Candidate::default()
    }
}

#[test]
fn two_hosts_exchange_the_run_s_topics_once_and_drop_what_is_invalid() {
    let run = RunId::unique("bridge");
    let (run_a, run_b) = (
        run.clone().in_domain("ha").unwrap(),
        run.clone().in_domain("hb").unwrap(),
    );
    let mut hosts = Hosts {
        bridges: Vec::new(),
        runs: vec![run_a.clone(), run_b.clone()],
    };
    let a = Transport::builder(&run_a)
        .node_name("test-a")
        .create()
        .unwrap();
    let b = Transport::builder(&run_b)
        .node_name("test-b")
        .create()
        .unwrap();
    let cq = topics::candidates_qos(AGENTS);
    let (cand_a, cand_a_seen) = (
        a.sender::<Candidate>(topics::CANDIDATES, cq).unwrap(),
        a.receiver::<Candidate>(topics::CANDIDATES, cq).unwrap(),
    );
    let cand_b = b.receiver::<Candidate>(topics::CANDIDATES, cq).unwrap();
    let kq = topics::commit_qos(AGENTS);
    let (commit_b, commit_a) = (
        b.slice_sender::<Decision, CommitHeader>(topics::COMMIT, AGENTS, kq)
            .unwrap(),
        a.slice_receiver::<Decision, CommitHeader>(topics::COMMIT, kq)
            .unwrap(),
    );
    let lq = topics::lifecycle_qos(AGENTS);
    let (ready_b, ready_a) = (
        b.sender::<Lifecycle>(topics::READY, lq).unwrap(),
        a.receiver::<Lifecycle>(topics::READY, lq).unwrap(),
    );

    // Host A's own view of its candidates (for the echo check). The topic is reliable, so
    // it must be drained as A sends, or A's sends would wait for it.
    let mut mine = Vec::new();
    let mut send_a = |c: Candidate| {
        cand_a.send(c).unwrap();
        cand_a_seen.drain_pending(|v| mine.push(*v)).unwrap();
    };

    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    hosts
        .bridges
        .push(start(&run, "ha", &["--listen", &endpoint, "--maps"]));
    hosts
        .bridges
        .push(start(&run, "hb", &["--connect", &endpoint, "--maps"]));

    // The two sessions find each other in their own time: probe (round 0) until B hears one.
    let deadline = Instant::now() + TIMEOUT;
    let mut probes = 0u64;
    let waiter = b.waiter().unwrap();
    let attached = waiter.attach(&cand_b).unwrap();
    loop {
        send_a(candidate(0, 0));
        probes += 1;
        let heard = cand_b.drain_pending(|_| {}).unwrap().samples > 0;
        if heard {
            break;
        }
        assert!(Instant::now() < deadline, "the bridges never connected");
        waiter
            .wait(Some(Instant::now() + Duration::from_millis(100)))
            .unwrap();
    }
    drop(attached);

    // A -> B: 100 candidates, in order, once each.
    for r in 1..=100 {
        send_a(candidate(r, (r % 2) as u32));
    }
    let got = collect(&b, &cand_b, |g| g.iter().any(|c| c.round == 100));
    let rounds: Vec<u64> = got.iter().map(|c| c.round).filter(|&r| r > 0).collect();
    assert_eq!(rounds, (1..=100).collect::<Vec<_>>());

    // B -> A: 20 commits, a decision per agent, and a lifecycle event.
    let decision = |r: u64, i: usize| Decision {
        agent: i as u32,
        verdict: Verdict::Accept as u8,
        cell: (r * 10) as u32 + i as u32,
        ..Decision::default()
    };
    for r in 1..=20 {
        let header = CommitHeader {
            round: r,
            count: AGENTS as u32,
            term: 0,
        };
        commit_b
            .send_from_fn(header, AGENTS, |i| decision(r, i))
            .unwrap();
    }
    ready_b.send(Lifecycle::up(Role::Agent, 1)).unwrap();
    let commits = collect_commits(&a, &commit_a, 20);
    assert_eq!(
        commits.iter().map(|c| c.round).collect::<Vec<_>>(),
        (1..=20).collect::<Vec<_>>()
    );
    for c in &commits {
        let want: Vec<Decision> = (0..AGENTS).map(|i| decision(c.round, i)).collect();
        assert_eq!(
            c.decisions, want,
            "round {}'s decisions crossed whole",
            c.round
        );
    }
    let ups = collect(&a, &ready_a, |g| !g.is_empty());
    assert_eq!((ups[0].role, ups[0].index), (Role::Agent as u8, 1));

    // An agent index past the largest swarm is dropped on arrival; the valid one after it
    // arrives.
    send_a(candidate(101, hnav_runtime::msg::MAX_AGENTS as u32));
    send_a(candidate(102, 1));
    let got = collect(&b, &cand_b, |g| g.iter().any(|c| c.round == 102));
    assert_eq!(
        got.iter().map(|c| c.round).collect::<Vec<_>>(),
        vec![102],
        "the invalid candidate reached host B"
    );

    // A neural-map snapshot (--maps) crosses A -> B as its header and activations.
    let (map_a, map_b) = (
        a.slice_sender::<f32, MapHeader>(&topics::map(1), 1000, topics::state_qos())
            .unwrap(),
        b.slice_receiver::<f32, MapHeader>(&topics::map(1), topics::state_qos())
            .unwrap(),
    );
    let values: Vec<f32> = (0..1000).map(|v| v as f32 * 0.5).collect();
    let mut loan = map_a.loan(values.len()).unwrap();
    *loan.header_mut() = MapHeader {
        round: 7,
        agent: 1,
        width: 40,
        height: 25,
        ..MapHeader::default()
    };
    loan.copy_and_send(&values).unwrap();
    let waiter = b.waiter().unwrap();
    let attached = waiter.attach(&map_b).unwrap();
    let deadline = Instant::now() + TIMEOUT;
    let mut snapshot = None;
    while snapshot.is_none() {
        assert!(Instant::now() < deadline, "no map snapshot reached B");
        map_b
            .drain_pending(|h, v| snapshot = Some((*h, v.to_vec())))
            .unwrap();
        if snapshot.is_none() {
            waiter.wait(Some(deadline)).unwrap();
        }
    }
    drop(attached);
    let (h, v) = snapshot.unwrap();
    assert_eq!((h.round, h.agent, h.width, h.height), (7, 1, 40, 25));
    assert_eq!(v, values);

    // Nothing came back to A: its own candidates only, each once.
    cand_a_seen.drain_pending(|v| mine.push(*v)).unwrap();
    let mut rounds: Vec<u64> = mine.iter().map(|c| c.round).filter(|&r| r > 0).collect();
    rounds.dedup();
    assert_eq!(rounds.len(), 102, "an echo: {mine:?}");

    let counts_b = stop(&mut hosts.bridges[1]);
    let counts_a = stop(&mut hosts.bridges[0]);
    assert_eq!(counts_a["out"], probes + 102 + 1, "{counts_a:?}");
    assert_eq!(counts_a["in"], 21, "{counts_a:?}");
    assert_eq!(counts_a["dropped"], 0, "{counts_a:?}");
    assert_eq!(counts_b["dropped"], 1, "{counts_b:?}");
    assert_eq!(counts_b["out"], 21, "{counts_b:?}");
    println!("host A {counts_a:?}; host B {counts_b:?}; {probes} probes");
}
