//! The faults ([`Nemesis`], [`Action`]) and a run's schedule of them ([`Event`],
//! [`schedule`]), drawn from the seed.
//!
//! A nemesis is a family of faults; a run under it gets a schedule of a few of its
//! [`Action`]s at times in the fault window, each undone after its duration (an action
//! without one is instant). Every fault ends at the heal, whatever its duration. A target
//! `leader` is the replica that leads when the action fires (the highest term's, if two
//! think they do), so that the faults find the leader as often as a nemesis wants.
//!
//! A schedule is text, one event a line or `;` between them, which a failure prints and
//! `--trace` replays: `@1200ms kill leader; @2500ms partition 1,2|3 for 800ms`.

use std::fmt;
use std::str::FromStr;

use super::clock::Time;
use super::disk::DiskFault;
use super::rng::Rng;

/// A family of faults; one per row of the sweep's table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Nemesis {
    /// Processes killed and restarted by their supervisor, or stopped for a while.
    Kill,
    /// Processes paused (`SIGSTOP`) and resumed.
    Pause,
    /// The cluster split in two, both ways.
    Partition,
    /// Links cut one way only: one link, or everything a replica sends, or everything it
    /// would receive.
    OneWay,
    /// The leader cut off from everyone, both ways.
    LeaderIsolated,
    /// Two majorities that share one replica (a bridge), or with five replicas each one
    /// seeing a different majority (a ring).
    MajoritySplit,
    /// Messages delayed by up to 400 ms, in order.
    Slow,
    /// Messages dropped.
    Lossy,
    /// Messages delivered twice.
    Duplicate,
    /// Messages delivered out of order.
    Reorder,
    /// A replica's clock fast, stalled, or jumping ahead.
    Clock,
    /// A disk write that fails.
    DiskWrite,
    /// An fsync that fails.
    DiskFsync,
    /// A power loss, during a write (torn) or between two.
    DiskTorn,
    /// Any of the above, several in one run.
    Mixed,
}

impl Nemesis {
    /// Every nemesis, in the table's order.
    pub const ALL: [Nemesis; 15] = [
        Nemesis::Kill,
        Nemesis::Pause,
        Nemesis::Partition,
        Nemesis::OneWay,
        Nemesis::LeaderIsolated,
        Nemesis::MajoritySplit,
        Nemesis::Slow,
        Nemesis::Lossy,
        Nemesis::Duplicate,
        Nemesis::Reorder,
        Nemesis::Clock,
        Nemesis::DiskWrite,
        Nemesis::DiskFsync,
        Nemesis::DiskTorn,
        Nemesis::Mixed,
    ];

    /// Its name on the command line and in the table.
    pub fn name(self) -> &'static str {
        match self {
            Nemesis::Kill => "kill",
            Nemesis::Pause => "pause",
            Nemesis::Partition => "partition",
            Nemesis::OneWay => "one-way",
            Nemesis::LeaderIsolated => "leader-isolated",
            Nemesis::MajoritySplit => "majority-split",
            Nemesis::Slow => "slow",
            Nemesis::Lossy => "lossy",
            Nemesis::Duplicate => "duplicate",
            Nemesis::Reorder => "reorder",
            Nemesis::Clock => "clock",
            Nemesis::DiskWrite => "disk-write",
            Nemesis::DiskFsync => "disk-fsync",
            Nemesis::DiskTorn => "disk-torn",
            Nemesis::Mixed => "mixed",
        }
    }

    /// The nemesis named `name`.
    pub fn from_name(name: &str) -> Option<Nemesis> {
        Nemesis::ALL.into_iter().find(|n| n.name() == name)
    }

    /// Every name, for an error message.
    pub fn names() -> String {
        Nemesis::ALL.map(Nemesis::name).join(", ")
    }
}

/// Whom an action hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// Replica `id`.
    Id(u64),
    /// The replica that leads when the action fires.
    Leader,
}

/// What a network fault does while it lasts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NetFault {
    /// Up to 400 ms more per message.
    Slow,
    /// This percentage of messages dropped.
    Lossy(u8),
    /// This percentage delivered twice.
    Dup(u8),
    /// Messages out of order.
    Reorder,
}

/// What a clock fault does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClockFault {
    /// This many ticks per period, for the duration.
    Fast(u32, u64),
    /// No ticks, for the duration.
    Stall(u64),
    /// This many ticks at once.
    Jump(u32),
}

