//! What a run shows in Foxglove, folded from the swarm's own messages: [`SceneFold`] takes
//! ground truth ([`TruthView`]), each round's decisions ([`CommitView`]) and process events, and
//! gives the messages of [`super::shown`]'s channels. The live view feeds it from a run's
//! topics, the export from the recording and the consensus log, so both draw the same.
//!
//! The scene (`/scene`, one `foxglove.SceneUpdate` per ground-truth sample, replacing the
//! previous one whole):
//!
//! | entity | drawn as | from |
//! |---|---|---|
//! | `robot/<i>` | a cube with its index above it: blue, red while its last decision was a block or a hold for a conflict, grey while its process is down | the ground-truth pose |
//! | `goal/<i>` | a flat green square on the goal cell | the run's goals |
//! | `route/<i>` | a line: the robot, the cell last committed to it, the waypoint of its last replan, its goal | the decisions |
//! | `conflict/<i>` | a flat red square on the cell refused or held, with the conflict's kind | a block or a hold for a conflict in its last decision |
//! | `mover/<k>` | a tall red-brown box with `mover k` above it | a mover on the floor (`[[events]]` movers: the sim's `movers` topic, the recording's mover samples) |
//!
//! The route is what the swarm decided for the robot, then a straight line to its goal: an
//! agent's own path (its neural map's gradient) is on no topic.

use serde_json::{json, Value};

use super::messages::{cell, occupancy, pose, stamp, FRAME};
use super::{schemas, Message, LOG, MAP, SCENE};
use hnav_runtime::grid::Grid;
use hnav_runtime::msg::{
    CommitView, ConflictKind, LifecycleEvent, MoverPlace, Pose, Role, TruthView, Verdict, NO_CELL,
};

/// `foxglove.Log` levels.
const INFO: u8 = 2;
const WARNING: u8 = 3;
const ERROR: u8 = 4;

/// What does not change while a run runs: its map, its robots' goals, its cell size.
#[derive(Debug, Clone)]
pub struct Picture {
    /// The map at the start.
    pub grid: Grid,
    /// Each robot's goal cell (0-based row-major index).
    pub goals: Vec<u32>,
    /// Side of a cell in metres.
    pub cell_m: f64,
}

/// One robot as the scene knows it.
#[derive(Debug, Clone, Default)]
struct Robot {
    pose: Option<Pose>,
    /// Simulated time of `pose`, ns.
    at_ns: u64,
    speed_m_s: f64,
    committed: Option<u32>,
    waypoint: Option<u32>,
    /// The conflict of its last decision: kind and the cell refused or held.
    conflict: Option<(ConflictKind, u32)>,
    /// Its last hold or block logged (verdict, kind, cell), so a repeat is not logged again.
    logged: Option<(u8, u8, u32)>,
    down: bool,
}

/// The fold; see the [module docs](self).
#[derive(Debug, Clone)]
pub struct SceneFold {
    picture: Picture,
    robots: Vec<Robot>,
    /// The movers on the floor, as last told.
    movers: Vec<MoverPlace>,
}

impl SceneFold {
    /// A fold of a run of `picture`, before any message.
    pub fn new(picture: Picture) -> Self {
        let robots = vec![Robot::default(); picture.goals.len()];
        SceneFold {
            picture,
            robots,
            movers: Vec::new(),
        }
    }

    /// The movers on the floor now: the next scene draws these.
    pub fn movers(&mut self, places: &[MoverPlace]) {
        self.movers.clear();
        self.movers.extend_from_slice(places);
    }

    /// The run's static picture.
    pub fn picture(&self) -> &Picture {
        &self.picture
    }

    /// `/map`: `grid` (the start's, or after a close or open) at `t_ns`.
    pub fn map(&self, grid: &Grid, t_ns: u64) -> Message {
        Message {
            topic: MAP.into(),
            schema: schemas::GRID,
            t_ns,
            body: occupancy(grid, t_ns, self.picture.cell_m),
        }
    }

    /// Folds a ground-truth sample: each robot's pose and speed. Returns `/scene` and each
    /// robot's `/robots/<i>/stats`.
    pub fn truth(&mut self, truth: TruthView<'_>) -> Vec<Message> {
        let t = truth.sim_time_ns();
        let n = truth.poses().len().min(self.robots.len());
        let mut out = Vec::with_capacity(n + 1);
        for (i, (r, p)) in self.robots.iter_mut().zip(truth.poses()).enumerate() {
            if let Some(last) = r.pose.filter(|_| t > r.at_ns) {
                let dt = (t - r.at_ns) as f64 * 1e-9;
                r.speed_m_s = (p.x_m - last.x_m).hypot(p.y_m - last.y_m) / dt;
            }
            r.pose = Some(*p);
            r.at_ns = t;
            out.push(Message {
                topic: super::stats(i),
                schema: schemas::ROBOT_STATS,
                t_ns: t,
                body: json!({"timestamp": stamp(t), "robot": i, "speed_m_s": r.speed_m_s, "energy_j": null}),
            });
        }
        out.insert(0, self.scene(t));
        out
    }

