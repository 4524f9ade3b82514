//! Placement: which host runs which process of a run, and how the hosts' bridges reach each
//! other (`hosts.toml`, read by `hnav run --host NAME` and by `hnav-bridge --hosts`).
//!
//! ```toml
//! # The base station: the sim and the coordinator (all its replicas).
//! [[host]]
//! name = "base"
//! listen = ["tcp/10.0.0.1:7447"]
//! sim = true
//! coordinator = true
//!
//! # A robot's computer: its agent.
//! [[host]]
//! name = "robot-0"
//! agents = "0"            # or a list: [0, 1], or ranges: "0-7,9"
//! ```
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
    /// Whether it runs the coordinator (every replica of it).
    pub coordinator: bool,
    /// The agents it runs, ascending.
    pub agents: Vec<u32>,
}

impl Host {
    /// Whether it runs process `role`/`index` (any replica of the coordinator).
    pub fn runs(&self, role: Role, index: u32) -> bool {
        match role {
            Role::Sim => self.sim,
            Role::Coordinator => self.coordinator,
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
    coordinator: bool,
    #[serde(default)]
    agents: Option<Spanned<RawAgents>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawAgents {
    List(Vec<u32>),
    Ranges(String),
}

impl Placement {
    /// Reads and checks `path` for a run of `agents` agents.
    pub fn load(path: &Path, agents: usize) -> Result<Self, PlacementError> {
        let text = std::fs::read_to_string(path).map_err(|e| PlacementError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Self::parse(&text, &path.display().to_string(), agents)
    }

    /// Parses and checks `text` (named `file` in errors) for a run of `agents` agents.
    pub fn parse(text: &str, file: &str, agents: usize) -> Result<Self, PlacementError> {
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
        let mut agent_host: Vec<Option<usize>> = vec![None; agents];
        let (mut sim, mut coordinator) = (None::<usize>, None::<usize>);
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
            for (flag, holder, what) in [
                (h.sim, &mut sim, "the sim"),
                (h.coordinator, &mut coordinator, "the coordinator"),
            ] {
                if let (true, Some(other)) = (flag, *holder) {
                    let other = &hosts[other].name;
                    return Err(invalid(
                        start,
                        format!("{what} is on host `{other}` already"),
                    ));
                }
                if flag {
                    *holder = Some(i);
                }
            }
            let mine = match &h.agents {
                None => Vec::new(),
                Some(a) => parse_agents(a.get_ref(), agents)
                    .map_err(|what| invalid(a.span().start, what))?,
            };
            for &a in &mine {
                if let Some(other) = agent_host[a as usize].replace(i) {
                    let other = &hosts.get(other).map_or(name, |o| &o.name);
                    return Err(invalid(
                        h.agents.as_ref().map_or(start, |s| s.span().start),
                        format!("agent {a} is on host `{other}` already"),
                    ));
                }
            }
            hosts.push(Host {
                name: name.clone(),
                listen,
                sim: h.sim,
                coordinator: h.coordinator,
                agents: mine,
            });
        }
        let unplaced = |what: String| PlacementError::Unplaced {
            file: file.to_string(),
            what,
        };
        if sim.is_none() {
            return Err(unplaced("the sim".into()));
        }
        if coordinator.is_none() {
            return Err(unplaced("the coordinator".into()));
        }
        if let Some(a) = agent_host.iter().position(Option::is_none) {
            return Err(unplaced(format!("agent {a} (the run has {agents} agents)")));
        }
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

/// The agents of `raw`, ascending and each once, all below `agents`.
fn parse_agents(raw: &RawAgents, agents: usize) -> Result<Vec<u32>, String> {
    let mut out = match raw {
        RawAgents::List(v) => v.clone(),
        RawAgents::Ranges(s) => {
            let mut out = Vec::new();
            for part in s.split(',').map(str::trim) {
                let bad = || format!("agents `{s}`: `{part}` is no index or range `A-B`");
                let (a, b) = match part.split_once('-') {
                    Some((a, b)) => (a.trim(), b.trim()),
                    None => (part, part),
                };
                let (a, b): (u32, u32) =
                    (a.parse().map_err(|_| bad())?, b.parse().map_err(|_| bad())?);
                if a > b || b as usize >= agents {
                    return Err(format!(
                        "agents `{s}`: `{part}` is not within 0-{} (the run has {agents} agents)",
                        agents.saturating_sub(1)
                    ));
                }
                out.extend(a..=b);
            }
            out
        }
    };
    if let Some(&a) = out.iter().find(|&&a| a as usize >= agents) {
        return Err(format!(
            "agent {a}: the run has {agents} agents (0-{})",
            agents.saturating_sub(1)
        ));
    }
    out.sort_unstable();
    if let Some(w) = out.windows(2).find(|w| w[0] == w[1]) {
        return Err(format!("agent {} is listed twice", w[0]));
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
        let p = Placement::parse(THREE, "hosts.toml", 4).unwrap();
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
            Placement::parse(text, "h.toml", agents)
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
}
