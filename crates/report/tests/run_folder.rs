//! Reading run folders, and the plots and page drawn from them.

mod common;

use common::*;
use mrsim_report::{
    BodyKind, EventKind, PALETTE, RenderError, RunData, plot_size, render_all, robot_color,
    write_plots, write_replay,
};
use std::path::Path;

#[test]
fn a_run_folder_loads_with_every_file() {
    let dir = temp_dir("load");
    write_run(&dir, 3, true);
    let run = RunData::load(&dir).unwrap();
    assert_eq!(run.scenario, scenario(3));
    assert_eq!(run.trajectory.ticks, (0..=TICKS).collect::<Vec<_>>());
    assert_eq!(run.trajectory.bodies.len(), 4);
    let r1 = run.trajectory.body("r1").unwrap();
    assert_eq!(r1.kind, BodyKind::Robot);
    assert_eq!(r1.samples.len(), TICKS as usize + 1);
    let s = r1.at(10).unwrap();
    assert_eq!([s.x, s.y], robot_at(1, 3, 10));
    assert_eq!(run.trajectory.body("o1").unwrap().kind, BodyKind::Obstacle);
    let metrics = run.metrics.as_ref().unwrap();
    assert_eq!(metrics.robots["r1"].deadline_misses, 2);
    assert_eq!(metrics.robots["r1"].latency_us.p99, 90.0);
    assert_eq!(metrics.world_pid, 999);
    let diagnostics = run.diagnostics.as_ref().unwrap();
    assert_eq!(diagnostics.len(), 2 * 3 * (TICKS as usize + 1));
    assert_eq!(run.robot_index("r2"), Some(2));
}

#[test]
fn an_empty_diagnostics_file_reads_as_no_diagnostics_and_non_finite_values_as_numbers() {
    let dir = temp_dir("diag-empty");
    write_run(&dir, 2, false);
    std::fs::write(dir.join("diagnostics.csv"), "").unwrap();
    assert!(RunData::load(&dir).unwrap().diagnostics.is_none());
    std::fs::write(
        dir.join("diagnostics.csv"),
        "tick,time,robot,name,value\n0,0.0,r0,vd_2,inf\n1,0.1,r0,vd_2,3.5\n",
    )
    .unwrap();
    let run = RunData::load(&dir).unwrap();
    let values: Vec<f64> = run.diagnostics.iter().flatten().map(|d| d.value).collect();
    assert_eq!(values, [f64::INFINITY, 3.5]);
    write_plots(&run, &dir).unwrap();
}

#[test]
fn unknown_event_types_are_skipped_and_known_ones_kept_in_order() {
    let dir = temp_dir("events");
    write_run(&dir, 3, false);
    let run = RunData::load(&dir).unwrap();
    let kinds: Vec<&str> = run
        .events
        .iter()
        .map(|e| match &e.kind {
            EventKind::Collision { .. } => "collision",
            EventKind::GoalReached { .. } => "goal",
            EventKind::DeadlineMiss { .. } => "miss",
            EventKind::AgentLost { .. } => "lost",
            EventKind::AgentRejoined { .. } => "rejoined",
            EventKind::CommandRejected { .. } => "rejected",
            EventKind::Unknown => "unknown",
        })
        .collect();
    assert_eq!(
        kinds,
        [
            "miss",
            "miss",
            "collision",
            "lost",
            "rejoined",
            "rejected",
            "goal",
            "goal",
            "goal"
        ]
    );
    assert_eq!(
        run.events[0].kind,
        EventKind::DeadlineMiss {
            robot: "r1".into(),
            late_us: Some(1500.0)
        }
    );
    assert!(run.diagnostics.is_none());
}