/// One fault; durations in milliseconds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Action {
    /// The process killed; its supervisor restarts it.
    Kill(Target),
    /// The process killed and kept down for the duration.
    Stop(Target, u64),
    /// The process paused for the duration.
    Pause(Target, u64),
    /// The links between the two groups cut both ways.
    Partition(Vec<u64>, Vec<u64>, u64),
    /// The link from the first to the second cut.
    Cut(Target, Target, u64),
    /// Every link from the target cut: it hears, but is not heard.
    Mute(Target, u64),
    /// Every link to the target cut: it is heard, but hears nothing.
    Deafen(Target, u64),
    /// Every link of the target cut both ways.
    Isolate(Target, u64),
    /// Two majorities sharing only the target.
    Bridge(Target, u64),
    /// Each replica linked to its two neighbours only (five replicas).
    Ring(u64),
    /// A network fault.
    Net(NetFault, u64),
    /// A clock fault.
    Clock(Target, ClockFault),
    /// A disk fault armed to fire at the target's nth write (or fsync).
    Disk(Target, DiskFault, u32),
    /// The target's power lost now.
    Power(Target),
}

/// An action at a time.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Event {
    /// When it fires.
    pub at: Time,
    /// What it does.
    pub action: Action,
}

/// When faults may start: after the first election, before the heal.
pub const WINDOW: (u64, u64) = (300, 5_000);

/// The schedule of a run under `nemesis` with `n` replicas, drawn from `rng`.
pub fn schedule(nemesis: Nemesis, n: u64, rng: &mut Rng) -> Vec<Event> {
    let episodes = match nemesis {
        Nemesis::Mixed => rng.range(3, 9),
        Nemesis::Kill | Nemesis::DiskWrite | Nemesis::DiskFsync | Nemesis::DiskTorn => {
            rng.range(1, 5)
        }
        _ => rng.range(1, 4),
    };
    let mut events: Vec<Event> = (0..episodes)
        .map(|_| {
            let kind = match nemesis {
                Nemesis::Mixed => rng.pick(&Nemesis::ALL[..Nemesis::ALL.len() - 1]),
                k => k,
            };
            Event {
                at: Time::ms(rng.range(WINDOW.0, WINDOW.1)),
                action: action(kind, n, rng),
            }
        })
        .collect();
    events.sort_by_key(|e| e.at);
    events
}

fn action(kind: Nemesis, n: u64, rng: &mut Rng) -> Action {
    let target = |rng: &mut Rng| {
        if rng.chance(50) {
            Target::Leader
        } else {
            Target::Id(rng.range(1, n + 1))
        }
    };
    let t = target(rng);
    let d = rng.range(100, 2_500);
    match kind {
        Nemesis::Kill if rng.chance(50) => Action::Stop(t, d),
        Nemesis::Kill => Action::Kill(t),
        Nemesis::Pause => Action::Pause(t, d),
        Nemesis::Partition => {
            let (a, b) = split(n, rng);
            Action::Partition(a, b, d)
        }
        Nemesis::OneWay if rng.chance(25) => Action::Mute(t, d),
        Nemesis::OneWay if rng.chance(33) => Action::Deafen(t, d),
        Nemesis::OneWay => {
            let to = rng.range(1, n + 1);
            let from = if rng.chance(50) {
                Target::Leader
            } else {
                Target::Id(to % n + 1)
            };
            Action::Cut(from, Target::Id(to), d)
        }
        Nemesis::LeaderIsolated => Action::Isolate(Target::Leader, d),
        Nemesis::MajoritySplit if n == 5 && rng.chance(50) => Action::Ring(d),
        Nemesis::MajoritySplit => Action::Bridge(t, d),
        Nemesis::Slow => Action::Net(NetFault::Slow, d),
        Nemesis::Lossy => Action::Net(NetFault::Lossy(rng.range(10, 70) as u8), d),
        Nemesis::Duplicate => Action::Net(NetFault::Dup(rng.range(10, 60) as u8), d),
        Nemesis::Reorder => Action::Net(NetFault::Reorder, d),
        Nemesis::Clock => Action::Clock(
            t,
            match rng.range(0, 3) {
                0 => ClockFault::Fast(rng.range(2, 9) as u32, d),
                1 => ClockFault::Stall(d),
                _ => ClockFault::Jump(rng.range(5, 40) as u32),
            },
        ),
        Nemesis::DiskWrite => Action::Disk(t, DiskFault::FailWrite, rng.range(1, 9) as u32),
        Nemesis::DiskFsync => Action::Disk(t, DiskFault::FailFsync, rng.range(1, 9) as u32),
        Nemesis::DiskTorn if rng.chance(25) => Action::Power(t),
        Nemesis::DiskTorn => Action::Disk(t, DiskFault::Torn, rng.range(1, 9) as u32),
        Nemesis::Mixed => Action::Kill(t),
    }
}

