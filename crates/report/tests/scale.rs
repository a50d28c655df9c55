//! Big runs: the replay page and the plot draw a bounded number of points
//! whatever the run's size, and still show every robot and the last tick.

mod common;

use common::*;
use mrsim_report::{
    MAX_PLOT_POINTS, MAX_REPLAY_POSITIONS, plot_every, replay_every, write_plots, write_replay,
};

#[test]
fn a_small_run_replays_every_recorded_tick() {
    let dir = temp_dir("scale-small");
    let run = big_run(&dir, 20, 100);
    assert_eq!(replay_every(&run), 1);
    write_replay(&run, &dir).unwrap();
    let data = replay_json(&dir);
    assert_eq!(data["ticks"].as_array().unwrap().len(), 101);
    assert_eq!(data["decimation"]["every"], 1);
}

#[test]
fn a_big_run_replay_keeps_within_the_position_budget_and_ends_at_the_last_tick() {
    let dir = temp_dir("scale-replay");
    // 3,000 robots x 1,001 ticks = 3M positions: every 4th tick (and the last).
    let (n, ticks) = (3_000, 1_000);
    let run = big_run(&dir, n, ticks);
    let every = replay_every(&run);
    assert_eq!(every, 4);
    write_replay(&run, &dir).unwrap();
    let data = replay_json(&dir);
    let shown: Vec<u64> = data["ticks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_u64().unwrap())
        .collect();
    assert_eq!(shown.first(), Some(&0));
    assert_eq!(
        shown.last(),
        Some(&ticks),
        "the last tick is always a frame"
    );
    assert!(shown.windows(2).all(|w| w[1] - w[0] <= every as u64));
    let robots = data["robots"].as_array().unwrap();
    assert_eq!(robots.len(), n, "every robot is in the page");
    let positions: usize = robots
        .iter()
        .map(|r| r["x"].as_array().unwrap().len())
        .sum();
    assert!(
        positions <= MAX_REPLAY_POSITIONS + n,
        "{positions} positions"
    );
    assert_eq!(data["decimation"]["ticksRecorded"], ticks + 1);
    // Each position costs two numbers of a few characters: the page's size
    // follows the budget, not the run.
    let bytes = std::fs::metadata(dir.join("replay.html")).unwrap().len();
    assert!(
        bytes < 24 * MAX_REPLAY_POSITIONS as u64,
        "replay.html is {bytes} bytes"
    );
    // A frame shows the robots where the trajectory has them at its tick.
    let k = shown.len() / 2;
    let s = run.trajectory.bodies[7].at(shown[k]).unwrap();
    let x = robots[7]["x"][k].as_f64().unwrap();
    assert!((x - s.x).abs() < 0.01, "{x} vs {}", s.x);
}

#[test]
fn a_big_run_plot_draws_a_bounded_number_of_points() {
    let dir = temp_dir("scale-plot");
    let small = big_run(&dir, 10, 100);
    assert_eq!(plot_every(&small), 1);
    let run = big_run(&dir, 4_000, 200);
    let every = plot_every(&run);
    assert!(
        run.trajectory.bodies.len() * 201 / every <= MAX_PLOT_POINTS + 4_000,
        "every {every}"
    );
    assert!(every > 1);
    write_plots(&run, &dir).unwrap();
    // Two panels of at most MAX_PLOT_POINTS points each, a few dozen bytes
    // a point, plus a start and goal mark per robot.
    let bytes = std::fs::metadata(dir.join("plot.svg")).unwrap().len();
    assert!(
        bytes < 2 * 40 * MAX_PLOT_POINTS as u64 + 4_000 * 400,
        "plot.svg is {bytes} bytes"
    );
}
