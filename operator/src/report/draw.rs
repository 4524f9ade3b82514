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
//! | conflict | a cross: two `<line>`s, [`style::CONFLICT`] |
//! | replan | a triangle: `<polygon>`, [`style::REPLAN`] |
//! | collision | `<circle>` unfilled, [`style::COLLISION`] |
//!
//! The legend draws one of each marker (and a swatch per robot) besides; nothing else draws
//! a line, a polyline or a polygon.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::data::RunData;
use super::layout::{Layout, Panel, CAPTION_PX, LEGEND_LINE, TITLE_PX};
use super::style::{self, LogScale};
use super::ReportError;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type DrawResult = Result<(), DrawingAreaErrorKind<std::io::Error>>;

/// Draws `data` into the SVG file `path`.
pub fn draw(data: &RunData, path: &Path) -> Result<(), ReportError> {
    let layout = Layout::new(data.width, data.height, data.maps.len(), data.starts.len());
    let failed = |e: DrawingAreaErrorKind<std::io::Error>| ReportError::Draw {
        path: path.to_path_buf(),
        problem: e.to_string(),
    };
    {
        let root = SVGBackend::new(path, (layout.width, layout.height)).into_drawing_area();
        draw_all(&root, data, &layout).map_err(failed)?;
        root.present().map_err(failed)?;
    }
    Ok(())
}

fn draw_all(root: &Area<'_>, data: &RunData, layout: &Layout) -> DrawResult {
    root.fill(&WHITE)?;
    let title = format!(
        "{} robots, {} rounds, {} conflicts, {} replans, {} collisions",
        data.starts.len(),
        data.rounds,
        data.conflicts.len(),
        data.replans.len(),
        data.collisions
    );
    root.draw(&Text::new(
        title,
        (layout.map.x, layout.map.y - TITLE_PX - CAPTION_PX + 4),
        ("sans-serif", 18).into_font(),
    ))?;
    draw_map(root, data, &layout.map)?;
    for (panel, snap) in layout.heatmaps.iter().zip(&data.maps) {
        draw_heatmap(root, data, panel, snap)?;
    }
    draw_legend(root, data, layout)
}

fn caption(root: &Area<'_>, panel: &Panel, text: String) -> DrawResult {
    root.draw(&Text::new(
        text,
        (panel.x, panel.y - CAPTION_PX + 2),
        ("sans-serif", 14).into_font(),
    ))
}

fn frame(root: &Area<'_>, panel: &Panel) -> DrawResult {
    root.draw(&Rectangle::new(
        [(panel.x, panel.y), (panel.right(), panel.bottom())],
        style::FRAME.stroke_width(1),
    ))
}

/// Sizes of the marks on a map of `cell` pixels per cell.
struct Sizes {
    dot: i32,
    start: i32,
    goal: i32,
    cross: i32,
    triangle: i32,
    ring: i32,
}

impl Sizes {
    fn of(cell: f64) -> Self {
        let at_least = |f: f64, min: i32| ((cell * f).round() as i32).max(min);
        Sizes {
            dot: at_least(0.1, 1),
            start: at_least(0.25, 2),
            goal: at_least(0.35, 2),
            cross: at_least(0.2, 2),
            triangle: at_least(0.22, 2),
            ring: at_least(0.6, 3),
        }
    }
}

fn draw_map(root: &Area<'_>, data: &RunData, map: &Panel) -> DrawResult {
    caption(root, map, "map: committed cells, true trajectories".into())?;
    for (i, _) in data.blocked.iter().enumerate().filter(|(_, b)| **b) {
        let (c, r) = (i as u32 % map.cols.max(1), i as u32 / map.cols.max(1));
        root.draw(&Rectangle::new(
            map.cell_rect(c, r),
            style::OBSTACLE.filled(),
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
    for (i, (&start, &goal)) in data.starts.iter().zip(&data.goals).enumerate() {
        let colour = style::robot(i);
        start_mark(root, map.centre(start.0, start.1), s.start, colour)?;
        goal_mark(root, map.centre(goal.0, goal.1), s.goal, colour)?;
    }
    for m in &data.conflicts {
        root.draw(&Cross::new(
            map.centre(m.cell.0, m.cell.1),
            s.cross,
            style::CONFLICT.stroke_width(2),
        ))?;
    }
    for m in &data.replans {
        root.draw(&TriangleMarker::new(
            map.centre(m.cell.0, m.cell.1),
            s.triangle,
            style::REPLAN.filled(),
        ))?;
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
            "agent {} neural map, round {}",
            snap.header.agent, snap.header.round
        ),
    )?;
    let range = scale.map_or_else(
        || "no positive activation".to_string(),
        |s| format!("log10 activation {:.1} to {:.1}", s.lo, s.hi),
    );
    root.draw(&Text::new(
        range,
        (panel.x, panel.bottom() + 4),
        ("sans-serif", 13).into_font(),
    ))?;
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
    root.draw(&Cross::new(centre(3), 5, style::CONFLICT.stroke_width(2)))?;
    label(robots + 3, "conflict (refused/held)".into())?;
    root.draw(&TriangleMarker::new(centre(4), 6, style::REPLAN.filled()))?;
    label(robots + 4, "replan".into())?;
    root.draw(&Circle::new(centre(5), 7, style::COLLISION.stroke_width(3)))?;
    label(robots + 5, "collision".into())
}
