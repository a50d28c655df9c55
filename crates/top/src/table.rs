//! `mrsim top`'s robot table, usable at 10,000 robots: summary rows
//! (robots by state; latency and misses as percentiles over the robots),
//! then the robots, the worst first once they do not all fit (lost, then
//! most deadline misses, then highest p99 latency, then most collisions),
//! a page at a time.

use super::{TopModel, micros, robot_color};
use mrsim_proto::RobotStats;
use ratatui::Frame;
use ratatui::layout::{Constraint, Direction, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Cell, Paragraph, Row, Table};

/// In which order the table lists the robots.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Order {
    /// Scenario order while every robot fits, worst first otherwise.
    #[default]
    Auto,
    /// The scenario's order.
    Scenario,
    /// The worst first.
    Worst,
}

/// What the user has scrolled to and asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TableView {
    /// First listed robot (0-based, in the table's order).
    pub offset: usize,
    /// The order.
    pub order: Order,
}

impl TableView {
    /// Moves down (positive) or up by `rows`, kept within `0..robots`.
    pub fn scroll(&mut self, rows: isize, robots: usize) {
        let last = robots.saturating_sub(1);
        self.offset = self.offset.saturating_add_signed(rows).min(last);
    }

    /// Switches between worst first and the scenario's order.
    pub fn toggle_order(&mut self, worst_now: bool) {
        self.order = if worst_now {
            Order::Scenario
        } else {
            Order::Worst
        };
        self.offset = 0;
    }
}

/// Robot indices, the worst first (ties in scenario order).
pub fn worst_first(robots: &[RobotStats], n: usize) -> Vec<usize> {
    let stats = |i: usize| robots.get(i).copied().unwrap_or_default();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| {
        let (x, y) = (stats(a), stats(b));
        let lost = |s: &RobotStats| s.state == mrsim_proto::agent_state::LOST;
        lost(&y)
            .cmp(&lost(&x))
            .then(y.deadline_misses.cmp(&x.deadline_misses))
            .then(y.latency_p99_us.total_cmp(&x.latency_p99_us))
            .then(y.collisions.cmp(&x.collisions))
            .then(a.cmp(&b))
    });
    order
}

/// `p`-th percentile (nearest rank) of `values`, sorted in place.
fn percentile(values: &mut [f64], p: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let rank = ((p / 100.0) * values.len() as f64).ceil() as usize;
    values[rank.clamp(1, values.len()) - 1]
}

/// Lines of summary above the robots.
pub const SUMMARY_ROWS: usize = 3;

/// The summary lines: robots by state, and the spread over robots of their
/// p99 latency and of their deadline misses.
pub fn summary_lines(m: &TopModel) -> [String; SUMMARY_ROWS] {
    let n = m.scenario.robots.len();
    let mut counts = [0usize; 5];
    let states = ["live", "at goal", "waiting", "lost", "?"];
    for i in 0..n {
        let s = m.state_of(i);
        if let Some(k) = states.iter().position(|x| *x == s) {
            counts[k] += 1;
        }
    }
    let by_state: Vec<String> = states
        .iter()
        .zip(counts)
        .filter(|(_, c)| *c > 0)
        .map(|(s, c)| format!("{c} {s}"))
        .collect();
    let with_commands: Vec<&RobotStats> = m.robots.iter().filter(|r| r.commands > 0).collect();
    let mut p99: Vec<f64> = with_commands.iter().map(|r| r.latency_p99_us).collect();
    let mut misses: Vec<f64> = m.robots.iter().map(|r| r.deadline_misses as f64).collect();
    let missed = m.robots.iter().filter(|r| r.deadline_misses > 0).count();
    let latency = if p99.is_empty() {
        "p99 latency: no commands yet".to_string()
    } else {
        let (a, b, c) = (
            percentile(&mut p99, 50.0),
            percentile(&mut p99, 99.0),
            percentile(&mut p99, 100.0),
        );
        format!("p99 µs over robots: median {a:.0}, p99 {b:.0}, max {c:.0}")
    };
    let miss = format!(
        "misses: {missed} robots with any; per robot p99 {:.0}, max {:.0}",
        percentile(&mut misses, 99.0).max(0.0),
        percentile(&mut misses, 100.0).max(0.0)
    );
    [
        format!("{n} robots: {}", by_state.join(", ")),
        latency,
        miss,
    ]
}

