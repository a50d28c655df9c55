//! The replay page in a real browser: headless Chromium screenshots the
//! page at a given tick and the robots must be in their colours at the
//! pixels trajectory.csv puts them at.
//!
//! Needs `/usr/bin/chromium` (Debian: `apt-get install -y chromium`) or
//! `MRSIM_CHROMIUM=/path/to/chromium`; fails without it unless
//! `MRSIM_SKIP_BROWSER=1`.

mod common;

use common::*;
use mrsim_report::{
    BodyKind, COLLISION, MAP_HEIGHT, MAP_WIDTH, ReplayView, RunData, STRIP_HEIGHT, robot_color,
    write_replay,
};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

const WINDOW: (u32, u32) = (1100, 800);

/// One Chromium at a time: the machine may have two cores.
static BROWSER: Mutex<()> = Mutex::new(());

fn find_chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("MRSIM_CHROMIUM") {
        let p = PathBuf::from(p);
        return p.exists().then_some(p);
    }
    let fixed = PathBuf::from("/usr/bin/chromium");
    if fixed.exists() {
        return Some(fixed);
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|d| ["chromium", "chromium-browser"].map(|n| d.join(n)))
        .find(|p| p.exists())
}

/// The browser, or `None` when it is missing and MRSIM_SKIP_BROWSER=1.
fn chromium() -> Option<PathBuf> {
    match find_chromium() {
        Some(p) => Some(p),
        None if std::env::var("MRSIM_SKIP_BROWSER").as_deref() == Ok("1") => {
            // Seen past libtest's capture, and in CI's list of skips.
            use std::io::Write;
            let line = "skipped: the replay browser test: no chromium (MRSIM_SKIP_BROWSER=1)\n";
            let _ = std::io::stderr().write_all(line.as_bytes());
            let list = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("skipped.txt");
            if let Ok(mut f) = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(list)
            {
                let _ = f.write_all(line.as_bytes());
            }
            None
        }
        None => panic!(
            "headless Chromium not found (/usr/bin/chromium, `chromium` on PATH or \
             MRSIM_CHROMIUM): install it with `apt-get install -y chromium`, or set \
             MRSIM_SKIP_BROWSER=1 to skip this test"
        ),
    }
}

/// Runs Chromium headless on `url` with `extra` arguments; returns stdout.
fn run_chromium(chromium: &Path, url: &str, extra: &[String]) -> String {
    let _one = BROWSER.lock().unwrap_or_else(|e| e.into_inner());
    let profile = temp_dir("chromium-profile");
    let stderr_path = profile.join("stderr.txt");
    let stdout_path = profile.join("stdout.txt");
    let mut child = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
        ])
        .arg(format!(
            "--user-data-dir={}",
            profile.join("data").display()
        ))
        .arg(format!("--window-size={},{}", WINDOW.0, WINDOW.1))
        .args(extra)
        .arg(url)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&stdout_path).unwrap())
        .stderr(std::fs::File::create(&stderr_path).unwrap())
        .spawn()
        .unwrap_or_else(|e| panic!("starting {}: {e}", chromium.display()));
    // A guard against a hung browser, not a timing assertion.
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > Duration::from_secs(180) {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "chromium did not finish in 180 s; stderr:\n{}",
                std::fs::read_to_string(&stderr_path).unwrap_or_default()
            );
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(
        status.success(),
        "chromium failed ({status}); stderr:\n{}",
        std::fs::read_to_string(&stderr_path).unwrap_or_default()
    );
    std::fs::read_to_string(&stdout_path).unwrap()
}

/// A 3-robot run folder with its replay page.
fn replay_run(tag: &str) -> (TempDir, RunData) {
    let dir = temp_dir(tag);
    write_run(&dir, 3, false);
    let run = RunData::load(&dir).unwrap();
    write_replay(&run, &dir).unwrap();
    (dir, run)
}

fn page_url(dir: &Path, tick: u64) -> String {
    format!("file://{}?tick={tick}", dir.join("replay.html").display())
}

struct Shot {
    width: u32,
    height: u32,
    pixels: Vec<[u8; 3]>,
}