/// Replicas `1..=n` in two non-empty groups.
fn split(n: u64, rng: &mut Rng) -> (Vec<u64>, Vec<u64>) {
    loop {
        let mask = rng.range(1, (1 << n) - 1);
        let (a, b): (Vec<u64>, Vec<u64>) = (1..=n).partition(|i| mask & (1 << (i - 1)) != 0);
        if !a.is_empty() && !b.is_empty() {
            return (a, b);
        }
    }
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Target::Id(id) => write!(f, "{id}"),
            Target::Leader => write!(f, "leader"),
        }
    }
}

fn ids(ids: &[u64]) -> String {
    ids.iter().map(u64::to_string).collect::<Vec<_>>().join(",")
}

impl fmt::Display for Action {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Action::Kill(t) => write!(f, "kill {t}"),
            Action::Stop(t, d) => write!(f, "stop {t} for {d}ms"),
            Action::Pause(t, d) => write!(f, "pause {t} for {d}ms"),
            Action::Partition(a, b, d) => write!(f, "partition {}|{} for {d}ms", ids(a), ids(b)),
            Action::Cut(a, b, d) => write!(f, "cut {a}>{b} for {d}ms"),
            Action::Mute(t, d) => write!(f, "mute {t} for {d}ms"),
            Action::Deafen(t, d) => write!(f, "deafen {t} for {d}ms"),
            Action::Isolate(t, d) => write!(f, "isolate {t} for {d}ms"),
            Action::Bridge(t, d) => write!(f, "bridge {t} for {d}ms"),
            Action::Ring(d) => write!(f, "ring for {d}ms"),
            Action::Net(NetFault::Slow, d) => write!(f, "net slow for {d}ms"),
            Action::Net(NetFault::Lossy(p), d) => write!(f, "net lossy {p}% for {d}ms"),
            Action::Net(NetFault::Dup(p), d) => write!(f, "net dup {p}% for {d}ms"),
            Action::Net(NetFault::Reorder, d) => write!(f, "net reorder for {d}ms"),
            Action::Clock(t, ClockFault::Fast(k, d)) => write!(f, "clock {t} fast {k}x for {d}ms"),
            Action::Clock(t, ClockFault::Stall(d)) => write!(f, "clock {t} stall for {d}ms"),
            Action::Clock(t, ClockFault::Jump(k)) => write!(f, "clock {t} jump {k}"),
            Action::Disk(t, fault, nth) => write!(f, "disk {t} {} {nth}", fault.name()),
            Action::Power(t) => write!(f, "power {t}"),
        }
    }
}

impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "@{}ms {}", self.at.as_ms(), self.action)
    }
}

/// A schedule as text, `; ` between events.
pub fn text(events: &[Event]) -> String {
    events
        .iter()
        .map(Event::to_string)
        .collect::<Vec<_>>()
        .join("; ")
}

/// Why a schedule's text does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("event {index} `{text}`: {why}")]
pub struct ParseError {
    /// The event's place in the text, from 1.
    pub index: usize,
    /// The event's text.
    pub text: String,
    /// What is wrong.
    pub why: String,
}

/// Reads a schedule (events separated by `;` or new lines) for `n` replicas.
pub fn parse(text: &str, n: u64) -> Result<Vec<Event>, ParseError> {
    text.split([';', '\n'])
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .enumerate()
        .map(|(i, t)| {
            parse_event(t, n).map_err(|why| ParseError {
                index: i + 1,
                text: t.to_string(),
                why,
            })
        })
        .collect()
}

