//! `mrsim top` against real worlds: a hand-started `mrsim world` that
//! waits for its agents (so the screen is checked while nothing races),
//! then agents that run it to the end.
//!
//! The first test renders the dashboard on ratatui's TestBackend from a
//! real observer in this process; the second drives the real binary in a
//! tmux pane (Debian's tmux; `.ci/run` installs it; `MRSIM_SKIP_TMUX=1`
//! skips that test on a machine without it).

use crate::common::*;
use mrsim_top::{TopModel, draw, wait_for_setup};
use mrsim_transport::{Namespace, ObserverTransport};
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const ROBOTS: [&str; 3] = ["north", "east", "south-west"];

/// Three robots far apart, each with a short straight way to its goal.
fn scenario(dir: &Path) -> PathBuf {
    let path = dir.join("three.toml");
    std::fs::write(
        &path,
        r#"
name = "three"
description = "three robots far apart, each 1 m from its goal"
[world]
dt = 0.1
duration = 20.0
mode = "lockstep"
[defaults]
planner = "orca"
radius = 0.2
max_speed = 1.0
max_accel = 4.0
goal_tolerance = 0.1
[[robot]]
name = "north"
start = [0.0, 5.0]
goal = [1.0, 5.0]
[[robot]]
name = "east"
start = [5.0, 0.0]
goal = [5.0, 1.0]
[[robot]]
name = "south-west"
start = [-5.0, -5.0]
goal = [-4.0, -5.0]
"#,
    )
    .expect("write scenario");
    path
}

/// One agent per robot of run `run_id`, with `link` (the transport's
/// arguments) after the rest.
fn start_agents(run_id: &str, link: &[&str]) -> Vec<Child> {
    ROBOTS
        .iter()
        .map(|r| {
            mrsim()
                .args(["agent", "--robot", r, "--run", run_id])
                .args(link)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("start agent")
        })
        .collect()
}

fn wait_exit(child: &mut Child, what: &str) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().expect("wait") {
            return s;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("{what} did not end");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn screen(terminal: &Terminal<TestBackend>) -> Vec<String> {
    let buf = terminal.backend().buffer();
    (0..buf.area.height)
        .map(|y| {
            (0..buf.area.width)
                .map(|x| buf[(x, y)].symbol())
                .collect::<String>()
        })
        .collect()
}

/// The table row of `robot`: the screen line with `│robot ` in it.
fn row<'a>(lines: &'a [String], robot: &str) -> Option<&'a String> {
    let cell = format!("│{robot} ");
    lines.iter().find(|l| l.contains(&cell))
}

