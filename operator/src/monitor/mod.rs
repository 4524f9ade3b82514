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
//! themselves (a [`Truth`](hnav_runtime::msg::Truth), a [`Commit`](hnav_runtime::msg::Commit), ...) plus
//! the process-health rows and the end of the run, and the static picture of the run
//! ([`RunInfo`](feed::RunInfo): map, starts, goals). [`ViewState`](state::ViewState) folds
//! updates into what the screen shows (each agent's state, the round rate, the latest
//! decisions) and [`view::draw`] renders it with ratatui into any backend, the terminal or
//! ratatui's `TestBackend`. Nothing past the feed knows where the data came from.
//!
//! Two feeds implement it: [`LiveFeed`](live::LiveFeed), a subscriber of a live run like any
//! other client (`hnav top`), and [`PlaybackFeed`](playback::PlaybackFeed), a finished run's
//! recording and consensus log yielded at a chosen speed (`hnav log replay DIR --speed X`):
//! `Truth` from the recorded poses, `Commit`s rebuilt from the log's round records, `Ended`
//! at the log's end record. The state and the view do not know which one they are fed by.
//!
//! | module | what it holds |
//! |---|---|
//! | [`feed`] | the [`Feed`](feed::Feed) trait, its [`Update`](feed::Update)s and errors |
//! | [`live`] | the live feed: the run found in the registry, its topics read without back-pressure |
//! | [`playback`] | the playback feed: a run directory's recording and log, paced by simulated time / speed |
//! | [`health`] | process-health rows: pid, state and restarts from the registry, CPU from `/proc` |
//! | [`state`] | the view's state and the per-agent state machine (decision -> moving / held / ...) |
//! | [`map`] | the map scaled to the terminal, robots and goals on it |
//! | [`view`] | the whole screen: header, map, agents, processes, latest decisions |

pub mod feed;
pub mod health;
pub mod live;
pub mod map;
pub mod playback;
pub mod state;
pub mod view;
