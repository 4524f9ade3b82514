//! The drawing: every element of the report, through `plotters`' SVG backend on pixel
//! coordinates from [`Layout`].
//!
//! Each kind of mark has its own shape, so that the SVG can be checked element by element:
//!
//! | mark | SVG element |
//! |---|---|
//! | obstacle (map), heatmap cell | `<rect>` filled |
//! | start | `<rect>` filled, robot colour, half a cell |
//! | goal | `<rect>` unfilled, robot colour |
//! | committed cell | `<circle>` filled, robot colour |
//! | true trajectory | `<polyline>`, robot colour, one per robot with samples |
//! | conflict | a cross: two `<line>`s, robot colour, in the cell's top-left corner |
//! | replan | a triangle: `<polygon>` of 3 points, robot colour, in the top-right corner |
//! | process down (agent) | a diamond: `<polygon>` of 4 points, robot colour, at the bottom |
//! | collision | `<circle>` unfilled, [`style::COLLISION`] |
//!
//! Marks of one kind share a corner of the cell, so a conflict, a replan and a robot's start
//! or goal in one cell do not hide each other, and each mark has its robot's colour. The
//! legend draws one of each marker (and a swatch per robot) besides; nothing else draws a
//! line, a polyline or a polygon. Text: the title, captions, the map's cell coordinates along
//! its top and left edges (`[x, y]` as `hnav log show` prints them), the lines under each
//! heatmap, the legend and the process events.

use std::path::Path;

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use plotters::style::text_anchor::{HPos, Pos, VPos};

use hnav_runtime::msg::LifecycleEvent;

use super::data::{CellXy, LifeMark, RunData};
use super::layout::{Layout, Panel, AXIS_TOP, CAPTION_PX, LEGEND_LINE, MAX_EVENT_LINES, TITLE_PX};
use super::style::{self, LogScale};
use super::ReportError;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type DrawResult = Result<(), DrawingAreaErrorKind<std::io::Error>>;

/// Draws `data` into the SVG file `path`.
pub fn draw(data: &RunData, path: &Path) -> Result<(), ReportError> {
    let mut events = data.criteria.clone();
    events.truncate(super::layout::MAX_CRITERIA_LINES);
    events.extend(event_lines(&data.lifecycle));
    let layout = Layout::with_events(
        data.width,
        data.height,
        data.maps.len(),
        data.starts.len(),
        events.len(),
    );
    let failed = |e: DrawingAreaErrorKind<std::io::Error>| ReportError::Draw {
        path: path.to_path_buf(),
        problem: e.to_string(),
    };
    {
        let root = SVGBackend::new(path, (layout.width, layout.height)).into_drawing_area();
        draw_all(&root, data, &layout, &events).map_err(failed)?;
        root.present().map_err(failed)?;
    }
    Ok(())
}

fn draw_all(root: &Area<'_>, data: &RunData, layout: &Layout, events: &[String]) -> DrawResult {
    root.fill(&WHITE)?;
    let [first, second] = title(data);
    let x = layout.map.x - super::layout::AXIS_LEFT;
    let top = layout.map.y - AXIS_TOP - CAPTION_PX - TITLE_PX;
    root.draw(&Text::new(first, (x, top), ("sans-serif", 18).into_font()))?;
    root.draw(&Text::new(
        second,
        (x, top + 22),
        ("sans-serif", 14).into_font(),
    ))?;
    draw_map(root, data, &layout.map)?;
    for (panel, snap) in layout.heatmaps.iter().zip(&data.maps) {
        draw_heatmap(root, data, panel, snap)?;
    }
    draw_legend(root, data, layout)?;
    draw_events(root, layout, events)
}

