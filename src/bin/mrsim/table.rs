//! The summary table printed after a run, from metrics.json.

use mrsim_runfolder::RunMetrics;
use mrsim_runfolder::metrics::EndedBy;
use std::fmt::Write;

/// `v` with `digits` decimals, `-` if there is none.
pub(crate) fn num(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}"))
        .unwrap_or_else(|| "-".to_string())
}

/// `s`, or `-` if it is empty.
pub(crate) fn text(s: &str) -> String {
    if s.is_empty() { "-" } else { s }.to_string()
}

/// One row per robot (planner, reached goal, time to goal, path length,
/// collisions, min clearance, in a scene with people its contacts with
/// them, its clearance to them and its discomfort time, latency p99,
/// deadline misses), then the run's totals.
pub fn summary(m: &RunMetrics) -> String {
    let mut out = String::new();
    let people = m.person_collisions_total.is_some();
    let mut header = vec![
        "robot", "planner", "goal", "t_goal s", "path", "coll", "min clr",
    ];
    if people {
        header.extend(["p coll", "p clr", "discomf s"]);
    }
    header.extend(["lat p99 us", "misses"]);
    let mut rows: Vec<Vec<String>> = Vec::new();
    for (name, r) in &m.robots {
        let mut row = vec![
            name.clone(),
            text(&r.planner),
            if r.reached_goal { "yes" } else { "NO" }.to_string(),
            num(r.time_to_goal, 2),
            num(Some(r.path_length), 2),
            r.collisions.to_string(),
            num(r.min_clearance, 3),
        ];
        if people {
            row.extend([
                r.person_collisions.map_or("-".into(), |c| c.to_string()),
                num(r.person_min_clearance.flatten(), 3),
                num(r.discomfort_time, 2),
            ]);
        }
        row.extend([
            num(Some(r.latency_us.p99), 0),
            r.deadline_misses.to_string(),
        ]);
        rows.push(row);
    }
    let mut width: Vec<usize> = header.iter().map(|h| h.len()).collect();
    for r in &rows {
        for (w, c) in width.iter_mut().zip(r) {
            *w = (*w).max(c.len());
        }
    }
    let line = |cells: &[String]| {
        let mut s = String::new();
        for (i, (c, &w)) in cells.iter().zip(&width).enumerate() {
            if i < 3 {
                let _ = write!(s, "{c:<w$}  ");
            } else {
                let _ = write!(s, "{c:>w$}  ");
            }
        }
        s.trim_end().to_string()
    };
    let header: Vec<String> = header.into_iter().map(String::from).collect();
    let _ = writeln!(out, "{}", line(&header));
    for r in &rows {
        let _ = writeln!(out, "{}", line(r));
    }
    let _ = writeln!(
        out,
        "{} robots, success {:.0}%, collisions {}, {} ticks ({} s simulated, {} mode, {:.1}x real time), agents lost {}, commands rejected {}",
        rows.len(),
        m.success_rate * 100.0,
        m.collisions_total,
        m.ticks,
        num(Some(m.sim_time), 1),
        text(&m.mode),
        m.realtime_factor,
        m.agents_lost,
        m.commands_rejected,
    );
    if let Some(contacts) = m.person_collisions_total {
        let _ = writeln!(
            out,
            "people: contacts {contacts} (not in the collisions above), min clearance {} m, discomfort {} s (robot-seconds within 0.2 m of a person)",
            num(m.person_min_clearance.flatten(), 3),
            num(m.discomfort_time, 2),
        );
    }
    for line in what_happened(m) {
        let _ = writeln!(out, "{line}");
    }
    out
}

