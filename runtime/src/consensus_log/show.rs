//! One-line renderings of records, as `hnav log show` prints them: [`describe`] for people,
//! [`to_json`] for tools (one JSON object per record).

use std::fmt::Write as _;

use serde_json::{json, Map, Value};

use super::frame::decode_record;
use super::reader::RecordPos;
use super::record::{LoggedDecision, Record};
use crate::msg::{ConflictKind, LifecycleEvent, Role, Verdict, NO_CELL};

const DIRECTIONS: [&str; 8] = ["N", "NE", "E", "SE", "S", "SW", "W", "NW"];

/// A cell as `[x, y]` (0-based column and row, the one spelling of a cell in every output
/// of HNAV) for a grid `width` cells wide (`-` for none, `#index` without a width).
pub fn cell(index: u32, width: u32) -> String {
    if index == NO_CELL {
        "-".into()
    } else if width == 0 {
        format!("#{index}")
    } else {
        format!("[{}, {}]", index % width, index / width)
    }
}

/// `x` to at most three decimals, trailing zeros dropped (`3.333`, `0.5`, `2`): a speed or
/// priority as people read it (the JSON keeps every digit).
pub fn rounded(x: f64) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// One line describing `record`; `width` is the grid width from the log's header (0 if
/// unknown) for printing cells as `[x, y]`.
pub fn describe(record: &Record, width: u32) -> String {
    let mut s = String::new();
    match record {
        Record::Header(h) => {
            let _ = write!(
                s,
                "header  v{} scenario {:#018x} seed {} {} {}x{} agents {}",
                h.version,
                h.scenario_hash,
                h.seed,
                h.clock,
                h.width,
                h.height,
                h.agents.len()
            );
            for (i, a) in h.agents.iter().enumerate() {
                let sep = if i == 0 { ": " } else { ", " };
                let _ = write!(
                    s,
                    "{sep}a{i} {}->{} speed {} priority {}",
                    cell(a.start, h.width),
                    cell(a.goal, h.width),
                    rounded(a.speed),
                    rounded(a.priority)
                );
            }
        }
        Record::Round(r) => {
            let _ = write!(
                s,
                "round {}  candidates {} digest {:#018x} ",
                r.round, r.candidates, r.candidates_digest
            );
            for d in &r.decisions {
                s.push(' ');
                decision(&mut s, d, width);
            }
        }
        Record::Lifecycle(l) => {
            let _ = write!(s, "lifecycle round {}  ", l.round);
            match Role::from_u8(l.role) {
                Some(Role::Agent) => _ = write!(s, "{} {}", Role::Agent.name(), l.index),
                // A replica by its id (`coordinator-2`); a single coordinator, the sim by name.
                Some(r) => s.push_str(&r.node_name(l.index)),
                None => _ = write!(s, "role{} {}", l.role, l.index),
            }
            let event = match LifecycleEvent::from_u8(l.event) {
                Some(e) => e.name().to_string(),
                None => format!("event{}", l.event),
            };
            let _ = write!(s, " {event} restarts {}", l.restarts);
        }
        Record::Replan(r) => {
            let _ = write!(s, "replan round {}  a{} {} ", r.round, r.agent, r.planner);
            if r.found {
                s.push_str("found");
                for &w in &r.waypoints {
                    let _ = write!(s, " {}", cell(w, width));
                }
            } else {
                s.push_str("not found");
            }
        }
        Record::Unreachable(u) => {
            let _ = write!(
                s,
                "unreachable round {}  a{} at {}",
                u.round,
                u.agent,
                cell(u.cell, width)
            );
        }
        Record::Task(t) => {
            let _ = write!(
                s,
                "task round {}  a{} task {} goal {}",
                t.round,
                t.agent,
                t.task,
                cell(t.goal, width)
            );
        }
        Record::MapChange(m) => {
            let _ = write!(s, "map-change round {}  a{} saw", m.round, m.agent);
            for (what, cells) in [("closed", &m.closed), ("opened", &m.opened)] {
                if !cells.is_empty() {
                    let _ = write!(s, "  {what}");
                    for &c in cells.iter() {
                        let _ = write!(s, " {}", cell(c, width));
                    }
                }
            }
        }
        Record::End(e) => {
            let _ = write!(
                s,
                "end round {}  at_goal {} {}",
                e.round,
                e.at_goal,
                e.reason.name()
            );
        }
        Record::Raft(e) => {
            let _ = write!(s, "raft {}.{}  ", e.term, e.index);
            match (e.data.is_empty(), decode_record(&e.data)) {
                (true, _) => s.push_str("(empty)"),
                (false, Ok(inner)) => s.push_str(&describe(&inner, width)),
                (false, Err(p)) => _ = write!(s, "undecodable: {p}"),
            }
        }
        Record::RaftState(st) => {
            let _ = write!(
                s,
                "raft-state term {} vote {} commit {}",
                st.term, st.vote, st.commit
            );
        }
        Record::Snapshot(snap) => {
            let _ = write!(s, "snapshot {}.{}  ", snap.term, snap.index);
            match snap.applied() {
                Ok(a) => {
                    let _ = write!(
                        s,
                        "{} records through round {}  conflicts {}  replans {}  lost {}",
                        a.records,
                        a.round,
                        a.tally.conflicts(),
                        a.tally.replans(),
                        a.agents.iter().filter(|l| l.lost).count()
                    );
                    if let Some(e) = a.end {
                        let _ = write!(s, "  ended {}", e.reason.name());
                    }
                }
                Err(p) => _ = write!(s, "undecodable: {p}"),
            }
        }
    }
    s
}