/// The title's two lines: the run (robots, the rules it ran, rounds, collisions), then what
/// the log counts.
fn title(data: &RunData) -> [String; 2] {
    let rules = data
        .rules
        .as_deref()
        .map_or_else(|| "rules not known".to_string(), |r| format!("{r} rules"));
    let restarts = data
        .lifecycle
        .iter()
        .filter(|l| l.event == LifecycleEvent::Restarted)
        .count();
    [
        format!(
            "{} robots, {rules}, {} rounds, {} collisions",
            data.starts.len(),
            data.rounds,
            data.collisions
        ),
        format!(
            "{} conflicts, {} rounds waited, {} replans, {restarts} process restarts",
            data.conflicts.len(),
            data.waited,
            data.replans.len()
        ),
    ]
}

fn caption(root: &Area<'_>, panel: &Panel, text: String) -> DrawResult {
    root.draw(&Text::new(
        text,
        (panel.x, panel.y - AXIS_TOP - CAPTION_PX + 2),
        ("sans-serif", 14).into_font(),
    ))
}

fn frame(root: &Area<'_>, panel: &Panel) -> DrawResult {
    root.draw(&Rectangle::new(
        [(panel.x, panel.y), (panel.right(), panel.bottom())],
        style::FRAME.stroke_width(1),
    ))
}

/// Sizes of the marks on a map of `cell` pixels per cell, and where in its cell each kind
/// of mark sits.
struct Sizes {
    dot: i32,
    start: i32,
    goal: i32,
    cross: i32,
    triangle: i32,
    diamond: i32,
    ring: i32,
    /// From the cell's centre to a corner's marks, px.
    corner: i32,
}

impl Sizes {
    fn of(cell: f64) -> Self {
        let at_least = |f: f64, min: i32| ((cell * f).round() as i32).max(min);
        Sizes {
            dot: at_least(0.1, 1),
            start: at_least(0.25, 2),
            goal: at_least(0.35, 2),
            cross: at_least(0.14, 2),
            triangle: at_least(0.16, 2),
            diamond: at_least(0.16, 2),
            ring: at_least(0.6, 3),
            corner: (cell * 0.3).round() as i32,
        }
    }
}

fn shifted((x, y): (i32, i32), dx: i32, dy: i32) -> (i32, i32) {
    (x + dx, y + dy)
}

fn draw_map(root: &Area<'_>, data: &RunData, map: &Panel) -> DrawResult {
    caption(
        root,
        map,
        "map: committed cells, true trajectories; cells [x, y]".into(),
    )?;
    draw_axes(root, map)?;
    // Under the obstacles: a wall seen is still drawn as a wall.
    for (i, _) in data.sensed.iter().enumerate().filter(|(_, s)| **s) {
        let (c, r) = (i as u32 % map.cols.max(1), i as u32 / map.cols.max(1));
        root.draw(&Rectangle::new(map.cell_rect(c, r), style::SENSED.filled()))?;
    }
    for (i, _) in data.blocked.iter().enumerate().filter(|(_, b)| **b) {
        let (c, r) = (i as u32 % map.cols.max(1), i as u32 / map.cols.max(1));
        root.draw(&Rectangle::new(
            map.cell_rect(c, r),
            style::OBSTACLE.filled(),
        ))?;
    }
    // Cells the swarm saw close: outlined, since they were floor for part of the run.
    for &(c, r) in &data.closed {
        root.draw(&Rectangle::new(
            map.cell_rect(c, r),
            style::CLOSED.stroke_width(2),
        ))?;
    }
    frame(root, map)?;
    let s = Sizes::of(map.cell);
    for (i, cells) in data.committed.iter().enumerate() {
        let colour = style::robot(i);
        for &(c, r) in cells {
            root.draw(&Circle::new(map.centre(c, r), s.dot, colour.filled()))?;
        }
    }
    for (i, t) in data.trajectories.iter().enumerate() {
        if t.len() < 2 {
            continue;
        }
        let points: Vec<(i32, i32)> = t.iter().map(|&(x, y)| map.px(x, y)).collect();
        root.draw(&PathElement::new(points, style::robot(i).stroke_width(2)))?;
    }
    for track in data.movers.iter().filter(|t| !t.is_empty()) {
        let points: Vec<(i32, i32)> = track.iter().map(|&(x, y)| map.px(x, y)).collect();
        let last = points[points.len() - 1];
        root.draw(&DashedPathElement::new(
            points,
            4,
            3,
            style::MOVER.stroke_width(2),
        ))?;
        mover_mark(root, last, s.start, style::MOVER)?;
    }
    for (i, (&start, &goal)) in data.starts.iter().zip(&data.goals).enumerate() {
        let colour = style::robot(i);
        start_mark(root, map.centre(start.0, start.1), s.start, colour)?;
        goal_mark(root, map.centre(goal.0, goal.1), s.goal, colour)?;
    }
    let k = s.corner;
    for m in &data.conflicts {
        let at = shifted(map.centre(m.cell.0, m.cell.1), -k, -k);
        let colour = style::robot(m.agent as usize);
        root.draw(&Cross::new(at, s.cross, colour.stroke_width(2)))?;
    }
    for m in &data.replans {
        let at = shifted(map.centre(m.cell.0, m.cell.1), k, -k);
        let colour = style::robot(m.agent as usize);
        root.draw(&TriangleMarker::new(at, s.triangle, colour.filled()))?;
    }
    for (agent, cell) in downs(&data.lifecycle) {
        let at = shifted(map.centre(cell.0, cell.1), 0, k);
        diamond(root, at, s.diamond, style::robot(agent as usize))?;
    }
    for m in &data.collision_marks {
        root.draw(&Circle::new(
            map.px(m.x, m.y),
            s.ring,
            style::COLLISION.stroke_width(3),
        ))?;
    }
    Ok(())
}

