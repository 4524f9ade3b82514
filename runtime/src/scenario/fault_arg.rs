//! Faults written on the command line: the one parser behind `hnav run --kill/--term/--freeze`
//! and `hnav kill`'s target.
//!
//! ```text
//! TARGET@WHEN            --kill agent:3@round:40   --term coordinator@2.5s   --kill sim@round:200
//! TARGET@WHEN+SECONDSs   --freeze agent:5@round:60+3s   (no +...: never continued)
//! TARGET                 agent:N | coordinator | sim
//! WHEN                   round:R (once round R is committed) | SECONDSs (after Start)
//! ```
//!
//! A fault parsed here is the same [`FaultSpec`] a scenario's `[[faults]]` entry gives, with
//! the same rules for its numbers ([`check_at_s`], [`check_for_s`]). The supervisor hands the
//! command line's faults on to every process (`--fault FLAG=VALUE`, [`to_process_arg`],
//! [`parse_process_arg`]) so that they all see one fault plan: the lockstep sim holds at the
//! faults' rounds, the coordinator's log header hashes them.

use super::{FaultAction, FaultSignal, FaultSpec, FaultTarget, FaultTime};

/// The flag a fault was written with.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum FaultFlag {
    /// `--kill`: SIGKILL.
    Kill,
    /// `--term`: SIGTERM.
    Term,
    /// `--freeze`: SIGSTOP, and SIGCONT after the `+SECONDSs` if given.
    Freeze,
}

impl FaultFlag {
    /// All flags, in the order `hnav run --help` lists them.
    pub const ALL: [FaultFlag; 3] = [FaultFlag::Kill, FaultFlag::Term, FaultFlag::Freeze];

    /// The flag's name without dashes: `kill`, `term`, `freeze`.
    pub fn name(self) -> &'static str {
        match self {
            FaultFlag::Kill => "kill",
            FaultFlag::Term => "term",
            FaultFlag::Freeze => "freeze",
        }
    }

    fn from_name(name: &str) -> Option<FaultFlag> {
        FaultFlag::ALL.into_iter().find(|f| f.name() == name)
    }

    fn expected(self) -> &'static str {
        match self {
            FaultFlag::Freeze => "expected TARGET@WHEN[+SECONDSs], e.g. agent:5@round:60+3s",
            _ => "expected TARGET@WHEN, e.g. agent:3@round:40",
        }
    }
}

/// A fault argument that cannot be used; the message names the argument as written.
#[derive(Clone, PartialEq, Eq, Debug, thiserror::Error)]
#[error("{arg}: {problem}")]
pub struct FaultArgError {
    /// The argument: `--kill agent:9@round:40`.
    pub arg: String,
    /// What is wrong with it.
    pub problem: String,
}

/// Parses the value of `--kill`, `--term` or `--freeze`.
pub fn parse(flag: FaultFlag, value: &str) -> Result<FaultSpec, FaultArgError> {
    parse_value(flag, value).map_err(|problem| FaultArgError {
        arg: format!("--{} {value}", flag.name()),
        problem,
    })
}

fn parse_value(flag: FaultFlag, value: &str) -> Result<FaultSpec, String> {
    let Some((target, when)) = value.split_once('@') else {
        return Err(flag.expected().into());
    };
    if target.is_empty() || when.is_empty() {
        return Err(flag.expected().into());
    }
    let target = parse_target(target)?;
    let (when, for_s) = match when.split_once('+') {
        None => (when, None),
        Some((_, d)) if flag != FaultFlag::Freeze => {
            return Err(format!("`+{d}`: only --freeze takes a duration"));
        }
        Some((w, d)) => (w, Some(parse_duration(d)?)),
    };
    let at = parse_when(when)?;
    let action = match flag {
        FaultFlag::Kill => FaultAction::Kill(FaultSignal::Kill),
        FaultFlag::Term => FaultAction::Kill(FaultSignal::Term),
        FaultFlag::Freeze => FaultAction::Freeze { for_s },
    };
    Ok(FaultSpec { at, action, target })
}

/// Parses `agent:N`, `coordinator`, `coordinator:ID` (a replica) or `sim`; the error says
/// what is wrong.
pub fn parse_target(text: &str) -> Result<FaultTarget, String> {
    match text {
        "coordinator" => return Ok(FaultTarget::Coordinator),
        "sim" => return Ok(FaultTarget::Sim),
        "agent" => return Err("`agent` needs its number: agent:N, e.g. agent:3".into()),
        _ => {}
    }
    if let Some(id) = text.strip_prefix("coordinator:") {
        return match id.parse() {
            Ok(id) if (1..=crate::msg::MAX_REPLICAS).contains(&id) => Ok(FaultTarget::Replica(id)),
            _ => Err(format!(
                "`{id}` is not a coordinator replica: coordinator:ID, ID 1 to {}",
                crate::msg::MAX_REPLICAS
            )),
        };
    }
    match text.strip_prefix("agent:") {
        Some(n) => n
            .parse()
            .map(FaultTarget::Agent)
            .map_err(|_| format!("`{n}` is not an agent number")),
        None => Err(format!(
            "unknown target `{text}`: expected agent:N, coordinator, coordinator:ID or sim"
        )),
    }
}