#[test]
fn a_missing_trajectory_is_named_in_the_error() {
    let dir = temp_dir("missing");
    write_run(&dir, 2, false);
    std::fs::remove_file(dir.join("trajectory.csv")).unwrap();
    let err = RunData::load(&dir).unwrap_err();
    assert!(
        matches!(&err, RenderError::Missing { path } if path == &dir.join("trajectory.csv")),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(msg.contains("trajectory.csv: missing"), "{msg}");
}

#[test]
fn a_folder_that_does_not_exist_is_refused() {
    let dir = temp_dir("nodir").join("not-there");
    let err = RunData::load(&dir).unwrap_err();
    assert!(matches!(err, RenderError::NotADirectory { .. }), "{err:?}");
}

#[test]
fn a_run_without_metrics_still_loads() {
    let dir = temp_dir("nometrics");
    write_run(&dir, 2, false);
    std::fs::remove_file(dir.join("metrics.json")).unwrap();
    assert!(RunData::load(&dir).unwrap().metrics.is_none());
}

/// Replaces line `line` (1-based) of `file` in `dir` by `text`.
fn replace_line(dir: &Path, file: &str, line: usize, text: &str) {
    let path = dir.join(file);
    let body = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<&str> = body.lines().collect();
    lines[line - 1] = text;
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
}

fn parse_error(dir: &Path) -> (std::path::PathBuf, usize, String) {
    match RunData::load(dir).unwrap_err() {
        RenderError::Parse { path, line, reason } => (path, line, reason),
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn a_bad_number_in_the_trajectory_gives_its_line() {
    let dir = temp_dir("badnum");
    write_run(&dir, 2, false);
    replace_line(&dir, "trajectory.csv", 7, "2,0.2,r0,robot,abc,0,0,0");
    let (path, line, reason) = parse_error(&dir);
    assert_eq!(path, dir.join("trajectory.csv"));
    assert_eq!(line, 7);
    assert!(
        reason.contains("`x`") && reason.contains("`abc`"),
        "{reason}"
    );
    let msg = RunData::load(&dir).unwrap_err().to_string();
    assert!(msg.contains("trajectory.csv:7:"), "{msg}");
}

#[test]
fn a_short_trajectory_row_gives_its_line() {
    let dir = temp_dir("short");
    write_run(&dir, 2, false);
    replace_line(&dir, "trajectory.csv", 12, "3,0.3,r0,robot,1,2");
    let (_, line, reason) = parse_error(&dir);
    assert_eq!(line, 12);
    assert!(reason.contains("6 fields"), "{reason}");
}

#[test]
fn an_unknown_body_kind_gives_its_line() {
    let dir = temp_dir("kind");
    write_run(&dir, 2, false);
    replace_line(&dir, "trajectory.csv", 3, "0,0,r1,drone,0,0,0,0");
    let (_, line, reason) = parse_error(&dir);
    assert_eq!(line, 3);
    assert!(reason.contains("drone"), "{reason}");
}

#[test]
fn a_trajectory_header_without_a_column_is_refused_at_line_one() {
    let dir = temp_dir("header");
    write_run(&dir, 2, false);
    replace_line(&dir, "trajectory.csv", 1, "tick,time,body,kind,x,y,vx");
    let (_, line, reason) = parse_error(&dir);
    assert_eq!(line, 1);
    assert!(reason.contains("`vy`"), "{reason}");
}

#[test]
fn a_malformed_event_line_gives_its_line() {
    let dir = temp_dir("badevent");
    write_run(&dir, 3, false);
    replace_line(
        &dir,
        "events.jsonl",
        4,
        r#"{"tick":25,"time":2.5,"type":"agent_lost"}"#,
    );
    let (path, line, reason) = parse_error(&dir);
    assert_eq!(path, dir.join("events.jsonl"));
    assert_eq!(line, 4);
    assert!(reason.contains("robot"), "{reason}");
}

#[test]
fn a_bad_diagnostics_value_gives_its_line() {
    let dir = temp_dir("baddiag");
    write_run(&dir, 2, true);
    replace_line(&dir, "diagnostics.csv", 5, "1,0.1,r0,potential,high");
    let (path, line, _) = parse_error(&dir);
    assert_eq!(path, dir.join("diagnostics.csv"));
    assert_eq!(line, 5);
}

/// A minimal well-formedness check: every tag opened is closed in order.
fn assert_balanced_xml(text: &str) {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = text;
    let mut seen_root = false;
    while let Some(start) = rest.find('<') {
        rest = &rest[start..];
        if let Some(after) = rest.strip_prefix("<!--") {
            let end = after.find("-->").expect("unclosed comment");
            rest = &after[end + 3..];
            continue;
        }
        let end = rest.find('>').expect("unclosed tag");
        let tag = &rest[1..end];
        rest = &rest[end + 1..];
        if tag.starts_with('?') || tag.starts_with('!') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.trim()),
                "mismatched </{name}>"
            );
        } else if !tag.ends_with('/') {
            let name = tag.split_whitespace().next().unwrap().to_string();
            if stack.is_empty() {
                assert!(!seen_root, "two root elements");
                seen_root = true;
            }
            stack.push(name);
        }
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
    assert!(seen_root);
}

fn check_plots(dir: &Path, run: &RunData) -> Vec<[u8; 3]> {
    write_plots(run, dir).unwrap();
    let svg = std::fs::read_to_string(dir.join("plot.svg")).unwrap();
    assert!(svg.trim_start().starts_with("<svg"), "{}", &svg[..60]);
    assert_balanced_xml(&svg);
    assert!(svg.contains(&run.scenario.name), "title missing from svg");
    let (w, h, pixels) = decode_png(&dir.join("plot.png"));
    assert_eq!((w, h), plot_size(run));
    // The title's text is drawn in the PNG (embedded font): dark pixels
    // in the top 24 rows.
    let dark_in_title = pixels[..(24 * w) as usize]
        .iter()
        .filter(|p| p.iter().all(|&c| c < 100))
        .count();
    assert!(
        dark_in_title > 50,
        "no title text in plot.png ({dark_in_title} dark pixels)"
    );
    pixels
}

#[test]
fn plots_for_one_robot_are_valid_svg_and_png() {
    let dir = temp_dir("plot1");
    write_run(&dir, 1, false);
    let run = RunData::load(&dir).unwrap();
    let pixels = check_plots(&dir, &run);
    assert_eq!(
        plot_size(&run).1,
        1100,
        "no diagnostics panel without diagnostics.csv"
    );
    assert!(
        pixels.contains(&robot_color(0)),
        "r0's trajectory is not in plot.png"
    );
    assert!(!pixels.contains(&robot_color(1)));
}

#[test]
fn plots_for_64_robots_with_diagnostics_are_valid_and_use_the_whole_palette() {
    let dir = temp_dir("plot64");
    write_run(&dir, 64, true);
    let run = RunData::load(&dir).unwrap();
    assert_eq!(
        plot_size(&run).1,
        1100 + 2 * 220,
        "two diagnostics, two panels"
    );
    let pixels = check_plots(&dir, &run);
    for c in PALETTE {
        assert!(pixels.contains(&c), "colour {c:?} missing from plot.png");
    }
}

#[test]
fn a_collision_is_marked_in_red_on_the_map() {
    let dir = temp_dir("plotcoll");
    write_run(&dir, 3, false);
    let run = RunData::load(&dir).unwrap();
    let pixels = check_plots(&dir, &run);
    let red = pixels
        .iter()
        .filter(|&&p| p == mrsim_report::COLLISION)
        .count();
    assert!(red > 10, "{red} collision-red pixels");
    // And nothing red when there is no collision.
    let dir = temp_dir("plotnocoll");
    write_run(&dir, 2, false);
    let pixels = check_plots(&dir, &RunData::load(&dir).unwrap());
    assert!(!pixels.contains(&mrsim_report::COLLISION));
}

#[test]
fn render_all_writes_plots_and_replay_into_the_folder() {
    let dir = temp_dir("all");
    write_run(&dir, 3, true);
    render_all(&dir).unwrap();
    for f in ["plot.svg", "plot.png", "replay.html"] {
        assert!(std::fs::metadata(dir.join(f)).unwrap().len() > 1000, "{f}");
    }
}

#[test]
fn the_replay_page_is_self_contained_and_names_cannot_break_out_of_the_data() {
    let dir = temp_dir("page");
    write_run(&dir, 3, false);
    // A hostile robot name, everywhere the name appears.
    for file in [
        "scenario.json",
        "trajectory.csv",
        "events.jsonl",
        "metrics.json",
    ] {
        let path = dir.join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, text.replace("r0", "</script><b>x")).unwrap();
    }
    let run = RunData::load(&dir).unwrap();
    assert_eq!(run.scenario.robots[0].name, "</script><b>x");
    write_replay(&run, &dir).unwrap();
    let page = std::fs::read_to_string(dir.join("replay.html")).unwrap();
    assert_eq!(
        page.matches("</script>").count(),
        2,
        "data block broken out of"
    );
    assert!(!page.contains("<b>x"));
    for external in ["http://", "https://", "<link", " src="] {
        assert!(!page.contains(external), "page refers to {external}");
    }
}