/// The cell coordinates along the map's top (x, columns) and left (y, rows) edges: every
/// [`Layout::axis_step`]-th cell from 0, and the last one.
fn draw_axes(root: &Area<'_>, map: &Panel) -> DrawResult {
    let font = ("sans-serif", 11).into_font();
    let centred = TextStyle::from(font.clone()).pos(Pos::new(HPos::Center, VPos::Center));
    let right = TextStyle::from(font).pos(Pos::new(HPos::Right, VPos::Center));
    let labelled = |n: u32| {
        let step = Layout::axis_step(n, map.cell);
        let last = n.saturating_sub(1);
        (0..n).filter(move |&i| i % step == 0 || (i == last && last % step > step / 2))
    };
    for c in labelled(map.cols) {
        let (x, _) = map.centre(c, 0);
        root.draw(&Text::new(
            c.to_string(),
            (x, map.y - AXIS_TOP / 2),
            centred.clone(),
        ))?;
    }
    for r in labelled(map.rows) {
        let (_, y) = map.centre(0, r);
        root.draw(&Text::new(r.to_string(), (map.x - 4, y), right.clone()))?;
    }
    Ok(())
}

/// Where each agent went down: the robot's cell then, once per `Down` (a `Lost` follows a
/// `Down`, a `Restarted` comes where it went down: the robot stood meanwhile).
fn downs(lifecycle: &[LifeMark]) -> impl Iterator<Item = (u32, CellXy)> + '_ {
    lifecycle
        .iter()
        .filter(|l| l.event == LifecycleEvent::Down)
        .filter_map(|l| l.cell.map(|c| (l.index, c)))
}

fn diamond(root: &Area<'_>, (x, y): (i32, i32), h: i32, colour: RGBColor) -> DrawResult {
    root.draw(&Polygon::new(
        vec![(x, y - h), (x + h, y), (x, y + h), (x - h, y)],
        colour.filled(),
    ))
}

fn start_mark(root: &Area<'_>, (x, y): (i32, i32), h: i32, colour: RGBColor) -> DrawResult {
    root.draw(&Rectangle::new(
        [(x - h, y - h), (x + h, y + h)],
        colour.filled(),
    ))
}

