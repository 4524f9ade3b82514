//! Conflict resolution between agents: one decision round of the dissertation's
//! `shared_paths` check (§3.3.1–3.3.2, Figs. 3-5 to 3-7; seed 001's rules (a) and (b)).
//!
//! A pure function of the round's rows, with no I/O: the coordinator process calls
//! [`Resolver::resolve`] once per decision round, tests call it from a discrete-time loop.
//! [`Pibt`] is another round (`[coordinator] rules = "pibt"`, priority inheritance; see
//! [`pibt`]) over the same rows and outcomes, with the same invariants, and [`Lacam`] a third
//! (`rules = "lacam"`: a whole plan searched with LaCAM and followed; see [`lacam`]).
//!
//! # The model, and why it is this one
//!
//! Each agent has a row of `shared_paths` ([`AgentRow`]): the cell it is in (`current`), the
//! cell it has been committed to and is driving to (`next`, equal to `current` at rest), and
//! the step it asks for (`probable`). The dissertation shifts the row when a probable step is
//! accepted (`next <- probable`) and again when the robot arrives (`current <- next`).
//!
//! The papers check points: two agents conflict when they want the same cell or each other's
//! cells at the same instant. Physical robots occupy a cell's width and take time to cross, so
//! here cells are **reserved until the robot has left them**: a row holds `current` and `next`
//! and, while it drives a diagonal, the two orthogonal side cells of that diagonal too (a
//! robot as wide as a cell sweeps their corners; its body at the shared corner point is
//! `1/sqrt 2` cell from their centres). A move is accepted only into cells nobody holds, and
//! accepted moves never sweep a common cell. So, if no two rows held a common cell before the
//! round, none do after `next <- probable` for every accepted row: no co-location, and hence
//! no swap, which needs one robot to enter a cell the other has not left. This is stronger
//! than the papers' rules, and it costs time exactly where they let two robots touch: a robot
//! may not follow into a cell that is being vacated in the same round, and a robot may not cut
//! the corner of a cell another robot stands in. [`Options::sweep`] switches the side cells
//! off, giving the papers' point robots (the seed-001 reproduction needs that; the
//! no-co-location guarantee then holds for `current` and `next` only).
//!
//! Only an agent **at rest** (`next == current`) asks for a step. A moving agent has nothing
//! to decide: its `next` was verified and "will not change" (§3.3.1), and letting it queue a
//! second step would reserve three cells ahead of a robot that may still stop.
//!
//! # The rules (checked in this order for each agent A asking for `p`, direction `d`)
//!
//! | # | situation | verdict | kind |
//! |---|---|---|---|
//! | 1 | `p` not an 8-neighbour of `current`, off the grid or blocked | Block (bit `d` when `d` exists) | [`Invalid`](hnav_runtime::msg::ConflictKind::Invalid) |
//! | 2 | diagonal past blocked map corners (Fig. 3-7, per [`CornerCutting`]), or whose side cell another agent holds | Block | [`CornerCut`](hnav_runtime::msg::ConflictKind::CornerCut) |
//! | 3 | `p` held by a [`Standing`](AgentMode::Standing) or [`Finished`](AgentMode::Finished) agent: type (d), whatever the priorities | Block | [`StableCell`](hnav_runtime::msg::ConflictKind::StableCell) |
//! | 4 | head-on, type (b): an active agent B at rest asks for A's cell while A asks for B's | lower priority Block, higher Hold, equal both Block | [`HeadOn`](hnav_runtime::msg::ConflictKind::HeadOn) |
//! | 5 | `p` held by another active agent (moving out, or waiting) | Hold | [`Reserved`](hnav_runtime::msg::ConflictKind::Reserved) |
//! | 6 | crossing, type (a): the footprints (`p` plus a diagonal's side cells) of two remaining requests meet | lower priority Block, equal both Block | [`Crossing`](hnav_runtime::msg::ConflictKind::Crossing) |
//! | 7 | no request (moving, nothing asked, standing, finished) | Hold | [`None`](hnav_runtime::msg::ConflictKind::None) |
//!
//! Anything else is accepted ([`Verdict::Accept`], `cell = p`). A head-on agent whose
//! footprint also meets a third agent's request is reported as
//! [`Combined`](hnav_runtime::msg::ConflictKind::Combined), type (c); its verdict is the head-on one.
//!
//! Why these choices:
//!
//! * Priorities: larger wins. The caller supplies them (`P = 1 / speed` by default in the
//!   dissertation, so the slower robot wins and the faster, more agile one dodges).
//! * Head-on: the winner is told to **Hold**, not Accept, because its target cell is still
//!   occupied by the loser; it goes once the loser has sidestepped. With equal priorities both
//!   are refused, the dissertation's "both change direction".
//! * Reserved is a Hold, not a Block: the cell will free itself, so the direction stays right
//!   and the agent's map needs no correction.
//! * Crossing requests are decided in descending priority (ties by agent index), each against
//!   the requests already accepted: the order makes the outcome deterministic and independent
//!   of how the rows were gathered. A request that only conflicts with a refused one goes
//!   ahead, so one refusal does not cascade. Equal priorities refuse both (and revoke the
//!   accepted one), as the papers say; a revoked request still stops later requests of its
//!   own priority, so a tie of three for one cell refuses all three whatever their indices.
//! * A refusal sets the refused direction's bit ([`Outcome::refused`]): the agent's "virtual
//!   obstacle" for this step (§3.4, `grad_d = -1`); a Hold sets none.
//!
//! # Cost
//!
//! [`Resolver::new`] sizes every buffer for the grid and the agent count; a round then runs in
//! `O(n log n)` for `n` agents (one in-place sort; the type (c) check adds `O(n)` per head-on
//! agent) with generation stamps instead of clearing per-cell tables, and allocates nothing
//! (the caller's `out` keeps its capacity).
//!
//! [`CornerCutting`]: hnav_runtime::grid::CornerCutting
//! [`Verdict::Accept`]: hnav_runtime::msg::Verdict::Accept

pub mod lacam;
pub mod pibt;
mod resolve;
mod shared_paths;
#[cfg(test)]
mod tests;

pub use lacam::Lacam;
pub use pibt::Pibt;
pub use resolve::Resolver;
pub use shared_paths::{side_cells, AgentMode, AgentRow, Options, Outcome};
