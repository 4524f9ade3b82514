//! The supervisor library behind `hnav run` and `hnav ps`: it starts the run's processes (the
//! sim, the coordinator, one agent per robot) from binaries next to its own executable,
//! watches them, restarts what dies under the scenario's restart policy, and stops everything
//! cleanly.
//!
//! It builds on `hnav-runtime` (launch, msg, topics, transport, scenario, consensus_log) and,
//! in this crate, on `report`, `recording` and `invocation`. The processes of a run never
//! link it; the `hnav` binary drives it, [`crate::monitor`] reads its registry, and
//! `hnav-bench round` borrows its pieces to stand in for it.
//!
//! Modules, highest first (a module uses only those below it in this table):
//!
//! | module | what it holds |
//! |---|---|
//! | [`replay`] | `hnav log replay`: a lockstep run started again from its invocation, its log compared with the original's |
//! | [`run`] | `hnav run`: spawn, start-up handshake, watch and restart, faults, stop, summary |
//! | [`kill`] | `hnav kill`: a signal to one process of a live run found in the registry, recorded in its journal |
//! | [`ps`] | what `hnav ps` shows: each registered process as running, exited or dead, as JSON or a table |
//! | [`services`] | what `hnav services RUN` shows: a live run's topics with their publishers and subscribers |
//! | [`clean`] | removing what a dead run left: leftover processes, shared memory, iceoryx2 files, registry entry |
//! | [`registry`] | the on-disk list of live runs and their processes that `hnav ps` reads |
//! | [`summary`] | the run summary (`summary.json`): per-agent steps, length, conflicts, replans from the consensus log; goals and collisions from ground truth |
//! | [`recorder`] | the recorder thread: ground truth, estimates and neural maps into `DIR/recording/` by simulated time |
//! | [`startup`] | the supervisor's half of the lifecycle protocol: the start-up handshake and the events it publishes |
//! | [`stop`] | the escalating stop of a run's children: wait, SIGTERM, SIGKILL, reap |
//! | [`restart`] | per-child restart decisions: policy, cap, doubling backoff |
//! | [`child`] | one child process: spawn in its own process group with an appended log, reap, describe its exit, signal it or its group |
//! | [`exit_fd`] | the pidfd (or waiter-thread pipe) that makes a child's exit wake the supervisor's `Waiter` |
//! | [`events`] | the run's event journal `DIR/events.jsonl`: signals, exits, hangs, respawns, each stamped with the host's monotonic clock |
//! | [`run_dir`] | a run's hold on its output directory: the directory lock, and `--force` for a finished run's outputs |
//! | [`proc_stat`] | a process as `/proc` sees it: alive, its start time (a reused pid is not the process), its CPU time |

pub mod child;
pub mod clean;
pub mod events;
pub mod exit_fd;
pub mod kill;
pub mod proc_stat;
pub mod ps;
pub mod recorder;
pub mod registry;
pub mod replay;
pub mod restart;
pub mod run;
pub mod run_dir;
pub mod services;
pub mod startup;
pub mod stop;
pub mod summary;