fn goal_mark(root: &Area<'_>, (x, y): (i32, i32), h: i32, colour: RGBColor) -> DrawResult {
    root.draw(&Rectangle::new(
        [(x - h, y - h), (x + h, y + h)],
        colour.stroke_width(2),
    ))
}

fn draw_heatmap(
    root: &Area<'_>,
    data: &RunData,
    panel: &Panel,
    snap: &crate::recording::MapSnapshot,
) -> DrawResult {
    let scale = LogScale::of(&snap.values);
    caption(
        root,
        panel,
        format!(
            "agent {} neural map after round {}",
            snap.header.agent, snap.header.round
        ),
    )?;
    let range = scale.map_or_else(
        || "no positive activation".to_string(),
        |s| format!("log10 activation {:.1} to {:.1}", s.lo, s.hi),
    );
    let goal = data.goals.get(snap.header.agent as usize).copied();
    let [which, why] = map_story(&snap.header, goal, data.rules.as_deref());
    for (k, line) in [range, which, why].into_iter().enumerate() {
        root.draw(&Text::new(
            line,
            (panel.x, panel.bottom() + 4 + k as i32 * CAPTION_PX),
            ("sans-serif", 12).into_font(),
        ))?;
    }
    let cols = panel.cols.max(1);
    for (i, v) in snap.values.iter().enumerate() {
        let (c, r) = (i as u32 % cols, i as u32 / cols);
        let blocked = data.blocked.get(i).copied().unwrap_or(false);
        let colour = match scale.and_then(|s| s.colour(*v)) {
            Some(c) if !blocked => c,
            _ => style::OBSTACLE,
        };
        root.draw(&Rectangle::new(panel.cell_rect(c, r), colour.filled()))?;
    }
    frame(root, panel)
}

/// Which map a snapshot is and why it is of that round, in two lines. An agent publishes
/// its map when it builds it (at the start, and again after a restart) and when it rebuilds
/// it: toward a replan's waypoint, back toward its goal once the waypoint is reached, and
/// around an obstacle it learned (a block by a robot that stands). The report shows the
/// last one, so under rules that replan nobody (`lacam`, `pibt`) it is usually the start's.
pub fn map_story(
    header: &hnav_runtime::msg::MapHeader,
    goal: Option<CellXy>,
    rules: Option<&str>,
) -> [String; 2] {
    let w = header.width.max(1);
    let target = (header.target % w, header.target / w);
    let round = header.round;
    if goal.is_some_and(|g| g != target) {
        return [
            format!(
                "toward waypoint [{}, {}], set after round {round}",
                target.0, target.1
            ),
            "by a replan: its last rebuild".to_string(),
        ];
    }
    let toward = format!("toward its goal [{}, {}]", target.0, target.1);
    if round > 0 {
        return [
            format!("{toward}, rebuilt after round {round}:"),
            "a waypoint reached, an obstacle learned or a restart".to_string(),
        ];
    }
    let why = match rules {
        Some(r @ ("lacam" | "pibt")) => format!("never rebuilt: {r} makes no replans"),
        Some(_) => "never rebuilt: no replan, no obstacle learned".to_string(),
        None => "never rebuilt since".to_string(),
    };
    [format!("{toward}, built at the start;"), why]
}

