//! Placement: which host runs which process of a run, and how the hosts' bridges reach each
//! other (`hosts.toml`, read by `hnav run --host NAME` and by `hnav-bridge --hosts`).
//!
//! ```toml
//! # The base station: the sim and the coordinator (all its replicas).
//! [[host]]
//! name = "base"
//! listen = ["tcp/10.0.0.1:7447"]
//! sim = true
//! coordinator = true      # or some replicas by Raft id: [1], "1-2"
//!
//! # A robot's computer: its agent.
//! [[host]]
//! name = "robot-0"
//! agents = "0"            # or a list: [0, 1], or ranges: "0-7,9"
//! ```
//!
//! `coordinator = true` puts every replica of the coordinator on the host (the single
//! coordinator of a run without replicas); a list or ranges of Raft ids (1 to the run's
//! `replicas`) puts those replicas there, so that replicas can live on hosts of their own and
//! their Raft messages cross the bridges. Each replica runs on exactly one host.
//!
//! The hosts form a star: the first host (the hub, normally the base station) listens on its
//! `listen` endpoints as a Zenoh router, and every other host connects to it as a Zenoh
//! client, so that only the hub's address need be known and a host that drops away touches
//! nothing but its own link. (A full mesh of Zenoh peers was used before: with it, one peer
//! cut off could stall the traffic between the two still linked for as long as it was away;
//! see `docs/explanation/between-hosts.md`.) Only the hub has `listen`. Each process runs on
//! exactly one host; the file is checked against the run's agent count before anything
//! starts, and every problem names the file and line.

use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::msg::Role;
use crate::scenario::lines::Lines;
use crate::scenario::Loc;
use crate::transport::is_domain_name;

/// The file `hnav run --host` reads when no `--hosts` is given: `hosts.toml` beside the
/// scenario.
pub const DEFAULT_FILE: &str = "hosts.toml";

/// Why a placement is unusable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlacementError {
    /// The file could not be read.
    #[error("{}: cannot read the placement: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's words.
        message: String,
    },
    /// Not TOML, or not the placement's shape (an unknown key, a wrong type).
    #[error("{at}: {message}")]
    Toml {
        /// Where.
        at: Loc,
        /// The parser's words.
        message: String,
    },
    /// A value that parses but cannot be (a bad name, an agent out of range, a duplicate).
    #[error("{at}: {what}")]
    Invalid {
        /// Where.
        at: Loc,
        /// What is wrong.
        what: String,
    },
    /// A process no host runs.
    #[error("{file}: no host runs {what}")]
    Unplaced {
        /// The file.
        file: String,
        /// The process (`the sim`, `agent 3`).
        what: String,
    },
    /// Robots that share an agent process (`[run] agents_per_process`) placed on two hosts.
    #[error(
        "{file}: agents {a} and {b} share an agent process ([run] agents_per_process = {per}) \
         but run on hosts `{host_a}` and `{host_b}`: place each process's robots on one host"
    )]
    SplitProcess {
        /// The file.
        file: String,
        /// The scenario's robots per process.
        per: u32,
        /// The process's first robot.
        a: u32,
        /// A robot of it on another host.
        b: u32,
        /// The first robot's host.
        host_a: String,
        /// The other robot's host.
        host_b: String,
    },
    /// `--host NAME` names no host of the file.
    #[error("{file}: no host is named `{name}` (hosts: {known})")]
    NoSuchHost {
        /// The file.
        file: String,
        /// The name asked for.
        name: String,
        /// The names the file has.
        known: String,
    },
}

/// One host of a run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Host {
    /// Its name: 1 to 16 ASCII letters, digits, `-`, `_` (the spelling of an iceoryx2
    /// domain, so that hosts sharing one machine can use it as theirs).
    pub name: String,
    /// The Zenoh endpoints its bridge listens on (`tcp/10.0.0.1:7447`): the hub's only;
    /// empty for every other host.
    pub listen: Vec<String>,
    /// Whether it runs the sim.
    pub sim: bool,
    /// The coordinator processes it runs, ascending, by process index: `[0]` for the single
    /// coordinator of a run without replicas, else replica ids (1 to the run's replicas).
    pub coordinator: Vec<u32>,
    /// The agents it runs, ascending.
    pub agents: Vec<u32>,
}