fn parse_event(text: &str, n: u64) -> Result<Event, String> {
    let words: Vec<&str> = text.split_whitespace().collect();
    let at = words
        .first()
        .and_then(|w| w.strip_prefix('@'))
        .and_then(|w| w.strip_suffix("ms"))
        .and_then(|w| w.parse::<u64>().ok())
        .ok_or("it must start with its time, as `@1200ms`")?;
    let target = |w: &str| -> Result<Target, String> {
        match w {
            "leader" => Ok(Target::Leader),
            _ => match w.parse::<u64>() {
                Ok(id) if (1..=n).contains(&id) => Ok(Target::Id(id)),
                _ => Err(format!("`{w}` is no replica (1 to {n}, or `leader`)")),
            },
        }
    };
    let action = parse_action(&words[1..], &target)?;
    Ok(Event {
        at: Time::ms(at),
        action,
    })
}

fn parse_action(
    w: &[&str],
    target: &dyn Fn(&str) -> Result<Target, String>,
) -> Result<Action, String> {
    // The duration of an action that lasts: its last two words, `for 800ms`.
    let dur = |w: &[&str]| -> Result<u64, String> {
        match w {
            [.., "for", d] => d
                .strip_suffix("ms")
                .and_then(|d| d.parse().ok())
                .ok_or(format!("`{d}` is no duration (as `800ms`)")),
            _ => Err("it needs a duration, as `for 800ms`".into()),
        }
    };
    let num = |s: &str| -> Result<u64, String> {
        s.trim_end_matches(['%', 'x'])
            .parse()
            .map_err(|_| format!("`{s}` is no number"))
    };
    let group = |s: &str| -> Result<Vec<u64>, String> {
        s.split(',')
            .map(|id| match target(id)? {
                Target::Id(id) => Ok(id),
                Target::Leader => Err("a group lists replica ids".to_string()),
            })
            .collect()
    };
    Ok(match w {
        ["kill", t] => Action::Kill(target(t)?),
        ["stop", t, ..] => Action::Stop(target(t)?, dur(w)?),
        ["pause", t, ..] => Action::Pause(target(t)?, dur(w)?),
        ["partition", groups, ..] => {
            let (a, b) = groups
                .split_once('|')
                .ok_or("a partition is two groups, as `1,2|3`")?;
            Action::Partition(group(a)?, group(b)?, dur(w)?)
        }
        ["cut", link, ..] => {
            let (a, b) = link.split_once('>').ok_or("a cut is `from>to`")?;
            Action::Cut(target(a)?, target(b)?, dur(w)?)
        }
        ["isolate", t, ..] => Action::Isolate(target(t)?, dur(w)?),
        ["mute", t, ..] => Action::Mute(target(t)?, dur(w)?),
        ["deafen", t, ..] => Action::Deafen(target(t)?, dur(w)?),
        ["bridge", t, ..] => Action::Bridge(target(t)?, dur(w)?),
        ["ring", ..] => Action::Ring(dur(w)?),
        ["net", "slow", ..] => Action::Net(NetFault::Slow, dur(w)?),
        ["net", "lossy", p, ..] => Action::Net(NetFault::Lossy(num(p)?.min(100) as u8), dur(w)?),
        ["net", "dup", p, ..] => Action::Net(NetFault::Dup(num(p)?.min(100) as u8), dur(w)?),
        ["net", "reorder", ..] => Action::Net(NetFault::Reorder, dur(w)?),
        ["clock", t, "fast", k, ..] => {
            Action::Clock(target(t)?, ClockFault::Fast(num(k)? as u32, dur(w)?))
        }
        ["clock", t, "stall", ..] => Action::Clock(target(t)?, ClockFault::Stall(dur(w)?)),
        ["clock", t, "jump", k] => Action::Clock(target(t)?, ClockFault::Jump(num(k)? as u32)),
        ["disk", t, fault, nth] => {
            let f = DiskFault::from_name(fault).ok_or(format!(
                "`{fault}` is no disk fault (fail-write, fail-fsync, torn)"
            ))?;
            Action::Disk(target(t)?, f, num(nth)?.max(1) as u32)
        }
        ["power", t] => Action::Power(target(t)?),
        _ => return Err("no such action".into()),
    })
}

impl FromStr for Nemesis {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Nemesis::from_name(s).ok_or(format!("no nemesis `{s}` (one of {})", Nemesis::names()))
    }
}
