//! The whole screen of `hnav top`, drawn from a [`ViewState`] into any ratatui backend.
//!
//! ```text
//!  hnav top  RUN  lockstep  lacam rules  round 1234  2093 rounds/s  at goal 3/6  conflicts 12 ...
//! ┌ map ───────────────────┐┌ agents ──────────────────────────┐
//! │  . . 0 . + .           ││ 0  moving      [3, 4] -> [9, 9]  │
//! │  ...                   │├ processes ───────────────────────┤
//! │                        ││ agent 0  pid 4242  running  0  12%│
//! │                        │├ process events ──────────────────┤
//! │                        ││ r40      agent-1 down             │
//! │                        │├ latest decisions ────────────────┤
//! │                        ││ r1234  a3  block  head-on         │
//! │                        ││ r1290  a2  hold   reserved x57    │
//! └────────────────────────┘└──────────────────────────────────┘
//!  q / Esc / Ctrl-C quit                       (or: run ended: ...)
//! ```

use std::time::Instant;

use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Borders, Paragraph};
use ratatui::Frame;

use super::map::{agent_color, agent_label, MapWidget};
use super::state::{AgentState, ProcessEvent, RecentLine, ViewState};
use hnav_runtime::grid::Grid;

/// Columns the side panel takes.
const SIDE: u16 = 46;

/// What the status line says besides the state: the keys while the run goes on, what the
/// viewer waits for once it has ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hints {
    /// While the run goes on.
    pub running: &'static str,
    /// Once it has ended.
    pub ended: &'static str,
}

impl Default for Hints {
    fn default() -> Self {
        Hints {
            running: "q / Esc / Ctrl-C quit",
            ended: "press any key to leave",
        }
    }
}

/// Draws the whole screen of `state` at `now`.
pub fn draw(frame: &mut Frame, state: &ViewState, now: Instant, hints: Hints) {
    let [header, body, status] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Min(3),
        Constraint::Length(1),
    ])
    .areas(frame.area());
    frame.render_widget(Paragraph::new(header_line(state, now)), header);
    let [map_area, side] =
        Layout::horizontal([Constraint::Min(10), Constraint::Length(SIDE)]).areas(body);
    let map_block = Block::default().borders(Borders::ALL).title(" map ");
    let inner = map_block.inner(map_area);
    frame.render_widget(map_block, map_area);
    frame.render_widget(MapWidget::new(state), inner);
    draw_side(frame, state, side);
    frame.render_widget(Paragraph::new(status_line(state, hints)), status);
}

fn header_line(state: &ViewState, now: Instant) -> Line<'static> {
    let bold = Style::default().add_modifier(Modifier::BOLD);
    let mut spans = vec![
        Span::styled(" hnav top  ", bold),
        Span::raw(format!("{}  {}  ", state.info.run_id, state.info.mode)),
        Span::raw(if state.info.rules.is_empty() {
            String::new()
        } else {
            format!("{} rules  ", state.info.rules)
        }),
        Span::styled(format!("round {}", state.round), bold),
        Span::raw(format!(
            "  {:.0} rounds/s  at goal {}/{}",
            state.rounds_per_s(now),
            state.at_goal(),
            state.agents.len()
        )),
    ];
    if let Some(p) = &state.progress {
        spans.push(Span::raw(format!(
            "  conflicts {}  replans {}",
            p.conflicts, p.replans
        )));
    }
    spans.push(Span::raw(format!("  collisions {}", state.collisions)));
    if state.missed_commits > 0 {
        spans.push(Span::styled(
            format!("  {} commits not seen", state.missed_commits),
            Style::default().fg(Color::DarkGray),
        ));
    }
    Line::from(spans)
}

fn status_line(state: &ViewState, hints: Hints) -> Line<'static> {
    match state.ended {
        Some(end) => Line::from(vec![
            Span::styled(
                format!(" run ended: {} ", end.describe()),
                Style::default().fg(Color::Black).bg(Color::Yellow),
            ),
            Span::raw(format!("  {}", hints.ended)),
        ]),
        None => Line::from(Span::styled(
            format!(" {}", hints.running),
            Style::default().fg(Color::DarkGray),
        )),
    }
}