impl Host {
    /// Whether it runs process `role`/`index` (a coordinator by process index: 0 for a single
    /// coordinator, else the replica's Raft id).
    pub fn runs(&self, role: Role, index: u32) -> bool {
        match role {
            Role::Sim => self.sim,
            Role::Coordinator => self.coordinator.binary_search(&index).is_ok(),
            Role::Agent => self.agents.binary_search(&index).is_ok(),
            Role::Bridge => false,
        }
    }
}

/// A checked placement of a run's processes on hosts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Placement {
    hosts: Vec<Host>,
    file: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    host: Vec<Spanned<RawHost>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHost {
    name: Spanned<String>,
    #[serde(default)]
    listen: Option<Spanned<Vec<String>>>,
    #[serde(default)]
    sim: bool,
    #[serde(default)]
    coordinator: Option<Spanned<RawIds>>,
    #[serde(default)]
    agents: Option<Spanned<RawIds>>,
}

/// Indices as written: every one (`true`), none (`false`), a list or ranges.
#[derive(Deserialize)]
#[serde(untagged)]
enum RawIds {
    All(bool),
    List(Vec<u32>),
    Ranges(String),
}

/// The ids a key may name: `key` in `hosts.toml`, `noun` for one id, `first..=last` valid, a
/// run of `count` of them.
struct IdSpace {
    key: &'static str,
    noun: &'static str,
    first: u32,
    count: usize,
}

impl IdSpace {
    fn agents(count: usize) -> Self {
        Self {
            key: "agents",
            noun: "agent",
            first: 0,
            count,
        }
    }

    /// The replicas of a run of `replicas` (Raft ids from 1).
    fn replicas(replicas: u32) -> Self {
        Self {
            key: "coordinator",
            noun: "replica",
            first: 1,
            count: replicas as usize,
        }
    }

    fn last(&self) -> u32 {
        (self.first as usize + self.count).saturating_sub(1) as u32
    }

    fn range(&self) -> String {
        format!("{}-{}", self.first, self.last())
    }

    fn contains(&self, id: u32) -> bool {
        id >= self.first && (id as usize) < self.first as usize + self.count
    }
}

