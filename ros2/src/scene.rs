//! What `hnav-ros2` knows of the run, and the ROS 2 messages it makes of it.
//!
//! Frames: `map` is HNAV's world frame (x along the map's columns, y along its rows, metres;
//! so RViz shows the map file's rows bottom-up), `robot_<i>/odom` the frame of agent `i`'s
//! dead reckoning, which starts at the robot's known start pose in `map` coordinates: so
//! `map` → `robot_<i>/odom` is the identity, and `robot_<i>/odom` → `robot_<i>/base_link` the
//! agent's estimate. Ground truth is the sim's pose in `map`.
//!
//! A robot's plan is the agent's own: the ascent of its last neural-map snapshot (or a
//! route-following agent's route) from the robot's cell now to the snapshot's target, the
//! way the agent's path constructor walks it (to the largest neighbour a robot may step to
//! under the map's corner rule, [`Grid::neighbours`]).

use std::fmt::Write;

use hnav_runtime::grid::geometry::cell_centre_m;
use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use hnav_runtime::msg::{
    self, CommitView, ConflictKind, MapHeader, Pose, Truth, TruthView, Verdict,
};
use hnav_runtime::scenario::Scenario;

use crate::msgs::{
    self, Color, Header, Marker, MarkerArray, OccupancyGrid, Odometry, PoseStamped, Quaternion,
    TfMessage, Time, Transform, TransformStamped, Twist, Vec3,
};

/// One robot's latest state.
#[derive(Debug, Clone, Default)]
pub struct Robot {
    /// The agent's estimate and its sim time.
    pub estimate: Option<(u64, Pose)>,
    /// The last wheel command, rad/s (left, right).
    pub wheels: Option<(f64, f64)>,
    /// The last neural-map snapshot: its header and activations.
    pub map: Option<(MapHeader, Vec<f32>)>,
}

/// The run as far as it is known.
pub struct Scene {
    /// The map now (the scenario's, with the closes and opens whose time has passed).
    pub grid: Grid,
    corners: CornerCutting,
    cell_m: f64,
    wheel_radius_m: f64,
    axle_m: f64,
    goals: Vec<Cell>,
    /// The scenario's closes and opens not yet applied: (sim ns, cells, closed), by time.
    changes: Vec<(u64, Vec<Cell>, bool)>,
    /// Per robot.
    pub robots: Vec<Robot>,
    /// The last ground truth.
    pub truth: Option<Truth>,
    /// The cells of the last round's conflicts.
    pub conflicts: Vec<Cell>,
    /// Whether the map changed since it was last sent.
    pub map_dirty: bool,
}

impl Scene {
    /// The scene of a run of `scenario`, before anything is heard.
    pub fn new(scenario: &Scenario) -> Scene {
        let mut changes: Vec<(u64, Vec<Cell>, bool)> = (scenario.events.iter())
            .filter_map(|e| {
                let (cells, closed) = e.change.cells()?;
                Some(((e.at_s * 1e9).round() as u64, cells.to_vec(), closed))
            })
            .collect();
        changes.sort_by_key(|c| c.0);
        changes.reverse();
        Scene {
            grid: scenario.map.grid.clone(),
            corners: scenario.map.corner_cutting,
            cell_m: scenario.robot.cell_size_m,
            wheel_radius_m: scenario.robot.wheel_radius_m,
            axle_m: scenario.robot.axle_track_m,
            goals: scenario.agents.iter().map(|a| a.goal).collect(),
            changes,
            robots: vec![Robot::default(); scenario.agents.len()],
            truth: None,
            conflicts: Vec::new(),
            map_dirty: true,
        }
    }

    /// Takes ground truth in, applying the world changes its time has passed.
    pub fn truth(&mut self, t: TruthView<'_>) {
        while let Some((at, _, _)) = self.changes.last() {
            if *at > t.sim_time_ns() {
                break;
            }
            if let Some((_, cells, closed)) = self.changes.pop() {
                for c in cells {
                    self.grid.set_blocked(c, closed);
                }
                self.map_dirty = true;
            }
        }
        self.truth.get_or_insert_with(Truth::default).set(t);
    }

    /// Takes a commit in: its conflicts become the markers' conflicts.
    pub fn commit(&mut self, c: CommitView<'_>) {
        self.conflicts.clear();
        for d in c.decisions() {
            let conflict = ConflictKind::from_u8(d.kind).is_some_and(|k| {
                !matches!(
                    k,
                    ConflictKind::None | ConflictKind::Pushed | ConflictKind::Redirected
                )
            });
            if conflict {
                if let Some(cell) = self.cell_of_index(d.cell) {
                    self.conflicts.push(cell);
                }
            }
        }
    }

