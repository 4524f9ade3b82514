//! `hnav kill RUN TARGET [--signal KILL|TERM|STOP|CONT]`: a signal to one process of a live
//! run. The work is in `hnav_operator::supervisor::kill`.
//!
//! Exit codes: 0 the signal was sent (and recorded in the run's `events.jsonl`), 2 nothing
//! was sent: a bad target, a run the registry does not know or whose supervisor is dead, a
//! target the run does not have or that is not running.

use std::process::ExitCode;

use hnav_operator::supervisor::child::Signal;
use hnav_operator::supervisor::kill::kill;
use hnav_operator::supervisor::registry::RunRegistry;
use hnav_runtime::scenario::fault_arg::parse_target;

/// The signals `hnav kill` sends.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum KillSignal {
    /// SIGKILL: the process dies at once; the supervisor restarts it under its policy.
    #[value(name = "KILL")]
    Kill,
    /// SIGTERM: the process stops politely (and is restarted under `always` only).
    #[value(name = "TERM")]
    Term,
    /// SIGSTOP: the process freezes until SIGCONT (or until it is declared hung).
    #[value(name = "STOP")]
    Stop,
    /// SIGCONT: a frozen process goes on.
    #[value(name = "CONT")]
    Cont,
}

impl KillSignal {
    fn signal(self) -> Signal {
        match self {
            KillSignal::Kill => Signal::SIGKILL,
            KillSignal::Term => Signal::SIGTERM,
            KillSignal::Stop => Signal::SIGSTOP,
            KillSignal::Cont => Signal::SIGCONT,
        }
    }
}

/// `hnav kill` arguments.
#[derive(clap::Args, Debug)]
pub struct KillArgs {
    /// The run id, as `hnav ps` lists it.
    pub run: String,
    /// The process: agent:N, coordinator, coordinator:ID (a replica) or sim.
    pub target: String,
    /// The signal to send.
    #[arg(long, value_enum, default_value = "KILL", ignore_case = true)]
    pub signal: KillSignal,
}

/// Signals the target of a run of `$HNAV_RUNS_DIR` (default `<temp dir>/hnav-runs`).
pub fn run(a: KillArgs) -> ExitCode {
    hnav_runtime::logging::init();
    let target = match parse_target(&a.target) {
        Ok(t) => t,
        Err(problem) => {
            hnav_runtime::errln!("error: {}: {problem}", a.target);
            return ExitCode::from(2);
        }
    };
    match kill(
        &RunRegistry::default_location(),
        &a.run,
        target,
        a.signal.signal(),
    ) {
        Ok(k) => {
            let shared = match k.robots.as_slice() {
                [first, .., last] => format!(", the process of agents {first} to {last}"),
                _ => String::new(),
            };
            hnav_runtime::outln!(
                "sent {} to {} (pid {}{shared}) of run {} at round {}; recorded in {}",
                k.signal,
                a.target,
                k.pid,
                a.run,
                k.round,
                k.journal.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