/// Lines naming what a run shows beyond its numbers: its deadlocks, an
/// early end with everyone stuck, and the collisions of planners that do
/// not avoid, so that a scene made to show a failure is not read as a bug.
fn what_happened(m: &RunMetrics) -> Vec<String> {
    let mut lines = Vec::new();
    for d in &m.deadlocks {
        // A deadlock its members got out of is said to be one, so that a
        // run where everyone arrived does not read as a failure.
        let arrived: Vec<&str> = d
            .robots
            .iter()
            .filter(|r| m.robots.get(*r).is_some_and(|x| x.reached_goal))
            .map(String::as_str)
            .collect();
        let after = if arrived.len() == d.robots.len() {
            ", resolved: all reached their goals".to_string()
        } else if let [one] = arrived[..] {
            format!(", {one} later reached its goal")
        } else if !arrived.is_empty() {
            format!(", {} later reached their goals", arrived.join(", "))
        } else {
            String::new()
        };
        lines.push(format!(
            "deadlock at t = {:.1} s: {} stuck within each other's sensing range{after}",
            d.time,
            d.robots.join(", ")
        ));
    }
    let stuck: Vec<&str> = m
        .robots
        .iter()
        .filter(|(_, r)| !r.reached_goal && r.stuck_time.is_some_and(|t| t > 0.0))
        .map(|(n, _)| n.as_str())
        .collect();
    if !stuck.is_empty() && m.deadlocks.is_empty() {
        lines.push(format!(
            "stuck (no progress towards the goal): {}",
            stuck.join(", ")
        ));
    }
    if m.ended_stuck {
        lines.push("ended early: every robot not at its goal was stuck".into());
    }
    if let Some(e) = &m.episode {
        lines.push(episode_line(m, e));
    }
    let blind: Vec<&str> = m
        .robots
        .iter()
        .filter(|(_, r)| r.planner == "homing" && r.collisions > 0)
        .map(|(n, _)| n.as_str())
        .collect();
    if !blind.is_empty() {
        lines.push(format!(
            "homing steers straight at the goal and avoids nothing: the collisions of {} are \
             what it does",
            blind.join(", ")
        ));
    }
    lines
}

/// The run as an episode (`[world] end_on`): its outcome, what ended it,
/// each robot's outcome, the counts and the mean time to goal.
fn episode_line(m: &RunMetrics, e: &mrsim_runfolder::metrics::Episode) -> String {
    let ended = match e.ended_by {
        EndedBy::Collision => "a robot's first contact",
        EndedBy::Goals => "every robot at its goal",
        EndedBy::TimeLimit => "the time limit",
        EndedBy::Stuck => "every robot stuck",
        EndedBy::Interrupted => "a signal",
    };
    let robots: Vec<String> = m
        .robots
        .iter()
        .filter_map(|(n, r)| {
            let o = r.outcome?;
            let at = num(r.outcome_time, 2);
            Some(match &r.collided_with {
                Some(w) => format!("{n} {} with {w} at {at} s", o.name()),
                None => format!("{n} {} at {at} s", o.name()),
            })
        })
        .collect();
    let n = robots.len().max(1) as f64;
    format!(
        "episode ({}): {}, ended by {ended} at t = {:.2} s; {}; success {:.0}%, collision {:.0}%, \
         timeout {:.0}%, time to goal {} s",
        e.end_on.join(", "),
        e.outcome.name(),
        e.time,
        robots.join(", "),
        f64::from(e.success) * 100.0 / n,
        f64::from(e.collision) * 100.0 / n,
        f64::from(e.timeout) * 100.0 / n,
        num(e.time_to_goal, 2),
    )
}