    fn cell_of_index(&self, i: u32) -> Option<Cell> {
        (i != msg::NO_CELL)
            .then(|| self.grid.cell_at(i as usize))
            .flatten()
    }

    /// The sim time of the last ground truth, ns.
    pub fn now_ns(&self) -> u64 {
        self.truth.as_ref().map_or(0, |t| t.sim_time_ns)
    }

    /// Robot `i`'s true pose.
    pub fn true_pose(&self, i: usize) -> Option<Pose> {
        let t = self.truth.as_ref()?;
        t.poses().get(i).copied()
    }

    fn cell_of(&self, p: &Pose) -> Option<Cell> {
        let (x, y) = ((p.x_m / self.cell_m).floor(), (p.y_m / self.cell_m).floor());
        self.grid.cell_checked(x as i64, y as i64)
    }

    fn centre(&self, c: Cell) -> Vec3 {
        let (x, y) = cell_centre_m(self.cell_m, c);
        Vec3 { x, y, z: 0.0 }
    }

    /// Robot `i`'s commanded body velocity.
    pub fn twist(&self, i: usize) -> Twist {
        let (l, r) = self.robots[i].wheels.unwrap_or((0.0, 0.0));
        Twist {
            linear: Vec3 {
                x: self.wheel_radius_m * (l + r) / 2.0,
                ..Vec3::default()
            },
            angular: Vec3 {
                z: self.wheel_radius_m * (r - l) / self.axle_m,
                ..Vec3::default()
            },
        }
    }

    /// Fills `out` with robot `i`'s odometry: `pose` in `frame`, its commanded twist.
    pub fn odometry(&self, i: usize, stamp_ns: u64, pose: &Pose, frame: &str, out: &mut Odometry) {
        set_header(&mut out.header, stamp_ns, frame);
        set_string(&mut out.child_frame_id, format_args!("robot_{i}/base_link"));
        out.pose.pose = ros_pose(pose);
        out.twist.twist = self.twist(i);
    }

    /// Fills `out` with robot `i`'s plan (see the module docs); empty without a snapshot or
    /// a pose.
    pub fn plan(&self, i: usize, out: &mut msgs::Path) {
        set_header(&mut out.header, self.now_ns(), "map");
        out.poses.clear();
        let (Some((h, values)), Some(pose)) = (&self.robots[i].map, self.true_pose(i)) else {
            return;
        };
        let Some(mut at) = self.cell_of(&pose) else {
            return;
        };
        let value = |c: Cell| values.get(self.grid.index(c)).copied().unwrap_or(f32::MIN);
        let target = self.cell_of_index(h.target);
        let stamp = out.header.stamp;
        let mut push = |c: Cell| {
            out.poses.push(PoseStamped {
                header: Header {
                    stamp,
                    frame_id: "map".into(),
                },
                pose: msgs::Pose {
                    position: self.centre(c),
                    orientation: Quaternion::default(),
                },
            })
        };
        push(at);
        for _ in 0..self.grid.len() {
            if Some(at) == target {
                break;
            }
            let best = (self.grid.neighbours(at, self.corners))
                .map(|(_, n)| n)
                .max_by(|&a, &b| value(a).total_cmp(&value(b)));
            match best {
                Some(n) if value(n) > value(at) => {
                    at = n;
                    push(n);
                }
                _ => break,
            }
        }
    }

    /// Fills `out` with the map now.
    pub fn occupancy(&self, out: &mut OccupancyGrid) {
        set_header(&mut out.header, self.now_ns(), "map");
        out.info.map_load_time = out.header.stamp;
        out.info.resolution = self.cell_m as f32;
        out.info.width = self.grid.width();
        out.info.height = self.grid.height();
        out.info.origin = msgs::Pose::default();
        out.data.clear();
        (out.data).extend(self.grid.blocked().iter().map(|&b| if b { 100 } else { 0 }));
    }

