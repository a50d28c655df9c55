//! `mrsim top` with hundreds of robots: summary rows, the worst robots
//! first, and paging, on ratatui's TestBackend from a model with the
//! world's setup and statistics; then the real binary in tmux, paging
//! through the robots of a world that waits for its 300 agents.

use crate::common::*;
use mrsim_proto::{RobotStats, StatsHeader, agent_state, run_phase};
use mrsim_top::{TableView, TopModel, draw_with};
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use std::process::Command;
use std::time::{Duration, Instant};

const N: usize = 300;

/// 300 robots (r000 to r299), all live; r017 lost, r123 with 9 misses, r200 with 2.
fn model() -> TopModel {
    let loaded = mrsim_scenario::parse(
        "[generate]\nkind = \"circle\"\ncount = 300\nradius = 100.0\nname_prefix = \"r\"\n",
        "big.toml",
    )
    .expect("scenario");
    let setup = serde_json::json!({"run_id": "t", "out_dir": "/tmp", "scenario": loaded.scenario});
    let mut m = TopModel::from_setup(setup.to_string().as_bytes()).expect("setup");
    m.stats = Some(StatsHeader {
        tick: 10,
        max_ticks: 600,
        phase: run_phase::RUNNING,
        ..Default::default()
    });
    m.robots = (0..N)
        .map(|i| RobotStats {
            robot_id: i as u32,
            state: if i == 17 {
                agent_state::LOST
            } else {
                agent_state::LIVE
            },
            commands: 10,
            latency_p50_us: 50.0,
            latency_p99_us: 100.0 + i as f64,
            deadline_misses: match i {
                123 => 9,
                200 => 2,
                _ => 0,
            },
            ..Default::default()
        })
        .collect();
    m
}

fn screen(m: &TopModel, view: &TableView) -> Vec<String> {
    let mut t = Terminal::new(TestBackend::new(140, 40)).expect("terminal");
    t.draw(|f| draw_with(f, m, view)).expect("draw");
    let buf = t.backend().buffer().clone();
    (0..buf.area.height)
        .map(|y| {
            (0..buf.area.width)
                .map(|x| buf[(x, y)].symbol().to_string())
                .collect()
        })
        .collect()
}

fn first_row_with<'a>(lines: &[String], names: &[&'a str]) -> Vec<(usize, &'a str)> {
    names
        .iter()
        .filter_map(|n| {
            lines
                .iter()
                .position(|l| l.contains(&format!("│{n} ")))
                .map(|i| (i, *n))
        })
        .collect()
}

#[test]
fn hundreds_of_robots_show_summary_rows_and_the_worst_first() {
    let m = model();
    let lines = screen(&m, &TableView::default());
    let text = lines.join("\n");
    assert!(
        text.contains("300 robots: 299 live, 1 lost"),
        "no state summary:\n{text}"
    );
    assert!(
        text.contains("misses: 2 robots with any; per robot p99 0, max 9"),
        "no miss summary:\n{text}"
    );
    assert!(text.contains("median 249, p99 396, max 399"), "{text}");
    assert!(text.contains("agents 1-"), "no page in the title:\n{text}");
    assert!(text.contains("of 300, worst first"), "{text}");
    // Lost first, then the most misses, then the highest p99.
    let at = first_row_with(&lines, &["r017", "r123", "r200", "r299"]);
    let order: Vec<&str> = at.iter().map(|(_, n)| *n).collect();
    let mut sorted = at.clone();
    sorted.sort();
    assert_eq!(sorted.iter().map(|(_, n)| *n).collect::<Vec<_>>(), order);
    assert_eq!(order, ["r017", "r123", "r200", "r299"]);
    // r000 has the lowest p99 and no misses: not on the first page.
    assert!(first_row_with(&lines, &["r000"]).is_empty());
}

#[test]
fn paging_reaches_the_last_robots() {
    let m = model();
    let mut view = TableView::default();
    view.scroll(10_000, N);
    let text = screen(&m, &view).join("\n");
    assert!(text.contains("of 300, worst first"), "{text}");
    assert!(
        text.contains("│r000 "),
        "the best robot is on the last page:\n{text}"
    );
    assert!(!text.contains("│r017 "), "{text}");
    view.toggle_order(true);
    let text = screen(&m, &view).join("\n");
    assert!(text.contains("agents 1-"), "{text}");
    assert!(text.contains("scenario order"), "{text}");
    assert!(text.contains("│r000 ") && text.contains("│r001 "), "{text}");
}

/// tmux on its own server, whose socket lives in the test's folder.
fn tmux(socket: &std::path::Path, args: &[&str]) -> std::process::Output {
    Command::new("tmux")
        .arg("-S")
        .arg(socket)
        .args(args)
        .output()
        .expect("run tmux")
}

#[test]
fn mrsim_top_in_tmux_pages_through_three_hundred_robots() {
    if Command::new("tmux").arg("-V").output().is_err() {
        if std::env::var("MRSIM_SKIP_TMUX").as_deref() == Ok("1") {
            skip(
                "mrsim_top_in_tmux_pages_through_three_hundred_robots",
                "MRSIM_REQUIRE_TMUX",
                "tmux not installed (MRSIM_SKIP_TMUX=1)",
            );
            return;
        }
        panic!("tmux is needed for this test (apt-get install tmux, or MRSIM_SKIP_TMUX=1)");
    }
    let dir = fresh_dir("top-300");
    let id = run_id("top300");
    let scenario = dir.join("big.toml");
    std::fs::write(
        &scenario,
        "[world]\nduration = 30.0\n\
         [generate]\nkind = \"circle\"\ncount = 300\nradius = 100.0\nname_prefix = \"r\"\n",
    )
    .expect("scenario");
    // A world waiting for its 300 agents: top shows every robot waiting.
    let mut world = mrsim()
        .arg("world")
        .arg(&scenario)
        .args(["--run", &id, "--start-timeout", "60", "--out"])
        .arg(dir.join("out"))
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start world");
    let socket = dir.join("tmux.sock");
    let top = format!(
        "{} top --run {id} --timeout 30; echo top-exit-status=$?; sleep 60",
        env!("CARGO_BIN_EXE_mrsim")
    );
    let o = tmux(
        &socket,
        &[
            "new-session",
            "-d",
            "-s",
            "top",
            "-x",
            "150",
            "-y",
            "40",
            &top,
        ],
    );
    assert!(o.status.success(), "tmux: {o:?}");
    let capture = || {
        let o = tmux(&socket, &["capture-pane", "-p", "-t", "top"]);
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let mut wait_for = |what: &str| -> String {
        let start = Instant::now();
        loop {
            let s = capture();
            if s.contains(what) {
                return s;
            }
            if start.elapsed() > Duration::from_secs(60) {
                tmux(&socket, &["kill-server"]);
                let _ = world.kill();
                panic!("`{what}` never showed:\n{s}");
            }
            std::thread::sleep(Duration::from_millis(200));
        }
    };
    let first = wait_for("300 robots: 300 waiting");
    assert!(first.contains("agents 1-"), "{first}");
    tmux(&socket, &["send-keys", "-t", "top", "End"]);
    let last = wait_for("-300 of 300");
    assert!(last.contains("worst first"), "{last}");
    tmux(&socket, &["send-keys", "-t", "top", "q"]);
    let end = wait_for("top-exit-status=");
    tmux(&socket, &["kill-server"]);
    assert!(end.contains("top-exit-status=0"), "{end}");
    let _ = world.kill();
    let _ = world.wait();
    remove_leftovers(&id);
}
