//! # hnav-bench
//!
//! Measurements of HNAV against its foundations, run by the `hnav-bench` binary
//! (`src/main.rs`, one clap subcommand per module here).
//!
//! **Must not depend on**: `hnav-tests` or `hnav-fuzz`: the benchmarks measure the product
//! crates (all of which it may use), and `hnav-tests` uses the chaos campaign from here.
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | subcommand | what it measures |
//! |---|---|---|
//! | [`perf`] | `hnav-bench perf [--quick] --out DIR` | the performance suite in one run: `latency`, `round` at 1 to 256 agents, `neural-map`; `DIR/perf.md` for `docs/explanation/performance.md` |
//! | [`fanout`] | `hnav-bench fanout [--listeners 1,8,32,128,256] [--mechanisms hnav,hnav-bell,eventfd,futex] [--quick] [--out DIR]` | waking N waiting agents per commit: HNAV's publish + notify with and without the commit bell, against one eventfd write and one futex wake; the notifier's cost and the last waiter's wake-up |
//! | [`round`] | `hnav-bench round [--agents 1,8,32,128,256] [--rounds N] [--fsync every-record,none] [--json] [--out DIR]`, `hnav-bench round --faults [--trials N]` | a decision round's latency against a real `hnav-coordinator` (all candidates in -> commit at every agent); SIGKILL -> `Down` detection and restarted agent -> first decision |
//! | [`chaos`] | `hnav-bench chaos [--runs N] [--seed S] [--quick] [--only N]` | a seeded campaign of runs with agents, the coordinator or the sim killed or frozen: per-run checks (at goal, no collision, log verifies, every commit seen once, nothing left behind), a table per class and mode, detection and recovery latencies |
//! | [`raft_sim`] | `hnav-bench raft-sim [--seeds N] [--first S] [--nemesis LIST] [--replicas 3\|5] [--jobs J] [--trace SCHEDULE] [--sabotage BUG]` | the deterministic simulation of the coordinator's replicated log: per nemesis, runs, faults injected, leaders elected, processes crashed, commits, violations and the slowest recovery; each failure's seed and shortest failing schedule |
//! | [`mapf`] | `hnav-bench mapf --map FILE --scen FILE [--agents 50,100] [--rules dissertation,pibt,lacam] [--json] [--out DIR] [--quick]`; `hnav-bench lacam [--map FILE --scen FILE --agents N] [--limit-s 10] [--memory-mib M] [--no-swap] [--points] [--json] [--quick]` | the first-N-entries MAPF instances of a MovingAI `.scen` run by whole swarms: robots at goal, collisions, makespan, sum of lengths against the lower bound, conflicts, replans, wall time, the processes' memory; and ([`mapf::search_only`]) the coordinator's LaCAM search alone (no robots, up to thousands of agents) in a child per instance: first solution's time and sum of costs over the lower bound, LaCAM*'s refinement within the limit, configurations, peak RSS (`docs/perf/lacam-search.txt`) |
//! | [`latency`] | `hnav-bench latency [--quick] --out DIR` | one-way and round-trip latency, 8 B to 40 MiB, of raw iceoryx2, the HNAV transport, a Unix domain socket, TCP loopback and the in-process floors (crossbeam channel, futex wake-up), in a two-thread ping-pong; CSV, markdown and an SVG plot |
//! | [`futex`] | — | the bare Linux futex: the floor `latency` and `fanout` read the other wake-up mechanisms against |
//! | [`experiment`] | `hnav-bench experiment <name> [--quick] [--json] [--seed S]` | the seeds' experiments, ours beside the paper's tables with intervals |
//! | [`swarm_run`] | — | a whole swarm (`hnav run`) started from a benchmark, and what every such run is checked for afterwards |
//! | [`neural_map`] | `hnav-bench neural-map [--quick]` | neuron updates per second and time per map for 20x20 to 1024x1024, tanh against linear, and plan queries |
//! | [`plan`] | `hnav-bench plan --planner P --map FILE (--start X,Y --goal X,Y \| --scen FILE [--first N]) [--json]` | one planning query, or every entry of a MovingAI scenario against its optimal length |
//! | [`tick`] | — | a discrete-time multi-agent run (neural maps, path constructor, conflict resolver): the papers' conflict experiments, for `experiment fidelity` and the conflict tests of `hnav-tests` (`tests/conflict_*.rs`) |
//! | [`seed002`] | `hnav-bench seed002 [--trials N] [--seed S]` | seed 002's obstacle-density experiment (A*, Basic Theta*, Lazy Theta* on random circular obstacles) beside the thesis's Table 3.1 |
//! | [`sim`] | `hnav-bench sim [--robots 1,64,1024] [--seconds S] [--json]` | robot-steps per second of the physics stepper |
//!
//! Results go to stdout as a table and to CSV files in dora-benchmark's schema
//! (`date,language,platform,name,size_bytes,avg_us,p50_us,p90_us,p99_us,n`), so they can be
//! plotted next to other frameworks' numbers.

pub mod chaos;
pub mod experiment;
pub mod fanout;
pub mod futex;
pub mod latency;
pub mod mapf;
pub mod neural_map;
pub mod perf;
pub mod plan;
pub mod raft_sim;
pub mod round;
pub mod seed002;
pub mod sim;
pub mod swarm_run;
pub mod tick;