/// Width of the name column: the longest name, 5 to 24 characters.
pub fn name_width(m: &TopModel) -> u16 {
    let longest = m
        .scenario
        .robots
        .iter()
        .map(|r| r.name.chars().count())
        .max()
        .unwrap_or(0);
    longest.clamp(5, 24) as u16
}

/// Width of the table: its columns, the gaps between them and the border.
pub fn table_width(m: &TopModel) -> u16 {
    name_width(m) + (17 + 7 + 8 + 8 + 6 + 5 + 8) + 7 + 2
}

/// Rows of robots the table has room for in `area`.
pub fn page_rows(area: Rect, n: usize) -> usize {
    // Border (2), header (1), and the summary rows when they are shown.
    let extra = if n > 1 { 3 + SUMMARY_ROWS } else { 3 };
    usize::from(area.height).saturating_sub(extra)
}

/// Draws the table in `area`, scrolled and ordered as `view` says.
pub fn draw_table(f: &mut Frame, area: Rect, m: &TopModel, view: &TableView) {
    let n = m.scenario.robots.len();
    let page = page_rows(area, n).max(1);
    let worst = match view.order {
        Order::Auto => n > page,
        Order::Scenario => false,
        Order::Worst => true,
    };
    let order: Vec<usize> = if worst {
        worst_first(&m.robots, n)
    } else {
        (0..n).collect()
    };
    let offset = view.offset.min(n.saturating_sub(page));
    let bold = Style::default().add_modifier(Modifier::BOLD);
    let header = Row::new(
        [
            "robot", "planner", "agent", "p50 µs", "p99 µs", "misses", "coll", "pid",
        ]
        .map(|h| Cell::from(h).style(bold)),
    );
    let rows: Vec<Row> = order
        .iter()
        .skip(offset)
        .take(page)
        .map(|&i| robot_row(m, i))
        .collect();
    let title = if n > page {
        format!(
            " agents {}-{} of {n}, {} (PgUp/PgDn, s: order) ",
            offset + 1,
            (offset + page).min(n),
            if worst {
                "worst first"
            } else {
                "scenario order"
            }
        )
    } else {
        " agents ".to_string()
    };
    let widths = [
        Constraint::Length(name_width(m)),
        Constraint::Length(17),
        Constraint::Length(7),
        Constraint::Length(8),
        Constraint::Length(8),
        Constraint::Length(6),
        Constraint::Length(5),
        Constraint::Length(8),
    ];
    let block = Block::default().borders(Borders::ALL).title(title);
    let inner = block.inner(area);
    f.render_widget(block, area);
    let table_area = if n > 1 {
        let [summary, rest] = Layout::default()
            .direction(Direction::Vertical)
            .constraints([Constraint::Length(SUMMARY_ROWS as u16), Constraint::Min(1)])
            .areas(inner);
        let lines: Vec<Line> = summary_lines(m).into_iter().map(Line::from).collect();
        f.render_widget(
            Paragraph::new(lines).style(Style::default().fg(Color::Cyan)),
            summary,
        );
        rest
    } else {
        inner
    };
    let table = Table::new(rows, widths).header(header).column_spacing(1);
    f.render_widget(table, table_area);
}

/// One robot's row.
fn robot_row(m: &TopModel, i: usize) -> Row<'static> {
    let r = &m.scenario.robots[i];
    let st = m.robots.get(i).copied().unwrap_or_default();
    let state = m.state_of(i);
    let state_style = match state {
        "lost" => Style::default().fg(Color::Red),
        "at goal" => Style::default().fg(Color::Green),
        "waiting" | "?" => Style::default().fg(Color::Yellow),
        _ => Style::default(),
    };
    let misses_style = if st.deadline_misses > 0 {
        Style::default().fg(Color::Red)
    } else {
        Style::default()
    };
    Row::new(vec![
        Cell::from(r.name.clone()).style(Style::default().fg(robot_color(i))),
        Cell::from(r.planner.clone()),
        Cell::from(state).style(state_style),
        Cell::from(micros(st.latency_p50_us, st.commands)),
        Cell::from(micros(st.latency_p99_us, st.commands)),
        Cell::from(st.deadline_misses.to_string()).style(misses_style),
        Cell::from(st.collisions.to_string()),
        Cell::from(if st.agent_pid == 0 {
            "-".to_string()
        } else {
            st.agent_pid.to_string()
        }),
    ])
}
