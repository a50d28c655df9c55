//! Whether a run fits in the machine's memory, judged before it starts: a
//! run that outgrows it is killed by the kernel part-way, its outputs with
//! it, so a run whose estimate exceeds what is available is refused.
//!
//! The estimate, from the peak resident memory of runs of the current code
//! (BENCHMARKS.md, "Memory per robot"):
//!
//! - every run: `BASE`, and `PER_ROBOT` for each robot (its body, driver,
//!   planner, share of the snapshot and the recording);
//! - a robot whose sensing range reaches across the whole scene (the
//!   default range does) senses every other body each tick and keeps room
//!   for them: `SENSED` bytes per other body, so such robots cost the
//!   square of their number (10,000 of them: 6.4 GB); shorter ranges in a
//!   crowd are not counted;
//! - with one process per agent (shm, Zenoh), `PER_AGENT_PROCESS` for each
//!   (an agent drives `robots_per_agent` robots).
//!
//! It is compared with `MemAvailable` of /proc/meminfo.

use crate::error::Invalid;
use crate::launch::Transport;
use mrsim_scenario::Scenario;

/// What any run holds whatever its size (the binary, rapier, the
/// recording thread's buffers), bytes.
pub const BASE: u64 = 64 << 20;
/// Each robot: its body, driver, planner and observation, its share of the
/// snapshot and of the recording, bytes (17.5 KB measured in the crowded
/// crossing: the slope of the peak from 30,000 to 100,000 robots; rounded
/// up).
pub const PER_ROBOT: u64 = 20 << 10;
/// Each body a robot senses and keeps room for (`mrsim_planners::Sensed`).
pub const SENSED: u64 = 64;
/// Each agent process's own memory (its proportional set size: its heap,
/// iceoryx2 or Zenoh ports, its share of the binary), bytes.
pub const PER_AGENT_PROCESS: u64 = 4 << 20;

/// A run's memory estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Estimate {
    /// Bytes the run is expected to hold at its peak.
    pub bytes: u64,
    /// Robots.
    pub robots: u64,
    /// Robots whose sensing range reaches across the scene.
    pub seeing_all: u64,
    /// Agent processes (0 in-process).
    pub processes: u64,
}

/// The estimate for `scenario` over `transport`.
pub fn estimate(scenario: &Scenario, transport: Transport) -> Estimate {
    let robots = scenario.robots.len() as u64;
    let bodies = robots + scenario.obstacles.len() as u64;
    let reach = extent(scenario);
    let seeing_all = scenario
        .robots
        .iter()
        .filter(|r| r.sensing_range >= reach)
        .count() as u64;
    let processes = match transport {
        Transport::Inproc => 0,
        Transport::Shm | Transport::Zenoh => {
            robots.div_ceil(u64::from(scenario.world.robots_per_agent.max(1)))
        }
    };
    let bytes = BASE
        .saturating_add(robots.saturating_mul(PER_ROBOT))
        .saturating_add(
            seeing_all
                .saturating_mul(bodies.saturating_sub(1))
                .saturating_mul(SENSED),
        )
        .saturating_add(processes.saturating_mul(PER_AGENT_PROCESS));
    Estimate {
        bytes,
        robots,
        seeing_all,
        processes,
    }
}

/// The diagonal of the box around the arena, every start and goal: a
/// sensing range at least this long senses every body of the scene (the
/// default range, 1e9, does).
fn extent(scenario: &Scenario) -> f64 {
    let points = scenario
        .robots
        .iter()
        .flat_map(|r| [r.start, r.goal])
        .chain(scenario.obstacles.iter().map(|o| o.start))
        .chain(scenario.world.arena.iter().flat_map(|a| [a.min, a.max]));
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for [x, y] in points {
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    }
    if lo[0] > hi[0] {
        return 0.0;
    }
    (hi[0] - lo[0]).hypot(hi[1] - lo[1])
}