fn draw_side(frame: &mut Frame, state: &ViewState, area: Rect) {
    let agents = u16::try_from(state.agents.len()).unwrap_or(u16::MAX);
    let procs = u16::try_from(state.health.len().max(1)).unwrap_or(u16::MAX);
    let events = u16::try_from(state.events.len().max(1)).unwrap_or(u16::MAX);
    let [a, p, e, r] = Layout::vertical([
        Constraint::Max(agents.saturating_add(2)),
        Constraint::Max(procs.saturating_add(2)),
        Constraint::Max(events.saturating_add(2)),
        Constraint::Min(3),
    ])
    .areas(area);
    let grid = &state.info.grid;
    let agent_lines: Vec<Line> = state
        .agents
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let s = v.state();
            Line::from(vec![
                Span::styled(
                    format!(" {} ", agent_label(i)),
                    Style::default()
                        .fg(agent_color(i))
                        .add_modifier(Modifier::BOLD),
                ),
                Span::styled(format!("{:<11}", s.label()), state_style(s)),
                Span::raw(format!(
                    "{} -> {}",
                    cell_text(grid, v.cell),
                    cell_text(grid, Some(v.goal))
                )),
            ])
        })
        .collect();
    frame.render_widget(panel(agent_lines, " agents "), a);
    let proc_lines: Vec<Line> = if state.health.is_empty() {
        vec![Line::raw(" (no process data)")]
    } else {
        state
            .health
            .iter()
            .map(|h| {
                let cpu = h
                    .cpu_percent
                    .map_or_else(|| "   -".to_string(), |c| format!("{c:3.0}%"));
                Line::raw(format!(
                    " {:<12}{:>8}  {:<8}{:>3}  {cpu}",
                    h.role.node_name(h.index),
                    h.pid,
                    h.state.as_str(),
                    h.restarts
                ))
            })
            .collect()
    };
    frame.render_widget(panel(proc_lines, " processes: pid state restarts cpu "), p);
    let event_lines: Vec<Line> = if state.events.is_empty() {
        vec![Line::styled(
            " (none)",
            Style::default().fg(Color::DarkGray),
        )]
    } else {
        state.events.iter().rev().map(event_line).collect()
    };
    frame.render_widget(panel(event_lines, " process events "), e);
    let recent: Vec<Line> = state.recent.iter().rev().map(recent_line).collect();
    frame.render_widget(panel(recent, " latest decisions "), r);
}

fn panel<'a>(lines: Vec<Line<'a>>, title: &'a str) -> Paragraph<'a> {
    Paragraph::new(lines).block(Block::default().borders(Borders::ALL).title(title))
}

fn recent_line(l: &RecentLine) -> Line<'static> {
    let why = match l.kind {
        hnav_runtime::msg::ConflictKind::None => "",
        k => k.name(),
    };
    let times = if l.times > 1 {
        format!(" x{}", l.times)
    } else {
        String::new()
    };
    Line::raw(format!(
        " r{:<7} a{:<4}{:<8}{why}{times}",
        l.round,
        l.agent,
        l.verdict.name()
    ))
}

fn event_line(e: &ProcessEvent) -> Line<'static> {
    let colour = match e.event {
        hnav_runtime::msg::LifecycleEvent::Restarted => Color::Yellow,
        _ => Color::LightRed,
    };
    Line::styled(
        format!(
            " r{:<7} {} {}",
            e.round,
            e.role.node_name(e.index),
            e.event.name()
        ),
        Style::default().fg(colour),
    )
}

fn state_style(s: AgentState) -> Style {
    let fg = match s {
        AgentState::AtGoal => Color::LightGreen,
        AgentState::Moving => Color::White,
        AgentState::Held | AgentState::Waiting => Color::Yellow,
        AgentState::Blocked | AgentState::Replanning => Color::LightMagenta,
        AgentState::Down => Color::LightRed,
    };
    Style::default().fg(fg)
}

fn cell_text(grid: &Grid, id: Option<u32>) -> String {
    match id.and_then(|i| grid.cell_at(i as usize)) {
        // `[x, y]`, as every other output of HNAV writes a cell.
        Some(c) => c.to_string(),
        None => "(off map)".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_agents_panel_writes_cells_as_every_other_output_does() {
        let grid = Grid::new(5, 4).unwrap();
        // Cell index 17 on a 5-wide grid: column 2, row 3.
        assert_eq!(cell_text(&grid, Some(17)), "[2, 3]");
        assert_eq!(cell_text(&grid, Some(99)), "(off map)");
        assert_eq!(cell_text(&grid, None), "(off map)");
    }
}