    /// Robot `i`'s `/robots/<i>/truth` of a ground-truth sample.
    pub fn pose_in_frame(truth: TruthView<'_>, i: usize) -> Message {
        let t = truth.sim_time_ns();
        let p = truth.poses()[i];
        Message {
            topic: super::truth(i),
            schema: schemas::POSE_IN_FRAME,
            t_ns: t,
            body: json!({"timestamp": stamp(t), "frame_id": FRAME, "pose": pose(p.x_m, p.y_m, 0.0, p.theta_rad)}),
        }
    }

    /// Folds one round's decisions, decided at `t_ns`; returns their `/log` lines.
    pub fn commit(&mut self, t_ns: u64, c: CommitView<'_>) -> Vec<Message> {
        let width = self.picture.grid.width();
        let mut out = Vec::new();
        for d in c.decisions() {
            let Some(r) = self.robots.get_mut(d.agent as usize) else {
                continue;
            };
            let verdict = Verdict::from_u8(d.verdict);
            let kind = ConflictKind::from_u8(d.kind).unwrap_or(ConflictKind::None);
            let at = cell(d.cell, width);
            let (level, text) = match verdict {
                Some(Verdict::Accept) => {
                    r.committed = Some(d.cell).filter(|&c| c != NO_CELL);
                    r.conflict = None;
                    r.logged = None;
                    (INFO, format!("accepted, to {at}"))
                }
                Some(Verdict::Replan) => {
                    r.waypoint = Some(d.waypoint).filter(|&c| c != NO_CELL);
                    r.conflict = None;
                    let via = cell(d.waypoint, width);
                    (WARNING, format!("replanned ({}), via {via}", kind.name()))
                }
                Some(v @ (Verdict::Block | Verdict::Hold)) if kind != ConflictKind::None => {
                    r.conflict = (d.cell != NO_CELL).then_some((kind, d.cell));
                    let same = (d.verdict, d.kind, d.cell);
                    if r.logged == Some(same) {
                        continue;
                    }
                    r.logged = Some(same);
                    (WARNING, format!("{} ({}) at {at}", v.name(), kind.name()))
                }
                _ => continue,
            };
            out.push(log(
                t_ns,
                level,
                &format!("agent-{}", d.agent),
                format!("round {}: {text}", c.round()),
            ));
        }
        out
    }

    /// Folds a process event at `t_ns` (role, index, event and restarts as the lifecycle
    /// message and record hold them); returns its `/log` line, if it is one worth a line.
    pub fn lifecycle(&mut self, t_ns: u64, role: u8, index: u32, event: u8) -> Option<Message> {
        let role = Role::from_u8(role)?;
        let event = LifecycleEvent::from_u8(event)?;
        let agent = (role == Role::Agent)
            .then(|| self.robots.get_mut(index as usize))
            .flatten();
        let level = match event {
            LifecycleEvent::Down | LifecycleEvent::Lost => ERROR,
            LifecycleEvent::Restarted | LifecycleEvent::Start | LifecycleEvent::Stop => INFO,
            _ => return None,
        };
        if let Some(r) = agent {
            r.down = matches!(event, LifecycleEvent::Down | LifecycleEvent::Lost);
        }
        let name = match event {
            LifecycleEvent::Start | LifecycleEvent::Stop => "supervisor".to_string(),
            _ => role.node_name(index),
        };
        let text = match event {
            LifecycleEvent::Start => "run started".to_string(),
            LifecycleEvent::Stop => "run stopped".to_string(),
            e => format!("{} {}", role.node_name(index), e.name()),
        };
        Some(log(t_ns, level, &name, text))
    }

    /// `/scene` at `t_ns`: every entity anew, the previous ones deleted.
    pub fn scene(&self, t_ns: u64) -> Message {
        let mut entities = Vec::with_capacity(3 * self.robots.len());
        for (i, r) in self.robots.iter().enumerate() {
            let goal = self.picture.goals[i];
            entities.push(self.goal(t_ns, i, goal));
            let Some(p) = r.pose else { continue };
            entities.push(self.robot(t_ns, i, r, &p));
            entities.push(self.route(t_ns, i, r, &p, goal));
            if let Some((kind, c)) = r.conflict {
                entities.push(self.conflict(t_ns, i, kind, c));
            }
        }
        for m in &self.movers {
            entities.push(self.mover(t_ns, m));
        }
        Message {
            topic: SCENE.into(),
            schema: schemas::SCENE_UPDATE,
            t_ns,
            body: json!({
                "deletions": [{"timestamp": stamp(t_ns), "type": 1, "id": ""}],
                "entities": entities,
            }),
        }
    }