/// Refuses a run whose estimate exceeds `available` bytes (`None`: not
/// known, nothing refused), saying both and how to make it fit.
pub fn check(
    origin: &str,
    scenario: &Scenario,
    transport: Transport,
    available: Option<u64>,
) -> Result<(), Invalid> {
    let e = estimate(scenario, transport);
    let Some(available) = available else {
        return Ok(());
    };
    if e.bytes <= available {
        return Ok(());
    }
    let mut how = format!("{} robots x {} KB", e.robots, PER_ROBOT >> 10);
    if e.seeing_all > 0 {
        how.push_str(&format!(
            ", {} of them sensing the whole scene x {} B for each other body",
            e.seeing_all, SENSED
        ));
    }
    if e.processes > 0 {
        how.push_str(&format!(
            ", {} agent processes x {} MB",
            e.processes,
            PER_AGENT_PROCESS >> 20
        ));
    }
    how.push_str(&format!(", plus {} MB", BASE >> 20));
    let mut advice = vec!["run fewer robots ([generate] count)".to_string()];
    if e.seeing_all > 0 {
        advice.push("give the robots a `sensing_range` shorter than the scene".into());
    }
    if e.processes > 0 {
        advice.push("drive more robots per agent process ([world] robots_per_agent)".into());
    }
    Err(Invalid(format!(
        "{origin}: this run needs about {} of memory ({how}), more than the {} available \
         (MemAvailable in /proc/meminfo): the kernel would kill it part-way, outputs and \
         all. To make it fit: {}",
        gib(e.bytes),
        gib(available),
        advice.join(", or ")
    )))
}

/// `bytes` in GiB, one decimal.
fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(robots: usize, per_agent: u32, sensing: &str) -> Scenario {
        let text = format!(
            "name = \"big\"\n[world]\nrobots_per_agent = {per_agent}\n[defaults]\n{sensing}\n[generate]\nkind = \"random\"\ncount = {robots}\nradius = 2000.0\n"
        );
        mrsim_scenario::parse(&text, "big.toml")
            .expect("scenario")
            .scenario
    }

    #[test]
    fn the_estimate_grows_by_the_documented_cost_of_each_robot() {
        let near = "sensing_range = 5.0";
        let (a, b) = (scenario(1000, 1, near), scenario(2000, 1, near));
        let inproc = |s| estimate(s, Transport::Inproc).bytes;
        assert_eq!(inproc(&b) - inproc(&a), 1000 * PER_ROBOT);
        assert_eq!(inproc(&a), BASE + 1000 * PER_ROBOT);
        let shm = estimate(&a, Transport::Shm);
        assert_eq!(shm.processes, 1000);
        assert_eq!(
            shm.bytes,
            BASE + 1000 * PER_ROBOT + 1000 * PER_AGENT_PROCESS
        );
        // Groups of 64: 16 processes (the last one uneven).
        let grouped = scenario(1000, 64, near);
        assert_eq!(estimate(&grouped, Transport::Shm).processes, 16);
    }

    #[test]
    fn robots_that_sense_everything_cost_the_square_of_their_number() {
        let all = scenario(1000, 1, "");
        let e = estimate(&all, Transport::Inproc);
        assert_eq!(e.seeing_all, 1000);
        assert_eq!(e.bytes, BASE + 1000 * PER_ROBOT + 1000 * 999 * SENSED);
    }

    #[test]
    fn a_run_past_what_is_available_is_refused_naming_both_and_how_to_fit() {
        let s = scenario(1000, 1, "sensing_range = 5.0");
        let need = estimate(&s, Transport::Inproc).bytes;
        assert!(check("big.toml", &s, Transport::Inproc, Some(need)).is_ok());
        assert!(check("big.toml", &s, Transport::Inproc, None).is_ok());
        let err = check("big.toml", &s, Transport::Inproc, Some(need - 1))
            .expect_err("refused")
            .0;
        assert!(
            err.starts_with("big.toml: this run needs about 0.1 GiB"),
            "{err}"
        );
        assert!(err.contains("1000 robots x 20 KB, plus 64 MB"), "{err}");
        assert!(err.contains("MemAvailable"), "{err}");
        assert!(err.contains("run fewer robots"), "{err}");
        assert!(!err.contains("sensing_range"), "{err}");
        let err = check("big.toml", &s, Transport::Shm, Some(1 << 20))
            .expect_err("refused")
            .0;
        assert!(err.contains("1000 agent processes"), "{err}");
        assert!(err.contains("robots_per_agent"), "{err}");
        let all = scenario(1000, 1, "");
        let err = check("big.toml", &all, Transport::Inproc, Some(1 << 20))
            .expect_err("refused")
            .0;
        assert!(
            err.contains("1000 of them sensing the whole scene"),
            "{err}"
        );
        assert!(
            err.contains("`sensing_range` shorter than the scene"),
            "{err}"
        );
    }
}