fn draw_legend(root: &Area<'_>, data: &RunData, layout: &Layout) -> DrawResult {
    let font = ("sans-serif", 13).into_font();
    let h = LEGEND_LINE / 2;
    let label = |i: usize, text: String| -> DrawResult {
        let (x, y) = layout.legend_entry(i);
        root.draw(&Text::new(text, (x + 2 * h + 6, y + 3), font.clone()))
    };
    let robots = data.starts.len();
    for i in 0..robots {
        let (x, y) = layout.legend_entry(i);
        root.draw(&Rectangle::new(
            [(x, y + 3), (x + 2 * h, y + 2 * h - 1)],
            style::robot(i).filled(),
        ))?;
        label(i, format!("robot {i}"))?;
    }
    let centre = |i: usize| {
        let (x, y) = layout.legend_entry(robots + i);
        (x + h, y + h)
    };
    start_mark(root, centre(0), 5, style::OBSTACLE)?;
    label(robots, "start".into())?;
    goal_mark(root, centre(1), 6, style::OBSTACLE)?;
    label(robots + 1, "goal".into())?;
    root.draw(&Circle::new(centre(2), 3, style::OBSTACLE.filled()))?;
    label(robots + 2, "committed cell (line: true path)".into())?;
    root.draw(&Cross::new(centre(3), 5, style::OBSTACLE.stroke_width(2)))?;
    label(robots + 3, "conflict (refused/held)".into())?;
    root.draw(&TriangleMarker::new(centre(4), 6, style::OBSTACLE.filled()))?;
    label(robots + 4, "replan".into())?;
    diamond(root, centre(5), 6, style::OBSTACLE)?;
    label(robots + 5, "agent down".into())?;
    root.draw(&Circle::new(centre(6), 7, style::COLLISION.stroke_width(3)))?;
    label(robots + 6, "collision".into())?;
    let (x, y) = centre(7);
    root.draw(&Rectangle::new(
        [(x - h + 1, y - h + 3), (x + h - 1, y + h - 1)],
        style::CLOSED.stroke_width(2),
    ))?;
    label(robots + 7, "closed during the run".into())?;
    root.draw(&Rectangle::new(
        [
            (centre(8).0 - h + 1, centre(8).1 - h + 3),
            (centre(8).0 + h - 1, centre(8).1 + h - 1),
        ],
        style::SENSED.filled(),
    ))?;
    label(robots + 8, "sensed by a robot".into())?;
    mover_mark(root, centre(9), 5, style::MOVER)?;
    label(robots + 9, "mover (dashed: its track)".into())
}

/// A mover's last place: a filled square, a shape no robot's mark has.
fn mover_mark(root: &Area<'_>, (x, y): (i32, i32), r: i32, colour: RGBColor) -> DrawResult {
    root.draw(&Rectangle::new(
        [(x - r, y - r), (x + r, y + r)],
        colour.filled(),
    ))
}

/// The lines of the process events under the legend: one per round and process, at most
/// [`MAX_EVENT_LINES`] and a count of the rest; none when nothing happened.
pub fn event_lines(lifecycle: &[LifeMark]) -> Vec<String> {
    let mut lines: Vec<(u64, String, Vec<&str>, Option<CellXy>)> = Vec::new();
    for l in lifecycle {
        let who = l.role.node_name(l.index);
        match lines.last_mut() {
            Some((round, p, events, _)) if *round == l.round && *p == who => {
                events.push(l.event.name())
            }
            _ => lines.push((l.round, who, vec![l.event.name()], l.cell)),
        }
    }
    if lines.is_empty() {
        return Vec::new();
    }
    let mut out = vec!["process events (consensus log):".to_string()];
    for (round, who, events, cell) in lines.iter().take(MAX_EVENT_LINES) {
        let at = cell.map_or_else(String::new, |(x, y)| format!(" at [{x}, {y}]"));
        out.push(format!("round {round}: {who} {}{at}", events.join(", ")));
    }
    if lines.len() > MAX_EVENT_LINES {
        out.push(format!(
            "... and {} more (hnav log show DIR)",
            lines.len() - MAX_EVENT_LINES
        ));
    }
    out
}

fn draw_events(root: &Area<'_>, layout: &Layout, lines: &[String]) -> DrawResult {
    let font = ("sans-serif", 13).into_font();
    for (k, line) in lines.iter().enumerate() {
        let (x, y) = layout.events;
        root.draw(&Text::new(
            line.clone(),
            (x, y + k as i32 * LEGEND_LINE),
            font.clone(),
        ))?;
    }
    Ok(())
}