/// One decision in words, as [`describe`] prints it in a round (`accept a1->[3, 4]`,
/// `block a2 crossing (N,NE)`, `hold a0`, `replan a3 via [5, 5]`).
pub fn describe_decision(d: &LoggedDecision, width: u32) -> String {
    let mut s = String::new();
    decision(&mut s, d, width);
    s
}

fn decision(s: &mut String, d: &LoggedDecision, width: u32) {
    let kind = ConflictKind::from_u8(d.kind)
        .map_or_else(|| format!("kind{}", d.kind), |k| k.name().into());
    match Verdict::from_u8(d.verdict) {
        Some(Verdict::Accept) => {
            let _ = write!(s, "accept a{}->{}", d.agent, cell(d.cell, width));
            if d.kind != ConflictKind::None as u8 {
                let _ = write!(s, " {kind}");
            }
        }
        Some(Verdict::Block) => {
            let _ = write!(s, "block a{} {kind}", d.agent);
            if d.refused != 0 {
                let dirs: Vec<&str> = (0..8)
                    .filter(|b| d.refused & (1 << b) != 0)
                    .map(|b| DIRECTIONS[b])
                    .collect();
                let _ = write!(s, " ({})", dirs.join(","));
            }
        }
        Some(Verdict::Hold) => {
            let _ = write!(s, "hold a{}", d.agent);
            if d.kind != ConflictKind::None as u8 {
                let _ = write!(s, " {kind}");
            }
        }
        Some(Verdict::Replan) => {
            let _ = write!(s, "replan a{}", d.agent);
            if d.cell != NO_CELL {
                let _ = write!(s, "->{}", cell(d.cell, width));
            }
            let _ = write!(s, " via {}", cell(d.waypoint, width));
        }
        Some(Verdict::Task) => {
            let _ = write!(s, "task a{}->{}", d.agent, cell(d.waypoint, width));
        }
        None => _ = write!(s, "verdict{} a{}", d.verdict, d.agent),
    }
}