impl Shot {
    fn at(&self, x: i64, y: i64) -> [u8; 3] {
        assert!(
            x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height,
            "({x}, {y}) is outside the {}x{} screenshot",
            self.width,
            self.height
        );
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Pixels in the rectangle [x0, x1) x [y0, y1) within `tol` of `c`.
    fn count_near(&self, (x0, y0, x1, y1): (i64, i64, i64, i64), c: [u8; 3], tol: u8) -> usize {
        let mut n = 0;
        for y in y0.max(0)..y1.min(self.height as i64) {
            for x in x0.max(0)..x1.min(self.width as i64) {
                if near(self.at(x, y), c, tol) {
                    n += 1;
                }
            }
        }
        n
    }
}

fn screenshot(chromium: &Path, dir: &Path, tick: u64) -> Shot {
    let out = dir.join(format!("shot-{tick}.png"));
    let _ = std::fs::remove_file(&out);
    run_chromium(
        chromium,
        &page_url(dir, tick),
        &[format!("--screenshot={}", out.display())],
    );
    assert!(out.exists(), "chromium wrote no screenshot");
    let (width, height, pixels) = decode_png(&out);
    assert!(
        width >= MAP_WIDTH && height >= MAP_HEIGHT + STRIP_HEIGHT,
        "screenshot is only {width}x{height}"
    );
    Shot {
        width,
        height,
        pixels,
    }
}

/// Canvas pixel (rounded) of body `name` at `tick`, from trajectory.csv.
fn pixel_of(run: &RunData, view: &ReplayView, name: &str, tick: u64) -> (i64, i64) {
    let s = run.trajectory.body(name).unwrap().at(tick).unwrap();
    let (x, y) = view.world_to_canvas(s.x, s.y);
    (x.round() as i64, y.round() as i64)
}

#[test]
fn robots_are_drawn_in_their_colours_where_the_trajectory_puts_them_at_the_requested_tick() {
    let Some(chromium) = chromium() else { return };
    let (dir, run) = replay_run("browser-robots");
    let view = ReplayView::of(&run);
    assert!(view.radius_px(0.3, BodyKind::Robot) >= 4.0);
    let tick = 10;
    let shot = screenshot(&chromium, &dir, tick);
    for (i, robot) in run.scenario.robots.iter().enumerate() {
        let (px, py) = pixel_of(&run, &view, &robot.name, tick);
        for dy in -1..=1 {
            for dx in -1..=1 {
                let got = shot.at(px + dx, py + dy);
                assert!(
                    near(got, robot_color(i), 6),
                    "{} at tick {tick}: pixel ({}, {}) is {got:?}, expected {:?}",
                    robot.name,
                    px + dx,
                    py + dy,
                    robot_color(i)
                );
            }
        }
        // The disc has the radius it should and is centred there: its
        // colour 2 px inside its edge, not 3 px outside, in 4 directions.
        let r = view.radius_px(robot.radius, BodyKind::Robot);
        for (ux, uy) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
            let inside = (
                (px as f64 + ux * (r - 2.0)).round() as i64,
                (py as f64 + uy * (r - 2.0)).round() as i64,
            );
            let outside = (
                (px as f64 + ux * (r + 3.0)).round() as i64,
                (py as f64 + uy * (r + 3.0)).round() as i64,
            );
            let (a, b) = (shot.at(inside.0, inside.1), shot.at(outside.0, outside.1));
            assert!(
                near(a, robot_color(i), 6),
                "{}: {inside:?} is {a:?}, inside the disc",
                robot.name
            );
            assert!(
                !near(b, robot_color(i), 40),
                "{}: {outside:?} is {b:?}, outside the disc",
                robot.name
            );
        }
        // Where it started it is no longer drawn (only its faded trail).
        let (sx, sy) = pixel_of(&run, &view, &robot.name, 0);
        let there = shot.at(sx, sy);
        assert!(
            !near(there, robot_color(i), 40),
            "{} still drawn at its tick-0 position: {there:?}",
            robot.name
        );
    }
    let (ox, oy) = pixel_of(&run, &view, "o1", tick);
    assert!(
        near(shot.at(ox, oy), [0xc8, 0xc8, 0xc8], 6),
        "obstacle: {:?}",
        shot.at(ox, oy)
    );

