//! The scenario hash written into the consensus log's run header.
//!
//! FNV-1a 64 ([`Fnv1a64`]) over a canonical byte encoding, so the hash does not depend on TOML
//! formatting, comments, key order, the file's location or the Rust version. It covers
//! everything that changes what a run does:
//!
//! * the map: width, height, every cell's MovingAI character, the terrain layer if any, and
//!   the corner-cutting rule;
//! * `[robot]`, `[sim]` (including the seed), `[coordinator]` and `[restart]`, every field
//!   (the sim's policy codes are arranged so that its default hashes as before it changed,
//!   see `sim_rule`);
//! * every agent (start, goal, speed, priority, start heading) in order, and every fault in
//!   order (the scenario's `[[faults]]`, then the command line's: both change the run). A
//!   kill at a round keeps the encoding it had before times in seconds and freezes existed.
//!
//! * `allow_unreachable`, only when it is `true` (appended last), so that the hash of every
//!   scenario without the key, and every log written before it existed, stays the same;
//!   likewise `[restart] on_give_up`, only when it is `"stop"`, and `[tasks]`, only when
//!   the section is there (the tag `tasks`, the stream's code and seed, each agent's cycle);
//!   `[localisation]`, only when it differs from its default (the tag `localisation`, rate,
//!   position and heading noise); `[[events]]`, only when there are some (the tag `events`,
//!   then each event's time and change: a code, its cells, a mover's name, speed and
//!   repeat), after `[sensing]`, only when the section is there (the tag `sensing`, range,
//!   known_map, the repair rule's code, and the tag `all-knowing` when it is on); so that the logs written before these sections
//!   existed keep their hash.
//!
//! It does **not** cover the scenario `name`, the source file name, or the map file's path
//! (only the map's content), so renaming or moving files keeps the hash.
//!
//! Encoding: the tag `hnav-scenario-v1`, then each value in the order above; integers as
//! little-endian `u64`, floats as the little-endian bits of the `f64`, booleans and enum
//! variants as one `u64` code, options as a presence code then the value.

use super::localisation::LocalisationParams;
use super::params::{
    ClockMode, FsyncPolicy, GiveUpAction, Planner, RestartPolicy, RestartRule, Rules, SimKind,
};
use super::tasks::StreamKind;
use super::{EventSpec, RepairRule, WorldChange};
use super::{FaultAction, FaultSignal, FaultSpec, FaultTarget, FaultTime, Scenario};
use crate::grid::{CornerCutting, TerrainKind};
use crate::hash::Fnv1a64;

fn rule(h: &mut Fnv1a64, r: &RestartRule) {
    let policy = match r.policy {
        RestartPolicy::Never => 0,
        RestartPolicy::OnFailure => 1,
        RestartPolicy::Always => 2,
    };
    h.u64(policy).u64(r.max_restarts.into()).u64(r.backoff_ms);
}

/// One fault. A kill at a round is encoded as before times in seconds and freezes existed
/// (round, code 0, target, signal number), so the hash of every such plan, and the header of
/// every log written with one, stays the same; the other kinds get codes of their own.
fn fault(h: &mut Fnv1a64, f: &FaultSpec) {
    match f.at {
        FaultTime::Round(r) => h.u64(r),
        FaultTime::Seconds(s) => h.f64(s),
    };
    h.u64(match (f.at, f.action) {
        (FaultTime::Round(_), FaultAction::Kill(_)) => 0,
        (FaultTime::Seconds(_), FaultAction::Kill(_)) => 1,
        (FaultTime::Round(_), FaultAction::Freeze { .. }) => 2,
        (FaultTime::Seconds(_), FaultAction::Freeze { .. }) => 3,
    });
    match f.target {
        FaultTarget::Agent(i) => h.u64(0).u64(i as u64),
        FaultTarget::Coordinator => h.u64(1),
        FaultTarget::Sim => h.u64(2),
        FaultTarget::Replica(id) => h.u64(3).u64(u64::from(id)),
    };
    match f.action {
        FaultAction::Kill(FaultSignal::Kill) => h.u64(9),
        FaultAction::Kill(FaultSignal::Term) => h.u64(15),
        FaultAction::Freeze { for_s: None } => h.u64(0),
        FaultAction::Freeze { for_s: Some(d) } => h.u64(1).f64(d),
    };
}

/// The sim's rule: its policy codes swap `never` and `on-failure` against [`rule`]'s, because
/// its default moved from `never` to `on-failure` and the default keeps the code it had. A
/// scenario that leaves the sim's rule alone keeps its hash, and with it every lockstep log.
fn sim_rule(h: &mut Fnv1a64, r: &RestartRule) {
    let policy = match r.policy {
        RestartPolicy::OnFailure => 0,
        RestartPolicy::Never => 1,
        RestartPolicy::Always => 2,
    };
    h.u64(policy).u64(r.max_restarts.into()).u64(r.backoff_ms);
}