fn parse_when(text: &str) -> Result<FaultTime, String> {
    if let Some(r) = text.strip_prefix("round:") {
        return r
            .parse()
            .map(FaultTime::Round)
            .map_err(|_| format!("`{r}` is not a round number"));
    }
    let secs = text
        .strip_suffix('s')
        .and_then(|n| n.parse::<f64>().ok())
        .ok_or_else(|| {
            format!("unknown time `{text}`: expected round:R or SECONDSs, e.g. round:40 or 2.5s")
        })?;
    check_at_s(secs).map_err(|p| format!("time `{text}` {p}"))?;
    Ok(FaultTime::Seconds(secs))
}

fn parse_duration(text: &str) -> Result<f64, String> {
    let secs = text
        .strip_suffix('s')
        .and_then(|n| n.parse::<f64>().ok())
        .ok_or_else(|| format!("`+{text}`: expected +SECONDSs, e.g. +3s"))?;
    check_for_s(secs).map_err(|p| format!("duration `+{text}` {p}"))?;
    Ok(secs)
}

/// Checks the number of seconds after `Start` a fault fires at; the error completes "`at_s`
/// ..." or "time `2.5s` ...".
pub fn check_at_s(secs: f64) -> Result<(), String> {
    if secs.is_finite() && secs >= 0.0 {
        Ok(())
    } else {
        Err(format!(
            "must be a finite number of seconds >= 0, got {}",
            super::error::number(secs)
        ))
    }
}

/// Checks how long a freeze lasts.
pub fn check_for_s(secs: f64) -> Result<(), String> {
    if secs.is_finite() && secs > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "must be a positive, finite number of seconds, got {}",
            super::error::number(secs)
        ))
    }
}

/// Refuses a fault parsed from `--FLAG value` whose agent the scenario of `agents` agents
/// does not have.
pub fn check_target(
    flag: FaultFlag,
    value: &str,
    fault: &FaultSpec,
    agents: usize,
) -> Result<(), FaultArgError> {
    match fault.target {
        FaultTarget::Agent(i) if i >= agents => Err(FaultArgError {
            arg: format!("--{} {value}", flag.name()),
            problem: agents_problem(agents),
        }),
        _ => Ok(()),
    }
}

/// "the scenario has 8 agents (0-7)": what a target beyond the agents is told.
pub fn agents_problem(agents: usize) -> String {
    match agents {
        0 => "the scenario has no agents".into(),
        1 => "the scenario has 1 agent (0)".into(),
        n => format!("the scenario has {n} agents (0-{})", n - 1),
    }
}

/// The flag and value that [`parse`] reads back as `fault`.
pub fn to_arg(fault: &FaultSpec) -> (FaultFlag, String) {
    let target = target_arg(fault.target);
    // `{}` of an f64 prints the shortest text that parses back to the same number.
    let when = match fault.at {
        FaultTime::Round(r) => format!("round:{r}"),
        FaultTime::Seconds(s) => format!("{s}s"),
    };
    let (flag, tail) = match fault.action {
        FaultAction::Kill(FaultSignal::Kill) => (FaultFlag::Kill, String::new()),
        FaultAction::Kill(FaultSignal::Term) => (FaultFlag::Term, String::new()),
        FaultAction::Freeze { for_s: None } => (FaultFlag::Freeze, String::new()),
        FaultAction::Freeze { for_s: Some(d) } => (FaultFlag::Freeze, format!("+{d}s")),
    };
    (flag, format!("{target}@{when}{tail}"))
}

/// The target as the command line writes it, which [`parse_target`] reads back: `agent:3`,
/// `coordinator`, `sim`.
pub fn target_arg(target: FaultTarget) -> String {
    match target {
        FaultTarget::Agent(i) => format!("agent:{i}"),
        FaultTarget::Coordinator => "coordinator".into(),
        FaultTarget::Replica(id) => format!("coordinator:{id}"),
        FaultTarget::Sim => "sim".into(),
    }
}

/// `fault` as the supervisor passes it to the processes: `kill=agent:3@round:40`.
pub fn to_process_arg(fault: &FaultSpec) -> String {
    let (flag, value) = to_arg(fault);
    format!("{}={value}", flag.name())
}

/// Reads a fault the supervisor passed on ([`to_process_arg`]).
pub fn parse_process_arg(text: &str) -> Result<FaultSpec, String> {
    let (flag, value) = text
        .split_once('=')
        .and_then(|(f, v)| Some((FaultFlag::from_name(f)?, v)))
        .ok_or_else(|| format!("`{text}`: expected kill=, term= or freeze= and a fault"))?;
    parse(flag, value).map_err(|e| e.to_string())
}

impl std::fmt::Display for FaultSpec {
    /// As on the command line: `--kill agent:3@round:40`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (flag, value) = to_arg(self);
        write!(f, "--{} {value}", flag.name())
    }
}

#[cfg(test)]
mod tests;