    /// Fills `out` with the transforms of every robot: `map` → `robot_<i>/odom` (identity)
    /// and `robot_<i>/odom` → `robot_<i>/base_link` (the estimate), for the robots with one.
    pub fn tf(&self, out: &mut TfMessage) {
        let mut n = 0;
        for (i, r) in self.robots.iter().enumerate() {
            let Some((t_ns, pose)) = r.estimate else {
                continue;
            };
            let p = ros_pose(&pose);
            let base = Transform {
                translation: p.position,
                rotation: p.orientation,
            };
            for (k, transform) in [Transform::default(), base].into_iter().enumerate() {
                if out.transforms.len() <= n {
                    out.transforms.push(TransformStamped::default());
                }
                let ts = &mut out.transforms[n];
                ts.header.stamp = Time::from_ns(t_ns);
                if k == 0 {
                    set_string(&mut ts.header.frame_id, format_args!("map"));
                    set_string(&mut ts.child_frame_id, format_args!("robot_{i}/odom"));
                } else {
                    set_string(&mut ts.header.frame_id, format_args!("robot_{i}/odom"));
                    set_string(&mut ts.child_frame_id, format_args!("robot_{i}/base_link"));
                }
                ts.transform = transform;
                n += 1;
            }
        }
        out.transforms.truncate(n);
    }

    /// Fills `out` with the markers: a cylinder per robot (ground truth), a cube per goal, a
    /// red sphere per conflict of the last round; the first marker clears the last set.
    pub fn markers(&self, out: &mut MarkerArray) {
        out.markers.clear();
        let stamp = self.now_ns();
        let clear = Marker {
            action: Marker::DELETEALL,
            ..Marker::default()
        };
        out.markers.push(clear);
        let cell = self.cell_m;
        let mut add = |ns: &str, id: usize, kind: i32, position: Vec3, size: Vec3, color: Color| {
            let mut m = Marker {
                ns: ns.into(),
                id: id as i32,
                r#type: kind,
                action: Marker::ADD,
                scale: size,
                color,
                ..Marker::default()
            };
            set_header(&mut m.header, stamp, "map");
            m.pose.position = position;
            out.markers.push(m);
        };
        let flat = |s: f64, h: f64| Vec3 { x: s, y: s, z: h };
        for (i, g) in self.goals.iter().enumerate() {
            let green = Color {
                r: 0.1,
                g: 0.8,
                b: 0.2,
                a: 0.6,
            };
            add(
                "goals",
                i,
                Marker::CUBE,
                self.centre(*g),
                flat(cell * 0.5, 0.02),
                green,
            );
        }
        for i in 0..self.robots.len() {
            if let Some(p) = self.true_pose(i) {
                let blue = Color {
                    r: 0.2,
                    g: 0.4,
                    b: 1.0,
                    a: 1.0,
                };
                let at = Vec3 {
                    x: p.x_m,
                    y: p.y_m,
                    z: 0.0,
                };
                add(
                    "robots",
                    i,
                    Marker::CYLINDER,
                    at,
                    flat(cell * 0.7, 0.05),
                    blue,
                );
            }
        }
        for (k, c) in self.conflicts.iter().enumerate() {
            let red = Color {
                r: 1.0,
                g: 0.1,
                b: 0.1,
                a: 0.8,
            };
            add(
                "conflicts",
                k,
                Marker::SPHERE,
                self.centre(*c),
                flat(cell * 0.4, cell * 0.4),
                red,
            );
        }
    }

    /// Writes `c` as `/hnav/decisions`' JSON into `out`: `{"round":R,"term":T,"decisions":
    /// [{"agent":A,"verdict":"accept","kind":"none","cell":[x,y]|null,"waypoint":[x,y]|null,
    /// "refused":BITS}]}`.
    pub fn decisions_json(&self, c: CommitView<'_>, out: &mut String) {
        out.clear();
        let _ = write!(
            out,
            "{{\"round\":{},\"term\":{},\"decisions\":[",
            c.round(),
            c.term()
        );
        for (k, d) in c.decisions().iter().enumerate() {
            let verdict = Verdict::from_u8(d.verdict).map_or("unknown", Verdict::name);
            let kind = ConflictKind::from_u8(d.kind).map_or("unknown", ConflictKind::name);
            let _ = write!(
                out,
                "{}{{\"agent\":{},\"verdict\":\"{verdict}\",\"kind\":\"{kind}\",\"cell\":",
                if k > 0 { "," } else { "" },
                d.agent
            );
            self.cell_json(d.cell, out);
            out.push_str(",\"waypoint\":");
            self.cell_json(d.waypoint, out);
            let _ = write!(out, ",\"refused\":{}}}", d.refused);
        }
        out.push_str("]}");
    }

    fn cell_json(&self, i: u32, out: &mut String) {
        match self.cell_of_index(i) {
            Some(c) => {
                let _ = write!(out, "[{},{}]", c.x, c.y);
            }
            None => out.push_str("null"),
        }
    }
}