fn poll_until(
    model: &mut TopModel,
    obs: &mut dyn ObserverTransport,
    what: &str,
    done: impl Fn(&TopModel) -> bool,
) {
    let start = Instant::now();
    loop {
        model.poll(obs).expect("poll");
        if done(model) {
            return;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no {what} within 60 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn the_dashboard_shows_every_robot_of_a_real_world_waiting_then_at_goal() {
    dashboard_of_a_real_world(None);
}

#[test]
fn the_dashboard_shows_a_world_reached_over_zenoh_as_one_over_shared_memory() {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    dashboard_of_a_real_world(Some(&format!("tcp/127.0.0.1:{port}")));
}

/// A hand-started world of three robots (over Zenoh listening at `zenoh`,
/// else over shared memory), watched by `mrsim top`'s observer and drawn
/// on ratatui's TestBackend: every robot waiting, then every robot at its
/// goal and the run finished.
fn dashboard_of_a_real_world(zenoh: Option<&str>) {
    let tag = if zenoh.is_some() { "topz" } else { "topb" };
    let dir = fresh_dir(&format!("top-backend-{tag}"));
    let scen = scenario(&dir);
    let id = run_id(tag);
    let out = dir.join("run");
    let mut world = match zenoh {
        None => hand_started_world(&scen, &out, &id, 60),
        Some(ep) => mrsim()
            .arg("world")
            .arg(&scen)
            .args([
                "--run",
                &id,
                "--start-timeout",
                "60",
                "--transport",
                "zenoh",
                "--listen",
                ep,
                "--out",
            ])
            .arg(&out)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start world"),
    };

    let ns = Namespace::new(&id).expect("run id");
    let options = zenoh.map(|ep| mrsim_transport::zenoh::ZenohOptions {
        endpoint: Some(ep.to_string()),
        config_file: None,
    });
    let mut obs =
        mrsim_top::connect_observer(&ns, "test", options.as_ref(), Duration::from_secs(30))
            .expect("observer attaches");
    let mut model = wait_for_setup(obs.as_mut(), Duration::from_secs(30)).expect("setup");
    assert_eq!(model.run_id, id);
    poll_until(&mut model, obs.as_mut(), "statistics", |m| {
        m.stats.is_some()
    });

    let mut terminal = Terminal::new(TestBackend::new(130, 24)).expect("terminal");
    terminal.draw(|f| draw(f, &model)).expect("draw");
    let lines = screen(&terminal);
    let text = lines.join("\n");
    assert!(
        text.contains("waiting for agents: 0/3 joined"),
        "status line:\n{text}"
    );
    for r in ROBOTS {
        let line = row(&lines, r).unwrap_or_else(|| panic!("no row for {r}:\n{text}"));
        assert!(line.contains("orca"), "{line}");
        assert!(line.contains("waiting"), "{line}");
    }

    let link: Vec<&str> = match zenoh {
        None => vec![],
        Some(ep) => vec!["--transport", "zenoh", "--connect", ep],
    };
    let mut agents = start_agents(&id, &link);
    poll_until(&mut model, obs.as_mut(), "end of the run", |m| {
        m.finished() && m.robots.len() == 3
    });
    terminal.draw(|f| draw(f, &model)).expect("draw");
    let lines = screen(&terminal);
    let text = lines.join("\n");
    assert!(text.contains("finished"), "status line:\n{text}");
    for r in ROBOTS {
        let line = row(&lines, r).unwrap_or_else(|| panic!("no row for {r}:\n{text}"));
        assert!(line.contains("at goal"), "{line}");
    }
    // The observer took no robot and was never waited for.
    assert!(
        model
            .robots
            .iter()
            .all(|s| s.commands > 0 && s.agent_pid != 0),
        "{:?}",
        model.robots
    );
    drop(obs);

    assert!(wait_exit(&mut world, "world").success());
    for a in agents.iter_mut() {
        assert!(wait_exit(a, "agent").success());
    }
    let m = metrics(&out);
    assert_eq!(m["success_rate"], 1.0);
    assert_eq!(m["agents_lost"], 0);
    assert_clean(&id);
}

/// tmux on its own server, whose socket lives in the test's folder.
fn tmux(socket: &Path, args: &[&str]) -> std::process::Output {
    Command::new("tmux")
        .arg("-S")
        .arg(socket)
        .args(args)
        .output()
        .expect("run tmux")
}

#[test]
fn mrsim_top_in_tmux_shows_every_robot_and_ends_with_the_run() {
    if Command::new("tmux").arg("-V").output().is_err() {
        if std::env::var("MRSIM_SKIP_TMUX").as_deref() == Ok("1") {
            skip(
                "mrsim_top_in_tmux_shows_every_robot_and_ends_with_the_run",
                "MRSIM_REQUIRE_TMUX",
                "tmux not installed (MRSIM_SKIP_TMUX=1)",
            );
            return;
        }
        panic!("tmux is needed for this test (apt-get install tmux, or MRSIM_SKIP_TMUX=1)");
    }
    let dir = fresh_dir("top-tmux");
    let scen = scenario(&dir);
    let id = run_id("topt");
    let out = dir.join("run");
    let mut world = hand_started_world(&scen, &out, &id, 60);

    let socket = dir.join("tmux.sock");
    let cmd = format!(
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
            "130",
            "-y",
            "24",
            &cmd,
        ],
    );
    assert!(o.status.success(), "tmux: {o:?}");
    let capture = || {
        let o = tmux(&socket, &["capture-pane", "-p", "-t", "top"]);
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let wait_for = |what: &str, ok: &dyn Fn(&str) -> bool| -> String {
        let start = Instant::now();
        loop {
            let screen = capture();
            if ok(&screen) {
                return screen;
            }
            if start.elapsed() > Duration::from_secs(60) {
                tmux(&socket, &["kill-server"]);
                panic!("no {what} in the pane within 60 s; last screen:\n{screen}");
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    };

    // While the world waits for its agents: every robot has a row.
    let screen = wait_for("row for every robot", &|s| {
        let lines: Vec<String> = s.lines().map(String::from).collect();
        ROBOTS
            .iter()
            .all(|r| row(&lines, r).is_some_and(|l| l.contains("waiting")))
    });
    assert!(
        screen.contains(&format!("mrsim top  {id} · three")),
        "{screen}"
    );

    // The agents run it to the end; top leaves on its own and says so.
    let mut agents = start_agents(&id, &[]);
    let screen = wait_for("exit of top", &|s| s.contains("top-exit-status="));
    tmux(&socket, &["kill-server"]);
    assert!(screen.contains("top-exit-status=0"), "{screen}");
    assert!(
        screen.contains(&format!("run `{id}` finished at tick"))
            && screen.contains("3/3 robots at goal"),
        "{screen}"
    );

    assert!(wait_exit(&mut world, "world").success());
    for a in agents.iter_mut() {
        assert!(wait_exit(a, "agent").success());
    }
    assert_eq!(metrics(&out)["agents_lost"], 0);
    assert_clean(&id);
}