/// The hash described in the [module docs](self).
pub(super) fn scenario_hash(s: &Scenario) -> u64 {
    let mut h = Fnv1a64::new();
    h.bytes(b"hnav-scenario-v1");
    let g = &s.map.grid;
    h.u64(g.width().into()).u64(g.height().into());
    for t in g.tiles() {
        h.bytes(&[t.to_char() as u8]);
    }
    match g.terrain() {
        None => h.u64(0),
        Some(t) => {
            h.u64(match t.kind() {
                TerrainKind::Elevation => 1,
                TerrainKind::Cost => 2,
            });
            for v in t.values() {
                h.bytes(&v.to_bits().to_le_bytes());
            }
            &mut h
        }
    };
    h.u64(match s.map.corner_cutting {
        CornerCutting::Allowed => 1,
        CornerCutting::Forbidden => 0,
    });

    let r = &s.robot;
    for v in [
        r.wheel_radius_m,
        r.axle_track_m,
        r.body_radius_m,
        r.max_wheel_speed_rad_s,
        r.max_wheel_accel_rad_s2,
        r.motor_lag_s,
        r.ticks_per_rev,
        r.cell_size_m,
    ] {
        h.f64(v);
    }

    let sim = &s.sim;
    h.u64(sim.step_ms.into()).u64(sim.odometry_hz.into());
    h.u64(match sim.clock {
        ClockMode::Lockstep => 0,
        ClockMode::Realtime => 1,
    });
    h.u64(sim.seed)
        .f64(sim.slip_std)
        .u64(sim.watchdog_ms.into())
        .f64(sim.slip_hold_s)
        .u64(sim.lockstep_deadline_ms.into());
    // Only when not the default, so that every scenario before the key keeps its hash.
    if sim.kind != SimKind::Hnav {
        h.bytes(b"sim.kind=ros2");
    }

    let c = &s.coordinator;
    h.u64(c.round_deadline_ms.into());
    h.u64(match c.fsync {
        FsyncPolicy::EveryRecord => 0,
        FsyncPolicy::Batched => 1,
        FsyncPolicy::None => 2,
    });
    h.u64(c.replan_after_rounds.into()).f64(c.time_limit_s);
    // Hashed only off the dissertation's rules, the default before the option existed and
    // until `lacam` became the default: a scenario that names `rules = "dissertation"` keeps
    // the hash it had without the key (the golden logs carry it), and an old scenario without
    // the key, now read as `lacam`, no longer matches its logs (replay refuses it by hash
    // rather than replaying other rules).
    if c.rules != Rules::Dissertation {
        h.u64(match c.rules {
            Rules::Dissertation => 0,
            Rules::Pibt => 1,
            Rules::Lacam => 2,
        });
    }

    rule(&mut h, &s.restart.agent);
    rule(&mut h, &s.restart.coordinator);
    sim_rule(&mut h, &s.restart.sim);

    h.u64(s.agents.len() as u64);
    for a in &s.agents {
        h.u64(a.start.x.into())
            .u64(a.start.y.into())
            .u64(a.goal.x.into())
            .u64(a.goal.y.into());
        h.f64(a.speed);
        match a.priority {
            None => h.u64(0),
            Some(p) => h.u64(1).f64(p),
        };
        h.f64(a.start_heading_deg);
        // Off the default only, for the same reason as `rules`.
        if a.planner != Planner::Hnav {
            h.u64(match a.planner {
                Planner::Hnav => 0,
                Planner::Pso => 1,
                Planner::GaFuzzy => 2,
            });
        }
    }
    h.u64(s.faults.len() as u64);
    for f in &s.faults {
        fault(&mut h, f);
    }
    if s.allow_unreachable {
        h.bytes(b"allow_unreachable");
    }
    if s.restart.on_give_up == GiveUpAction::Stop {
        h.bytes(b"on_give_up=stop");
    }
    if let Some(t) = &s.tasks {
        h.bytes(b"tasks");
        match t.stream {
            StreamKind::Seeded => h.u64(0).u64(t.seed),
            StreamKind::List => h.u64(1),
        };
        h.u64(t.cycles.len() as u64);
        for c in &t.cycles {
            h.u64(c.len() as u64);
            for g in c {
                h.u64(g.x.into()).u64(g.y.into());
            }
        }
    }
    let l = &s.localisation;
    if *l != LocalisationParams::default() {
        h.bytes(b"localisation")
            .f64(l.rate_hz)
            .f64(l.std_m)
            .f64(l.std_deg);
    }
    if let Some(v) = &s.sensing {
        let repair = match v.repair {
            RepairRule::Auto => 0,
            RepairRule::Partial => 1,
            RepairRule::Rebuild => 2,
        };
        h.bytes(b"sensing")
            .u64(v.range.into())
            .u64(v.known_map.into())
            .u64(repair);
        if v.all_knowing {
            h.bytes(b"all-knowing");
        }
    }
    if !s.events.is_empty() {
        h.bytes(b"events");
        h.u64(s.events.len() as u64);
        for e in &s.events {
            event(&mut h, e);
        }
    }
    h.finish()
}

fn event(h: &mut Fnv1a64, e: &EventSpec) {
    h.f64(e.at_s);
    let cells = match &e.change {
        WorldChange::Close(c) => {
            h.u64(0);
            c
        }
        WorldChange::Open(c) => {
            h.u64(1);
            c
        }
        WorldChange::Mover(m) => {
            h.u64(2)
                .bytes(m.name.as_bytes())
                .f64(m.speed)
                .u64(m.repeat.into());
            if !m.yields {
                // Only then: a mover that yields keeps the hash it had before `yields`.
                h.bytes(b"walks-on");
            }
            &m.cells
        }
    };
    h.u64(cells.len() as u64);
    for c in cells {
        h.u64(c.x.into()).u64(c.y.into());
    }
}