/// The verdict's predicted misses beside the run's measured ones, per
/// robot: its `deadline_misses` of the calls its period plans (`periods`:
/// each robot's `period_ticks`).
pub fn predicted_and_measured(
    v: &mrsim_scenario::schedulability::Verdict,
    m: &RunMetrics,
    periods: &[(String, u32)],
) -> String {
    let measured: Vec<(String, u64, u64)> = periods
        .iter()
        .map(|(name, k)| {
            let misses = m.robots.get(name).map_or(0, |r| r.deadline_misses);
            (name.clone(), misses, m.ticks.div_ceil(u64::from(*k)))
        })
        .collect();
    mrsim_scenario::schedulability::side_by_side(v, &measured)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_has_a_row_per_robot_and_a_totals_line() {
        let m = serde_json::json!({
            "robots": {"a": {"planner": "homing", "reached_goal": true, "time_to_goal": 1.5,
                             "path_length": 3.0, "collisions": 0, "min_clearance": 0.5,
                             "latency_us": {"p99": 42.0}, "deadline_misses": 0},
                       "b": {"planner": "chung-1", "reached_goal": false}},
            "success_rate": 0.5, "collisions_total": 0, "ticks": 10, "sim_time": 1.0,
            "mode": "lockstep", "realtime_factor": 3.0, "agents_lost": 0, "commands_rejected": 0});
        let m: RunMetrics = serde_json::from_value(m).expect("metrics.json's schema");
        let t = summary(&m);
        assert_eq!(t.lines().count(), 4, "{t}");
        assert!(!t.contains("deadlock"), "{t}");
        assert!(
            t.contains("homing") && t.contains("NO") && t.contains("success 50%"),
            "{t}"
        );
    }

    #[test]
    fn a_scene_with_people_shows_their_contacts_clearance_and_discomfort_apart() {
        let m = serde_json::json!({
            "robots": {"r0": {"planner": "orca", "reached_goal": true, "collisions": 0,
                              "min_clearance": 2.5, "person_collisions": 1,
                              "person_min_clearance": -0.05, "discomfort_time": 0.7}},
            "collisions_total": 0, "person_collisions_total": 1,
            "person_min_clearance": -0.05, "discomfort_time": 0.7});
        let m: RunMetrics = serde_json::from_value(m).expect("metrics.json's schema");
        let t = summary(&m);
        let mut lines = t.lines();
        let head = lines.next().expect("a header");
        assert!(
            head.contains("p coll") && head.contains("p clr") && head.contains("discomf s"),
            "{t}"
        );
        let row: Vec<&str> = lines.next().expect("a row").split_whitespace().collect();
        assert_eq!(row[5..10], ["0", "2.500", "1", "-0.050", "0.70"], "{t}");
        assert!(
            t.contains("people: contacts 1 (not in the collisions above), min clearance -0.050 m, discomfort 0.70 s"),
            "{t}"
        );
        // Without people: neither the columns nor the line.
        let none: RunMetrics = serde_json::from_value(serde_json::json!({
            "robots": {"r0": {"planner": "orca", "reached_goal": true}}}))
        .expect("metrics.json's schema");
        let t = summary(&none);
        assert!(!t.contains("p coll") && !t.contains("people:"), "{t}");
    }

    #[test]
    fn a_deadlock_and_a_blind_planner_s_collisions_are_named() {
        let m = serde_json::json!({
            "robots": {"l0": {"planner": "homing", "reached_goal": false, "collisions": 2,
                              "stuck_time": 30.0},
                       "r0": {"planner": "homing", "reached_goal": false, "collisions": 2,
                              "stuck_time": 30.0}},
            "deadlocks": [{"tick": 80, "time": 8.0, "robots": ["l0", "r0"]}],
            "ended_stuck": true});
        let m: RunMetrics = serde_json::from_value(m).expect("metrics.json's schema");
        let t = summary(&m);
        assert!(t.contains("deadlock at t = 8.0 s: l0, r0"), "{t}");
        assert!(t.contains("ended early"), "{t}");
        assert!(
            t.contains("avoids nothing: the collisions of l0, r0"),
            "{t}"
        );
    }

    #[test]
    fn an_episode_s_outcome_is_a_line_of_the_summary() {
        let m = serde_json::json!({
            "robots": {"r0": {"planner": "homing", "reached_goal": false, "collisions": 1,
                              "outcome": "collision", "outcome_time": 1.5,
                              "collided_with": "o1"}},
            "episode": {"end_on": ["collision", "timeout"], "outcome": "collision",
                        "ended_by": "collision", "time": 1.5, "success": 0, "collision": 1,
                        "timeout": 0, "unfinished": 0, "time_to_goal": null}});
        let m: RunMetrics = serde_json::from_value(m).expect("metrics.json's schema");
        let t = summary(&m);
        assert!(
            t.contains(
                "episode (collision, timeout): collision, ended by a robot's first contact at \
                 t = 1.50 s; r0 collision with o1 at 1.50 s; success 0%, collision 100%"
            ),
            "{t}"
        );
    }

    #[test]
    fn a_deadlock_its_robots_got_out_of_is_said_to_be_resolved() {
        let m = serde_json::json!({
            "robots": {"a": {"planner": "orca", "reached_goal": true},
                       "b": {"planner": "orca", "reached_goal": true},
                       "c": {"planner": "orca", "reached_goal": false}},
            "deadlocks": [{"tick": 50, "time": 5.0, "robots": ["a", "b"]},
                          {"tick": 90, "time": 9.0, "robots": ["b", "c"]}]});
        let m: RunMetrics = serde_json::from_value(m).expect("metrics.json's schema");
        let t = summary(&m);
        assert!(
            t.contains("deadlock at t = 5.0 s: a, b stuck within each other's sensing range, resolved: all reached their goals"),
            "{t}"
        );
        assert!(
            t.contains("deadlock at t = 9.0 s: b, c stuck within each other's sensing range, b later reached its goal"),
            "{t}"
        );
    }
}
