//! A realtime run whose world is SIGKILLed (the OOM killer, a cluster's
//! time limit): what it wrote stays readable, whole up to the flush bound,
//! and `mrsim report` and `mrsim rerun` read it.

use crate::common::*;
use mrsim_runfolder::stream::read_whole_rows;
use std::path::Path;
use std::process::Stdio;

/// Four robots crossing in realtime for far longer than the test waits.
fn scenario() -> String {
    four_crossing(
        "cut-crossing",
        "duration = 120.0\nmode = \"realtime\"\nstall_timeout = 30.0",
        "",
        false,
    )
}

/// Ticks in one simulated second (dt 0.1): the most a kill may lose.
const TICKS_PER_SECOND: u64 = 10;

/// The world process of run `id`: the `mrsim` process whose command is
/// `world ... --run ID`.
fn world_pid(id: &str) -> Option<u32> {
    find_processes(&["--run", id]).into_iter().find(|pid| {
        std::fs::read(format!("/proc/{pid}/cmdline"))
            .ok()
            .and_then(|c| {
                c.split(|b| *b == 0)
                    .nth(1)
                    .map(|a| a == b"world".as_slice())
            })
            .unwrap_or(false)
    })
}

/// The last tick trajectory.csv holds whole, if any.
fn whole_tick(dir: &Path) -> Option<u64> {
    let (text, _) = read_whole_rows(&dir.join("trajectory.csv")).ok()??;
    mrsim_runfolder::csv::last_whole_tick(&text).ok()?
}

#[test]
fn a_realtime_run_sigkilled_keeps_every_row_up_to_the_bound_and_rerun_and_report_read_it() {
    let _heavy = heavy();
    let dir = fresh_dir("cut");
    let file = dir.join("scenario.toml");
    std::fs::write(&file, scenario()).expect("write scenario");
    let out = dir.join("run");
    let id = run_id("cut");
    let mut launcher = launcher(&file, &out, &id, &["--no-report"], Stdio::null());
    // The known moment: tick 30 (3 simulated seconds) seen in the world's
    // trajectory on the disk, i.e. flushed at least once a simulated second.
    const SEEN: u64 = 30;
    let start = std::time::Instant::now();
    let world = loop {
        if let Some(t) = whole_tick(&out)
            && t >= SEEN
            && let Some(pid) = world_pid(&id)
        {
            break pid;
        }
        if let Ok(Some(status)) = launcher.try_wait() {
            let mut err = String::new();
            if let Some(mut e) = launcher.stderr.take() {
                use std::io::Read;
                let _ = e.read_to_string(&mut err);
            }
            panic!("the run ended before tick {SEEN} was on the disk: {status:?}\n{err}");
        }
        assert!(
            start.elapsed() < std::time::Duration::from_secs(120),
            "tick {SEEN} never reached trajectory.csv"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    send_signal(world, libc::SIGKILL);
    let _ = wait_timeout(&mut launcher, 60);
    remove_leftovers(&id);

    // trajectory.csv: whole ticks 0..=cut, every robot at each, nothing
    // but at most one torn row after them.
    let (text, _torn) = read_whole_rows(&out.join("trajectory.csv"))
        .expect("read")
        .expect("trajectory.csv");
    let cut = mrsim_runfolder::csv::last_whole_tick(&text)
        .expect("every whole row parses")
        .expect("a whole tick");
    assert!(cut >= SEEN, "the kill took back rows already on the disk");
    let mut per_tick = std::collections::BTreeMap::<u64, usize>::new();
    for row in mrsim_runfolder::csv::trajectory_rows(&text).expect("header") {
        let (_, row) = row.expect("row");
        *per_tick.entry(row.tick).or_default() += 1;
    }
    for t in 0..=cut {
        assert_eq!(
            per_tick.get(&t),
            Some(&4),
            "tick {t} not whole in {per_tick:?}"
        );
    }

    // timing.csv: flushed with the trajectory (before it), so it reaches
    // to within the bound of the trajectory's cut.
    let timing = mrsim_runfolder::timing::read_timing(&out).expect("timing.csv reads");
    let last_call = timing.rows.iter().map(|r| r.tick).max().expect("calls");
    assert!(
        last_call + TICKS_PER_SECOND >= cut,
        "timing.csv ends at tick {last_call}, the trajectory at {cut}"
    );
    // events.jsonl: every whole line is JSON; the joins are there.
    let (events, _) = read_whole_rows(&out.join("events.jsonl"))
        .expect("read")
        .expect("events.jsonl");
    let joined = events
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("a whole event line"))
        .filter(|e| e["type"] == "agent_joined")
        .count();
    assert_eq!(joined, 4, "{events}");
    assert!(
        !out.join("metrics.json").exists(),
        "the world wrote metrics.json"
    );

    // mrsim report draws what was recorded.
    let report = mrsim().arg("report").arg(&out).output().expect("report");
    assert_ok(&report);
    assert!(out.join("replay.html").is_file());

    // mrsim rerun replays it up to the cut, byte for byte.
    let again = dir.join("again");
    let rerun = mrsim()
        .arg("rerun")
        .arg(&out)
        .arg("--out")
        .arg(&again)
        .arg("--no-report")
        .output()
        .expect("rerun");
    assert_ok(&rerun);
    let said = String::from_utf8_lossy(&rerun.stdout);
    assert!(said.contains(&format!("rerun up to tick {cut}")), "{said}");
    let recorded: String = text
        .lines()
        .filter(|l| {
            l.split(',')
                .next()
                .and_then(|t| t.parse::<u64>().ok())
                .is_none_or(|t| t <= cut)
        })
        .flat_map(|l| [l, "\n"])
        .collect();
    let replayed =
        std::fs::read_to_string(again.join("trajectory.csv")).expect("rerun's trajectory");
    assert!(
        replayed == recorded,
        "the rerun differs from the record up to tick {cut}: {} lines against {}",
        replayed.lines().count(),
        recorded.lines().count()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