#[test]
fn a_256_robot_run_gets_plots_and_a_replay_with_cycling_colours() {
    let dir = temp_dir("r256");
    write_run(&dir, 256, true);
    render_all(&dir).unwrap();
    let run = RunData::load(&dir).unwrap();
    let (w, h, pixels) = decode_png(&dir.join("plot.png"));
    assert_eq!((w, h), plot_size(&run));
    for c in PALETTE {
        assert!(pixels.contains(&c));
    }
    assert_eq!(robot_color(255), robot_color(255 % PALETTE.len()));
    let page = std::fs::read_to_string(dir.join("replay.html")).unwrap();
    assert!(page.contains(r#""name":"r255""#));
}

/// Cuts `file` in `dir` `chars` characters before its end (a writer killed
/// mid-line).
fn cut_end(dir: &Path, file: &str, chars: usize) -> usize {
    let path = dir.join(file);
    let body = std::fs::read_to_string(&path).unwrap();
    let cut = &body[..body.len() - chars];
    std::fs::write(&path, cut).unwrap();
    cut.lines().count()
}

#[test]
fn a_last_line_cut_by_a_killed_writer_is_dropped_and_the_rest_kept() {
    let dir = temp_dir("cut");
    write_run(&dir, 2, false);
    let whole = RunData::load(&dir).unwrap();
    let samples = |r: &RunData| {
        r.trajectory
            .bodies
            .iter()
            .map(|b| b.samples.len())
            .sum::<usize>()
    };
    cut_end(&dir, "trajectory.csv", 5);
    cut_end(&dir, "events.jsonl", 3);
    let cut = RunData::load(&dir).unwrap();
    assert_eq!(samples(&cut), samples(&whole) - 1);
    assert_eq!(cut.events.len(), whole.events.len() - 1);
    assert!(whole.cut.is_empty(), "{:?}", whole.cut);
    // Both cut files are named, with their torn line.
    let named: Vec<String> = cut.cut.iter().map(|c| c.to_string()).collect();
    assert_eq!(named.len(), 2, "{named:?}");
    assert!(named[0].contains("trajectory.csv:") && named[0].contains("the run was cut"));
    assert!(named[1].contains("events.jsonl:"), "{named:?}");
}

#[test]
fn a_parquet_trajectory_without_its_footer_is_read_from_its_journal_and_named_as_cut() {
    let dir = temp_dir("cutpq");
    write_run(&dir, 2, false);
    let whole = RunData::load(&dir).unwrap();
    // The same run as a Parquet one killed before its footer: the journal
    // holds the CSV's rows, the Parquet file only its first bytes.
    let scenario = dir.join("scenario.json");
    let mut sc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scenario).unwrap()).unwrap();
    sc["output"]["trajectory"] = "parquet".into();
    std::fs::write(&scenario, sc.to_string()).unwrap();
    std::fs::rename(
        dir.join("trajectory.csv"),
        dir.join(mrsim_runfolder::TRAJECTORY_JOURNAL_FILE),
    )
    .unwrap();
    std::fs::write(dir.join("trajectory.parquet"), b"PAR1").unwrap();
    let cut = RunData::load(&dir).unwrap();
    assert_eq!(cut.trajectory, whole.trajectory);
    assert_eq!(cut.cut.len(), 1, "{:?}", cut.cut);
    assert!(
        cut.cut[0].to_string().contains("no Parquet footer"),
        "{}",
        cut.cut[0]
    );
}

#[test]
fn a_bad_line_in_the_middle_is_still_an_error_even_without_a_final_newline() {
    let dir = temp_dir("cutmid");
    write_run(&dir, 2, false);
    replace_line(&dir, "trajectory.csv", 3, "3,0.3,r0,robot,1,2,x,4");
    let lines = cut_end(&dir, "trajectory.csv", 1);
    let (path, line, _) = parse_error(&dir);
    assert_eq!(path, dir.join("trajectory.csv"));
    assert_eq!(line, 3);
    assert!(lines > 3);
}