    /// The centre of cell `c` (0-based row-major index), metres.
    fn centre(&self, c: u32) -> (f64, f64) {
        let w = self.picture.grid.width().max(1);
        let m = self.picture.cell_m;
        ((f64::from(c % w) + 0.5) * m, (f64::from(c / w) + 0.5) * m)
    }

    fn entity(&self, t_ns: u64, id: String, parts: Value) -> Value {
        let mut e = json!({
            "timestamp": stamp(t_ns),
            "frame_id": FRAME,
            "id": id,
            "lifetime": {"sec": 0, "nsec": 0},
            "frame_locked": false,
            "metadata": [],
            "cubes": [],
            "lines": [],
            "texts": [],
        });
        if let (Some(e), Some(parts)) = (e.as_object_mut(), parts.as_object()) {
            for (k, v) in parts {
                e.insert(k.clone(), v.clone());
            }
        }
        e
    }

    fn goal(&self, t_ns: u64, i: usize, goal: u32) -> Value {
        let (x, y) = self.centre(goal);
        let m = self.picture.cell_m;
        let cube = json!({"pose": pose(x, y, 0.005 * m, 0.0), "size": {"x": 0.8 * m, "y": 0.8 * m, "z": 0.01 * m}, "color": rgba(0.2, 0.7, 0.3, 0.5)});
        self.entity(
            t_ns,
            format!("goal/{i}"),
            json!({"cubes": [cube], "metadata": [kv("robot", i)]}),
        )
    }

    fn robot(&self, t_ns: u64, i: usize, r: &Robot, p: &Pose) -> Value {
        let m = self.picture.cell_m;
        let (state, color) = if r.down {
            ("down", rgba(0.5, 0.5, 0.5, 1.0))
        } else if r.conflict.is_some() {
            ("in conflict", rgba(0.85, 0.2, 0.2, 1.0))
        } else {
            ("running", rgba(0.2, 0.4, 0.9, 1.0))
        };
        let cube = json!({"pose": pose(p.x_m, p.y_m, 0.15 * m, p.theta_rad), "size": {"x": 0.6 * m, "y": 0.5 * m, "z": 0.3 * m}, "color": color});
        let text = json!({"pose": pose(p.x_m, p.y_m, 0.5 * m, 0.0), "billboard": true, "font_size": 14.0, "scale_invariant": true, "color": rgba(1.0, 1.0, 1.0, 1.0), "text": i.to_string()});
        let speed = format!("{:.3}", r.speed_m_s);
        self.entity(
            t_ns,
            format!("robot/{i}"),
            json!({"cubes": [cube], "texts": [text], "metadata": [kv("robot", i), kv("state", state), kv("speed_m_s", speed)]}),
        )
    }

    fn route(&self, t_ns: u64, i: usize, r: &Robot, p: &Pose, goal: u32) -> Value {
        let z = 0.02 * self.picture.cell_m;
        let mut points = vec![json!({"x": p.x_m, "y": p.y_m, "z": z})];
        for c in [r.committed, r.waypoint, Some(goal)].into_iter().flatten() {
            let (x, y) = self.centre(c);
            points.push(json!({"x": x, "y": y, "z": z}));
        }
        let line = json!({"type": 0, "pose": pose(0.0, 0.0, 0.0, 0.0), "thickness": 0.06 * self.picture.cell_m, "scale_invariant": false, "points": points, "color": rgba(0.2, 0.4, 0.9, 0.6)});
        self.entity(
            t_ns,
            format!("route/{i}"),
            json!({"lines": [line], "metadata": [kv("robot", i)]}),
        )
    }

    fn mover(&self, t_ns: u64, m: &MoverPlace) -> Value {
        let (cell, p) = (self.picture.cell_m, &m.pose);
        let cube = json!({"pose": pose(p.x_m, p.y_m, 0.4 * cell, p.theta_rad), "size": {"x": 0.5 * cell, "y": 0.5 * cell, "z": 0.8 * cell}, "color": rgba(0.47, 0.16, 0.08, 1.0)});
        let text = json!({"pose": pose(p.x_m, p.y_m, 1.0 * cell, 0.0), "billboard": true, "font_size": 12.0, "scale_invariant": true, "color": rgba(1.0, 0.8, 0.7, 1.0), "text": format!("mover {}", m.mover)});
        self.entity(
            t_ns,
            format!("mover/{}", m.mover),
            json!({"cubes": [cube], "texts": [text], "metadata": [kv("mover", m.mover)]}),
        )
    }

