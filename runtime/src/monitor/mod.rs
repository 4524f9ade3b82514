//! The live view behind `hnav top`: what it shows, where that comes from, and how it is
//! drawn, apart from the terminal (the binary's `top` module owns the terminal and the keys).
//!
//! ## The seam
//!
//! ```text
//!   a Feed ── Update (truth, commit, progress, lifecycle, health rows, end) ──> ViewState ──> view::draw
//! ```
//!
//! A [`Feed`](feed::Feed) is a source of [`Update`](feed::Update)s: the message contracts
//! themselves (a [`Truth`](crate::msg::Truth), a [`Commit`](crate::msg::Commit), ...) plus
//! the process-health rows and the end of the run, and the static picture of the run
//! ([`RunInfo`](state::RunInfo): map, starts, goals). [`ViewState`](state::ViewState) folds
//! updates into what the screen shows (each agent's state, the round rate, the latest
//! decisions) and [`view::draw`] renders it with ratatui into any backend, the terminal or
//! ratatui's `TestBackend`. Nothing past the feed knows where the data came from.
//!
//! The one feed today is [`LiveFeed`](live::LiveFeed), a subscriber of a live run like any
//! other client. A playback of a recorded run would be a second implementation that reads
//! the recorded trajectories and the consensus log and yields the same updates at a chosen
//! speed (`Truth` for poses, `Commit`s rebuilt from the log's round records with
//! [`RoundRecord::commit`](crate::consensus_log::record::RoundRecord::commit), `Ended` at the
//! log's end record); the state and the view stay as they are.
//!
//! | module | what it holds |
//! |---|---|
//! | [`feed`] | the [`Feed`](feed::Feed) trait, its [`Update`](feed::Update)s and errors |
//! | [`live`] | the live feed: the run found in the registry, its topics read without back-pressure |
//! | [`health`] | process-health rows: pid, state and restarts from the registry, CPU from `/proc` |
//! | [`state`] | the view's state and the per-agent state machine (decision -> moving / held / ...) |
//! | [`map`] | the map scaled to the terminal, robots and goals on it |
//! | [`view`] | the whole screen: header, map, agents, processes, latest decisions |

pub mod feed;
pub mod health;
pub mod live;
pub mod map;
pub mod state;
pub mod view;