    // The timing strip under the map shows r1's two deadline misses in
    // r1's colour, and nothing in r0's or r2's (they have none).
    let strip = (
        0,
        MAP_HEIGHT as i64,
        MAP_WIDTH as i64,
        (MAP_HEIGHT + STRIP_HEIGHT) as i64,
    );
    assert!(
        shot.count_near(strip, robot_color(1), 10) > 4,
        "r1's misses missing from the strip"
    );
    assert_eq!(shot.count_near(strip, robot_color(0), 10), 0);
    assert_eq!(shot.count_near(strip, robot_color(2), 10), 0);
}

#[test]
fn a_collision_flashes_red_at_its_tick_and_is_gone_later() {
    let Some(chromium) = chromium() else { return };
    let (dir, run) = replay_run("browser-collision");
    let view = ReplayView::of(&run);
    let event = run
        .events
        .iter()
        .find(|e| matches!(e.kind, mrsim_report::EventKind::Collision { .. }))
        .unwrap();
    let p = run.collision_point(event).unwrap();
    let (cx, cy) = view.world_to_canvas(p[0], p[1]);
    let around = (
        cx as i64 - 40,
        cy as i64 - 40,
        cx as i64 + 41,
        cy as i64 + 41,
    );
    let at_collision = screenshot(&chromium, &dir, COLLISION_TICK);
    let red = at_collision.count_near(around, COLLISION, 12);
    assert!(
        red > 20,
        "{red} red pixels around the collision at its tick"
    );
    let later = screenshot(&chromium, &dir, COLLISION_TICK + 15);
    assert_eq!(later.count_near(around, COLLISION, 12), 0);
}

#[test]
fn the_tick_in_the_url_is_the_frame_shown() {
    let Some(chromium) = chromium() else { return };
    let (dir, _run) = replay_run("browser-dom");
    let dom = run_chromium(&chromium, &page_url(&dir, 17), &["--dump-dom".to_string()]);
    assert!(
        dom.contains("synthetic-3 - mrsim replay @ tick 17"),
        "title not set:\n{}",
        &dom[..dom.len().min(400)]
    );
    assert!(dom.contains("tick 17 (18/41)"), "clock not at tick 17");
}

#[test]
fn without_a_tick_the_page_plays_to_the_last_tick() {
    let Some(chromium) = chromium() else { return };
    let (dir, _run) = replay_run("browser-play");
    let url = format!("file://{}", dir.join("replay.html").display());
    // Virtual time: the 4 s run at 1x plays out in no real time.
    let dom = run_chromium(
        &chromium,
        &url,
        &[
            "--virtual-time-budget=20000".to_string(),
            "--dump-dom".to_string(),
        ],
    );
    assert!(
        dom.contains("tick 40 (41/41)"),
        "did not play to the end:\n{}",
        dom.lines().find(|l| l.contains("clock")).unwrap_or("")
    );
    assert!(
        dom.contains(r#"<button id="play" type="button">Play</button>"#),
        "not paused at the end"
    );
}

#[test]
fn a_ten_thousand_robot_replay_stays_within_its_budget_and_draws_every_robot() {
    let Some(chromium) = chromium() else { return };
    let dir = temp_dir("browser-10k");
    // 10,000 robots x 201 ticks: two million positions, twice the budget.
    let run = big_run(&dir, 10_000, 200);
    write_replay(&run, &dir).unwrap();
    let bytes = std::fs::metadata(dir.join("replay.html")).unwrap().len();
    assert!(
        bytes < 24 * mrsim_report::MAX_REPLAY_POSITIONS as u64,
        "replay.html is {bytes} bytes"
    );
    let every = mrsim_report::replay_every(&run);
    assert!(every > 1);
    let frames = 200 / every as u64 + 1 + u64::from(200 % every as u64 != 0);
    let dom = run_chromium(&chromium, &page_url(&dir, 200), &["--dump-dom".to_string()]);
    let want = format!("10000 robots drawn, {frames} frames (1 in {every} of 201 recorded ticks)");
    assert!(
        dom.contains(&want),
        "expected `{want}` in:\n{}",
        dom.lines().find(|l| l.contains("drawn")).unwrap_or("")
    );
    assert!(dom.contains("tick 200 ("), "not at the last tick");
}