    fn conflict(&self, t_ns: u64, i: usize, kind: ConflictKind, c: u32) -> Value {
        let (x, y) = self.centre(c);
        let m = self.picture.cell_m;
        let cube = json!({"pose": pose(x, y, 0.01 * m, 0.0), "size": {"x": 0.9 * m, "y": 0.9 * m, "z": 0.02 * m}, "color": rgba(0.9, 0.1, 0.1, 0.4)});
        let text = json!({"pose": pose(x, y, 0.3 * m, 0.0), "billboard": true, "font_size": 12.0, "scale_invariant": true, "color": rgba(1.0, 0.6, 0.6, 1.0), "text": kind.name()});
        self.entity(
            t_ns,
            format!("conflict/{i}"),
            json!({"cubes": [cube], "texts": [text], "metadata": [kv("robot", i), kv("kind", kind.name())]}),
        )
    }
}

fn rgba(r: f64, g: f64, b: f64, a: f64) -> Value {
    json!({"r": r, "g": g, "b": b, "a": a})
}

fn kv(key: &str, value: impl ToString) -> Value {
    json!({"key": key, "value": value.to_string()})
}

fn log(t_ns: u64, level: u8, name: &str, message: String) -> Message {
    Message {
        topic: LOG.into(),
        schema: schemas::LOG,
        t_ns,
        body: json!({"timestamp": stamp(t_ns), "level": level, "message": message, "name": name, "file": "", "line": 0}),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::msg::Decision;
    use hnav_runtime::msg::{Commit, Truth};

    fn fold() -> SceneFold {
        let grid = Grid::new(4, 2).unwrap();
        SceneFold::new(Picture {
            grid,
            goals: vec![3, 7],
            cell_m: 0.5,
        })
    }

    fn truth(t_ns: u64, xs: [f64; 2]) -> Truth {
        let mut t = Truth {
            sim_time_ns: t_ns,
            poses: vec![Pose::default(); 2],
            ..Truth::default()
        };
        t.poses[0] = Pose {
            x_m: xs[0],
            y_m: 0.25,
            theta_rad: 0.0,
        };
        t.poses[1] = Pose {
            x_m: xs[1],
            y_m: 0.75,
            theta_rad: 0.0,
        };
        t
    }

    #[test]
    fn robots_move_in_the_scene_and_their_speed_is_plotted() {
        let mut f = fold();
        let first = f.truth(truth(0, [0.25, 0.25]).view());
        assert_eq!(first[0].topic, SCENE);
        let out = f.truth(truth(500_000_000, [0.75, 0.25]).view());
        let speed = |m: &Message| m.body["speed_m_s"].as_f64().unwrap();
        assert_eq!(out[1].topic, "/robots/0/stats");
        assert!((speed(&out[1]) - 1.0).abs() < 1e-9, "{}", out[1].body);
        assert_eq!(speed(&out[2]), 0.0);
        let ids: Vec<&str> = out[0].body["entities"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["id"].as_str().unwrap())
            .collect();
        assert_eq!(
            ids,
            ["goal/0", "robot/0", "route/0", "goal/1", "robot/1", "route/1"]
        );
        let robot = &out[0].body["entities"][1]["cubes"][0]["pose"]["position"];
        assert_eq!(robot["x"], 0.75);
    }

    #[test]
    fn a_conflict_is_drawn_and_logged_once_while_it_repeats() {
        let mut f = fold();
        f.truth(truth(0, [0.25, 0.25]).view());
        let mut c = Commit {
            round: 4,
            decisions: vec![Decision::default()],
            ..Commit::default()
        };
        c.decisions[0] = Decision {
            agent: 1,
            verdict: Verdict::Block as u8,
            kind: ConflictKind::HeadOn as u8,
            cell: 6,
            ..Decision::default()
        };
        let lines = f.commit(40, c.view());
        assert_eq!(lines.len(), 1);
        assert_eq!(lines[0].body["name"], "agent-1");
        assert!(
            lines[0].body["message"].as_str().unwrap().contains("block"),
            "{}",
            lines[0].body
        );
        assert!(
            f.commit(50, c.view()).is_empty(),
            "the same block again is not logged again"
        );
        let scene = f.scene(60);
        let ids: Vec<&str> = scene.body["entities"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["id"].as_str().unwrap())
            .collect();
        assert!(ids.contains(&"conflict/1"), "{ids:?}");
        let down = f.lifecycle(70, Role::Agent as u8, 1, LifecycleEvent::Down as u8);
        assert_eq!(down.unwrap().body["level"], ERROR);
        assert!(f
            .lifecycle(80, Role::Agent as u8, 1, LifecycleEvent::Up as u8)
            .is_none());
    }
}