/// One JSON object for `record` at `pos`: `segment`, `offset`, `kind` and the record's
/// fields, for a grid `width` cells wide (from the log's header; 0 if unknown). Enumerations
/// are their names (`"accept"`, `"crossing"`, `"agent"`, `"up"`, `"time-limit"`; an unknown
/// code stays its number), cells are `[x, y]` as everywhere else (`null` for none; the linear
/// index when the width is unknown), refused directions a list of compass names.
pub fn to_json(pos: &RecordPos, record: &Record, width: u32) -> Value {
    let cell = |index: u32| cell_json(index, width);
    let fields = match record {
        Record::Header(h) => json!({
            "version": h.version,
            "scenario_hash": h.scenario_hash,
            "seed": h.seed,
            "clock": h.clock,
            "width": h.width,
            "height": h.height,
            "agents": h.agents.iter().map(|a| json!({
                "start": cell_json(a.start, h.width),
                "goal": cell_json(a.goal, h.width),
                "speed": a.speed,
                "priority": a.priority,
            })).collect::<Vec<_>>(),
        }),
        Record::Round(r) => json!({
            "round": r.round,
            "candidates": r.candidates,
            "candidates_digest": r.candidates_digest,
            "decisions": r.decisions.iter().map(|d| json!({
                "agent": d.agent,
                "verdict": name_or_code(Verdict::from_u8(d.verdict).map(Verdict::name), d.verdict),
                "kind": name_or_code(ConflictKind::from_u8(d.kind).map(ConflictKind::name), d.kind),
                "refused": (0..8)
                    .filter(|b| d.refused & (1 << b) != 0)
                    .map(|b| DIRECTIONS[b])
                    .collect::<Vec<_>>(),
                "cell": cell(d.cell),
                "waypoint": cell(d.waypoint),
            })).collect::<Vec<_>>(),
        }),
        Record::Lifecycle(l) => json!({
            "round": l.round,
            "role": name_or_code(Role::from_u8(l.role).map(Role::name), l.role),
            "index": l.index,
            "event": name_or_code(LifecycleEvent::from_u8(l.event).map(LifecycleEvent::name), l.event),
            "restarts": l.restarts,
        }),
        Record::Replan(r) => json!({
            "round": r.round,
            "agent": r.agent,
            "planner": r.planner,
            "found": r.found,
            "waypoints": r.waypoints.iter().map(|&w| cell(w)).collect::<Vec<_>>(),
        }),
        Record::End(e) => json!({
            "round": e.round,
            "at_goal": e.at_goal,
            "reason": e.reason.name(),
        }),
        Record::Unreachable(u) => json!({
            "round": u.round,
            "agent": u.agent,
            "cell": cell(u.cell),
        }),
        Record::Task(t) => json!({
            "round": t.round,
            "agent": t.agent,
            "task": t.task,
            "goal": cell(t.goal),
        }),
        Record::MapChange(m) => json!({
            "round": m.round,
            "agent": m.agent,
            "closed": m.closed.iter().map(|&c| cell(c)).collect::<Vec<_>>(),
            "opened": m.opened.iter().map(|&c| cell(c)).collect::<Vec<_>>(),
        }),
        Record::Raft(e) => json!({
            "term": e.term,
            "index": e.index,
            "record": match (e.data.is_empty(), decode_record(&e.data)) {
                (true, _) => Value::Null,
                (false, Ok(inner)) => to_json(pos, &inner, width),
                (false, Err(p)) => json!({ "undecodable": p.to_string() }),
            },
        }),
        Record::RaftState(st) => json!({
            "term": st.term,
            "vote": st.vote,
            "commit": st.commit,
        }),
        Record::Snapshot(snap) => json!({
            "term": snap.term,
            "index": snap.index,
            "voters": snap.voters,
            "state": match snap.applied() {
                Ok(a) => json!({
                    "records": a.records,
                    "round": a.round,
                    "conflicts": a.tally.conflicts(),
                    "replans": a.tally.replans(),
                    "end": a.end.map(|e| e.reason.name()),
                }),
                Err(p) => json!({ "undecodable": p.to_string() }),
            },
        }),
    };
    let mut object = Map::new();
    object.insert("segment".into(), json!(pos.segment));
    object.insert("offset".into(), json!(pos.offset));
    object.insert("kind".into(), json!(record.kind()));
    if let Value::Object(map) = fields {
        object.extend(map);
    }
    Value::Object(object)
}

/// A cell as JSON: `[x, y]`, `null` for none, the linear index without a width.
fn cell_json(index: u32, width: u32) -> Value {
    if index == NO_CELL {
        Value::Null
    } else if width == 0 {
        json!(index)
    } else {
        json!([index % width, index / width])
    }
}

/// An enumeration's name, or its code when the code is unknown.
fn name_or_code(name: Option<&str>, code: u8) -> Value {
    name.map_or_else(|| json!(code), |n| json!(n))
}