/// An HNAV pose as a ROS pose (z = 0, yaw = theta).
pub fn ros_pose(p: &Pose) -> msgs::Pose {
    msgs::Pose {
        position: Vec3 {
            x: p.x_m,
            y: p.y_m,
            z: 0.0,
        },
        orientation: Quaternion::yaw(p.theta_rad),
    }
}

/// Sets a header in place (the frame's string keeps its allocation).
pub fn set_header(h: &mut Header, stamp_ns: u64, frame: &str) {
    h.stamp = Time::from_ns(stamp_ns);
    if h.frame_id != frame {
        h.frame_id.clear();
        h.frame_id.push_str(frame);
    }
}

fn set_string(s: &mut String, v: std::fmt::Arguments<'_>) {
    s.clear();
    let _ = s.write_fmt(v);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario() -> Scenario {
        let text = "name = \"s\"\n[map]\nrows = [\"....\", \".@..\", \"....\"]\n\
                    [[agents]]\nstart = [0, 0]\ngoal = [3, 2]\n\
                    [[events]]\nat_s = 1.0\nclose = [[3, 0]]\n";
        Scenario::from_str(text, "s.toml", std::path::Path::new(".")).unwrap()
    }

    #[test]
    fn the_plan_ascends_the_snapshot_to_its_target_around_the_wall() {
        let s = scenario();
        let mut scene = Scene::new(&s);
        let grid = s.map.grid.clone();
        // Activation: minus the Manhattan distance to the goal (3, 2), so the ascent walks
        // there.
        let goal = Cell::new(3, 2);
        let values: Vec<f32> = (0..grid.len())
            .map(|i| {
                let c = grid.cell_at(i).unwrap();
                -((c.x.abs_diff(goal.x) + c.y.abs_diff(goal.y)) as f32)
            })
            .collect();
        let header = MapHeader {
            target: grid.index(goal) as u32,
            ..MapHeader::default()
        };
        scene.robots[0].map = Some((header, values));
        let truth = Truth {
            poses: vec![Pose {
                x_m: 0.08,
                y_m: 0.08,
                theta_rad: 0.0,
            }],
            ..Truth::default()
        };
        scene.truth(truth.view());
        let mut path = msgs::Path::default();
        scene.plan(0, &mut path);
        let cells: Vec<(f64, f64)> = (path.poses.iter())
            .map(|p| {
                (
                    p.pose.position.x / 0.16 - 0.5,
                    p.pose.position.y / 0.16 - 0.5,
                )
            })
            .map(|(x, y)| (x.round(), y.round()))
            .collect();
        // (1, 1) is blocked and no corner is cut: along the top row, then down.
        assert_eq!(cells.first(), Some(&(0.0, 0.0)));
        assert_eq!(cells.last(), Some(&(3.0, 2.0)));
        assert!(!cells.contains(&(1.0, 1.0)));
        assert_eq!(path.header.frame_id, "map");
    }

    #[test]
    fn a_close_applies_once_truth_passes_its_time() {
        let mut scene = Scene::new(&scenario());
        let mut grid = OccupancyGrid::default();
        let mut truth = Truth {
            sim_time_ns: 999_999_999,
            ..Truth::default()
        };
        scene.truth(truth.view());
        scene.occupancy(&mut grid);
        assert_eq!(grid.data[3], 0);
        assert_eq!(grid.data[4 + 1], 100);
        truth.sim_time_ns = 1_000_000_000;
        scene.map_dirty = false;
        scene.truth(truth.view());
        assert!(scene.map_dirty);
        scene.occupancy(&mut grid);
        assert_eq!(grid.data[3], 100);
        assert_eq!((grid.info.width, grid.info.height), (4, 3));
    }

    #[test]
    fn decisions_are_one_json_object_per_commit() {
        let scene = Scene::new(&scenario());
        let mut c = msg::Commit {
            round: 7,
            decisions: vec![msg::Decision::default()],
            ..msg::Commit::default()
        };
        c.decisions[0].verdict = Verdict::Accept as u8;
        c.decisions[0].cell = 1;
        let mut out = String::new();
        scene.decisions_json(c.view(), &mut out);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["round"], 7);
        assert_eq!(v["decisions"][0]["verdict"], "accept");
        assert_eq!(v["decisions"][0]["cell"], serde_json::json!([1, 0]));
        assert_eq!(v["decisions"][0]["waypoint"], serde_json::Value::Null);
    }
}