impl Placement {
    /// Reads and checks `path` for a run of `agents` agents and `replicas` coordinator
    /// replicas (1: a single coordinator).
    pub fn load(path: &Path, agents: usize, replicas: u32) -> Result<Self, PlacementError> {
        let text = std::fs::read_to_string(path).map_err(|e| PlacementError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Self::parse(&text, &path.display().to_string(), agents, replicas)
    }

    /// Parses and checks `text` (named `file` in errors) for a run of `agents` agents and
    /// `replicas` coordinator replicas (1: a single coordinator).
    pub fn parse(
        text: &str,
        file: &str,
        agents: usize,
        replicas: u32,
    ) -> Result<Self, PlacementError> {
        let lines = Lines::new(text, file);
        let at = |offset: usize| Loc::new(file, lines.line(offset));
        let raw: RawFile = toml::from_str(text).map_err(|e| PlacementError::Toml {
            at: at(e.span().map_or(0, |s| s.start)),
            message: e.message().trim().to_string(),
        })?;
        let invalid = |offset: usize, what: String| PlacementError::Invalid {
            at: at(offset),
            what,
        };
        let mut hosts: Vec<Host> = Vec::with_capacity(raw.host.len());
        let mut claims = Claims::new(agents, replicas);
        for (i, h) in raw.host.iter().enumerate() {
            let start = h.span().start;
            let h = h.get_ref();
            let name = h.name.get_ref();
            if !is_domain_name(name) {
                return Err(invalid(
                    h.name.span().start,
                    format!("host name `{name}`: 1 to 16 ASCII letters, digits, '-' and '_'"),
                ));
            }
            if let Some(first) = hosts.iter().position(|o| &o.name == name) {
                return Err(invalid(
                    h.name.span().start,
                    format!("host `{name}` again (host {} has that name)", first + 1),
                ));
            }
            let listen = check_listen(name, i, h.listen.as_ref())
                .map_err(|(at, what)| invalid(at.unwrap_or(start), what))?;
            let host = claims
                .claim(i, name, h, &hosts)
                .map_err(|(at, what)| invalid(at.unwrap_or(start), what))?;
            hosts.push(Host { listen, ..host });
        }
        claims
            .check_all_placed()
            .map_err(|what| PlacementError::Unplaced {
                file: file.to_string(),
                what,
            })?;
        Ok(Self {
            hosts,
            file: file.to_string(),
        })
    }

    /// The hosts, in the file's order.
    pub fn hosts(&self) -> &[Host] {
        &self.hosts
    }

    /// The index of host `name`, or an error that lists the names there are.
    pub fn index_of(&self, name: &str) -> Result<usize, PlacementError> {
        self.hosts
            .iter()
            .position(|h| h.name == name)
            .ok_or_else(|| PlacementError::NoSuchHost {
                file: self.file.clone(),
                name: name.to_string(),
                known: self
                    .hosts
                    .iter()
                    .map(|h| h.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// Whether the coordinator's replicas are on more than one host (their Raft messages then
    /// cross the bridges).
    pub fn replicas_apart(&self) -> bool {
        self.hosts
            .iter()
            .filter(|h| !h.coordinator.is_empty())
            .count()
            > 1
    }

    /// The host that runs `role`/`index`.
    pub fn host_of(&self, role: Role, index: u32) -> Option<&Host> {
        self.hosts.iter().find(|h| h.runs(role, index))
    }

    /// The endpoints host `i` connects to: the hub's, for every host but the hub.
    pub fn connect_of(&self, i: usize) -> Vec<String> {
        match i {
            0 => Vec::new(),
            _ => self.hosts[0].listen.clone(),
        }
    }

    /// Whether host `i` is the hub: the first host, the Zenoh router the others connect to.
    pub fn is_hub(&self, i: usize) -> bool {
        i == 0
    }
}

/// The `listen` of host number `i` (from 0) named `name`: the hub must listen somewhere, no
/// other host may (it would wait for connections that never come). An error is the line it
/// is on, if any, and what is wrong.
fn check_listen(
    name: &str,
    i: usize,
    listen: Option<&Spanned<Vec<String>>>,
) -> Result<Vec<String>, (Option<usize>, String)> {
    let at = listen.map(|l| l.span().start);
    let endpoints = listen.map_or_else(Vec::new, |l| l.get_ref().clone());
    match (i, endpoints.is_empty()) {
        (0, true) => Err((
            at,
            format!("host `{name}` is the hub (the first host) and listens nowhere: the others could not reach it"),
        )),
        (0, false) => Ok(endpoints),
        (_, _) if listen.is_none() => Ok(Vec::new()),
        (_, _) => Err((
            at,
            format!("host `{name}` has `listen`, but only the first host (the hub) listens: the others connect to it"),
        )),
    }
}

/// Which host holds each process so far, while the hosts are read in order.
struct Claims {
    agents: IdSpace,
    replicas: IdSpace,
    sim: Option<usize>,
    agent_host: Vec<Option<usize>>,
    /// By Raft id from 1 (index 0 unused).
    replica_host: Vec<Option<usize>>,
}

impl Claims {
    fn new(agents: usize, replicas: u32) -> Self {
        Self {
            agents: IdSpace::agents(agents),
            replicas: IdSpace::replicas(replicas),
            sim: None,
            agent_host: vec![None; agents],
            replica_host: vec![None; replicas as usize + 1],
        }
    }

    /// Host number `i` (named `name`, `h` as written; `before` are the hosts read so far)
    /// claims its processes; it comes back without its `listen`. An error is the offset of
    /// what is wrong, if known, and what.
    fn claim(
        &mut self,
        i: usize,
        name: &str,
        h: &RawHost,
        before: &[Host],
    ) -> Result<Host, (Option<usize>, String)> {
        let host_name = |other: usize| before.get(other).map_or(name, |o| &o.name).to_string();
        if h.sim {
            if let Some(other) = self.sim {
                let other = host_name(other);
                return Err((None, format!("the sim is on host `{other}` already")));
            }
            self.sim = Some(i);
        }
        let ids = |raw: &Option<Spanned<RawIds>>, space: &IdSpace| match raw {
            None => Ok(Vec::new()),
            Some(r) => parse_ids(r.get_ref(), space).map_err(|what| (Some(r.span().start), what)),
        };
        let agents = ids(&h.agents, &self.agents)?;
        let replicas = ids(&h.coordinator, &self.replicas)?;
        for (mine, holders, space, raw) in [
            (&agents, &mut self.agent_host, &self.agents, &h.agents),
            (
                &replicas,
                &mut self.replica_host,
                &self.replicas,
                &h.coordinator,
            ),
        ] {
            for &a in mine {
                if let Some(other) = holders[a as usize].replace(i) {
                    let other = host_name(other);
                    let at = raw.as_ref().map(|s| s.span().start);
                    let what = self_noun(space, a);
                    return Err((at, format!("{what} is on host `{other}` already")));
                }
            }
        }
        // A single coordinator is process 0; replicas are their Raft ids.
        let coordinator = match self.replicas.count {
            1 => replicas.iter().map(|_| 0).collect(),
            _ => replicas,
        };
        Ok(Host {
            name: name.to_string(),
            listen: Vec::new(),
            sim: h.sim,
            coordinator,
            agents,
        })
    }

    /// What no host runs, if anything: the first in the run's order.
    fn check_all_placed(&self) -> Result<(), String> {
        if self.sim.is_none() {
            return Err("the sim".into());
        }
        if let Some(r) = (1..self.replica_host.len()).find(|&r| self.replica_host[r].is_none()) {
            return Err(match self.replicas.count {
                1 => "the coordinator".into(),
                n => format!("replica {r} of the coordinator (the run has {n} replicas)"),
            });
        }
        if let Some(a) = self.agent_host.iter().position(Option::is_none) {
            let agents = self.agents.count;
            return Err(format!("agent {a} (the run has {agents} agents)"));
        }
        Ok(())
    }
}

/// One id of `space` in words (`agent 3`; `the coordinator` for a single one).
fn self_noun(space: &IdSpace, id: u32) -> String {
    match (space.key, space.count) {
        ("coordinator", 1) => "the coordinator".to_string(),
        _ => format!("{} {id}", space.noun),
    }
}

/// The ids of `raw` in `space`, ascending and each once (`true`: all of them).
fn parse_ids(raw: &RawIds, space: &IdSpace) -> Result<Vec<u32>, String> {
    let (key, noun, count) = (space.key, space.noun, space.count);
    let mut out = match raw {
        RawIds::All(true) => (space.first..=space.last()).take(count).collect(),
        RawIds::All(false) => Vec::new(),
        RawIds::List(v) => v.clone(),
        RawIds::Ranges(s) => {
            let mut out = Vec::new();
            for part in s.split(',').map(str::trim) {
                let bad = || format!("{key} `{s}`: `{part}` is no index or range `A-B`");
                let (a, b) = match part.split_once('-') {
                    Some((a, b)) => (a.trim(), b.trim()),
                    None => (part, part),
                };
                let (a, b): (u32, u32) =
                    (a.parse().map_err(|_| bad())?, b.parse().map_err(|_| bad())?);
                if a > b || !space.contains(a) || !space.contains(b) {
                    return Err(format!(
                        "{key} `{s}`: `{part}` is not within {} (the run has {count} {noun}s)",
                        space.range()
                    ));
                }
                out.extend(a..=b);
            }
            out
        }
    };
    if let Some(&a) = out.iter().find(|&&a| !space.contains(a)) {
        return Err(format!(
            "{noun} {a}: the run has {count} {noun}s ({})",
            space.range()
        ));
    }
    out.sort_unstable();
    if let Some(w) = out.windows(2).find(|w| w[0] == w[1]) {
        return Err(format!("{noun} {} is listed twice", w[0]));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const THREE: &str = r#"
[[host]]
name = "base"
listen = ["tcp/10.0.0.1:7447"]
sim = true
coordinator = true

[[host]]
name = "robots-a"
agents = "0-1"

[[host]]
name = "robots-b"
agents = [2, 3]
"#;

    #[test]
    fn a_placement_names_each_process_host_and_the_star() {
        let p = Placement::parse(THREE, "hosts.toml", 4, 3).unwrap();
        assert_eq!(p.hosts().len(), 3);
        assert_eq!(p.host_of(Role::Sim, 0).unwrap().name, "base");
        assert_eq!(p.host_of(Role::Coordinator, 2).unwrap().name, "base");
        assert_eq!(p.host_of(Role::Agent, 1).unwrap().name, "robots-a");
        assert_eq!(p.host_of(Role::Agent, 3).unwrap().name, "robots-b");
        assert!(p.connect_of(0).is_empty() && p.is_hub(0) && !p.is_hub(1));
        assert_eq!(p.connect_of(1), ["tcp/10.0.0.1:7447"]);
        assert_eq!(p.connect_of(2), ["tcp/10.0.0.1:7447"]);
        assert_eq!(p.index_of("robots-b").unwrap(), 2);
        let e = p.index_of("nope").unwrap_err().to_string();
        assert_eq!(
            e,
            "hosts.toml: no host is named `nope` (hosts: base, robots-a, robots-b)"
        );
    }

    #[test]
    fn bad_placements_name_the_file_line_and_problem() {
        let err = |text: &str, agents| {
            Placement::parse(text, "h.toml", agents, 1)
                .unwrap_err()
                .to_string()
        };
        // Agent 4 does not exist in a 4-agent run (line 16: the agents of robots-b).
        let e = err(&THREE.replace("[2, 3]", "[2, 3, 4]"), 4);
        assert_eq!(e, "h.toml:14: agent 4: the run has 4 agents (0-3)");
        // Nobody runs agent 3.
        let e = err(&THREE.replace("[2, 3]", "[2]"), 4);
        assert_eq!(e, "h.toml: no host runs agent 3 (the run has 4 agents)");
        // Two hosts claim agent 1.
        let e = err(&THREE.replace("[2, 3]", "[1, 2, 3]"), 4);
        assert_eq!(e, "h.toml:14: agent 1 is on host `robots-a` already");
        // A second sim.
        let e = err(
            &THREE.replace("agents = [2, 3]", "agents = [2, 3]\nsim = true"),
            4,
        );
        assert!(
            e.starts_with("h.toml:12: the sim is on host `base` already"),
            "{e}"
        );
        // A typo in a key.
        let e = err(
            &THREE.replace("listen = [\"tcp/10.0.0.1", "lisen = [\"tcp/10.0.0.1"),
            4,
        );
        assert!(e.starts_with("h.toml:4: unknown field `lisen`"), "{e}");
        // A bad range.
        let e = err(&THREE.replace("\"0-1\"", "\"1-x\""), 4);
        assert_eq!(
            e,
            "h.toml:10: agents `1-x`: `1-x` is no index or range `A-B`"
        );
        // A name that could not be a domain.
        let e = err(&THREE.replace("robots-a", "robots a"), 4);
        assert!(e.starts_with("h.toml:9: host name `robots a`"), "{e}");
        // The hub without a listen endpoint.
        let e = err(&THREE.replace("[\"tcp/10.0.0.1:7447\"]", "[]"), 4);
        assert!(
            e.starts_with("h.toml:4: host `base` is the hub (the first host) and listens nowhere"),
            "{e}"
        );
        // A robot host that listens: nobody would connect to it.
        let e = err(
            &THREE.replace(
                "agents = [2, 3]",
                "agents = [2, 3]\nlisten = [\"tcp/10.0.0.3:7447\"]",
            ),
            4,
        );
        assert!(
            e.starts_with("h.toml:15: host `robots-b` has `listen`, but only the first host"),
            "{e}"
        );
    }

    /// Three replicas on three hosts of their own, the sim and the agents on the hub.
    const SPREAD: &str = r#"
[[host]]
name = "base"
listen = ["tcp/10.0.0.1:7447"]
sim = true
agents = "0-3"

[[host]]
name = "r1"
coordinator = [1]

[[host]]
name = "r2"
coordinator = "2"

[[host]]
name = "r3"
coordinator = "3"
"#;

    #[test]
    fn replicas_may_each_have_a_host_of_their_own() {
        let p = Placement::parse(SPREAD, "hosts.toml", 4, 3).unwrap();
        for id in 1..=3 {
            let h = p.host_of(Role::Coordinator, id).unwrap();
            assert_eq!(h.name, format!("r{id}"));
            assert_eq!(h.coordinator, [id]);
        }
        assert_eq!(p.host_of(Role::Coordinator, 0), None);
        assert!(p.replicas_apart());
        assert!(p.hosts()[0].coordinator.is_empty());
        // `true` is every replica; in a run of one coordinator, `true` and `[1]` are it.
        let all = Placement::parse(THREE, "hosts.toml", 4, 5).unwrap();
        assert_eq!(all.hosts()[0].coordinator, [1, 2, 3, 4, 5]);
        assert!(!all.replicas_apart());
        let one = Placement::parse(THREE, "hosts.toml", 4, 1).unwrap();
        assert_eq!(one.host_of(Role::Coordinator, 0).unwrap().name, "base");
        let text = THREE.replace("coordinator = true", "coordinator = [1]");
        let one = Placement::parse(&text, "hosts.toml", 4, 1).unwrap();
        assert_eq!(one.hosts()[0].coordinator, [0]);
    }

    #[test]
    fn a_replica_unplaced_placed_twice_or_out_of_range_is_named_with_its_line() {
        let err = |text: &str, replicas| {
            Placement::parse(text, "h.toml", 4, replicas)
                .unwrap_err()
                .to_string()
        };
        // Nobody runs replica 3.
        let e = err(&SPREAD.replace("coordinator = \"3\"", ""), 3);
        assert_eq!(
            e,
            "h.toml: no host runs replica 3 of the coordinator (the run has 3 replicas)"
        );
        // Replica 2 on two hosts (line 18: r3's `coordinator`).
        let e = err(
            &SPREAD.replace("coordinator = \"3\"", "coordinator = \"2-3\""),
            3,
        );
        assert_eq!(e, "h.toml:18: replica 2 is on host `r2` already");
        // Replica 4 of a run of 3 (line 10: r1's list; line 14: r2's ranges).
        let e = err(&SPREAD.replace("[1]", "[1, 4]"), 3);
        assert_eq!(e, "h.toml:10: replica 4: the run has 3 replicas (1-3)");
        let e = err(&SPREAD.replace("\"2\"", "\"2-4\""), 3);
        assert_eq!(
            e,
            "h.toml:14: coordinator `2-4`: `2-4` is not within 1-3 (the run has 3 replicas)"
        );
        // No coordinator at all in a run without replicas.
        let e = err(&THREE.replace("coordinator = true", ""), 1);
        assert_eq!(e, "h.toml: no host runs the coordinator");
        // A single coordinator on two hosts.
        let e = err(
            &THREE.replace("agents = [2, 3]", "agents = [2, 3]\ncoordinator = true"),
            1,
        );
        assert_eq!(e, "h.toml:15: the coordinator is on host `base` already");
    }
}
