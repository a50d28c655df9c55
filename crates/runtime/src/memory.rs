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
//!   for them: `SENSED` bytes per other body (216, a `Sensed` with its
//!   shape), so such robots cost the square of their number (10,000 of
//!   them: 21.6 GB); shorter ranges in a crowd are not counted;
//! - with one process per agent (shm, Zenoh), `PER_AGENT_PROCESS` for each
//!   (an agent drives `robots_per_agent` robots).
//!
//! It is compared with every bound the run lives under
//! ([`mrsim_sys::memory::limits`]): the machine's available memory and a
//! memory cgroup's limit (less what the cgroup uses already) against the
//! whole estimate, since every process of the run shares them; the
//! address-space and data rlimits (less what this process has mapped)
//! against its largest process, since each process has its own. The
//! estimate is of resident memory; a process maps more address space than
//! it touches (thread stacks, allocator arenas), so a run that fits
//! RLIMIT_AS only just may still fail to allocate.

use crate::error::Invalid;
use crate::transport::Transport;
use mrsim_scenario::Scenario;
use mrsim_sys::memory::{Limit, LimitKind};

/// What any run holds whatever its size (the binary, rapier, the
/// recording thread's buffers), bytes.
pub const BASE: u64 = 64 << 20;
/// Each robot: its body, driver, planner and observation, its share of the
/// snapshot and of the recording, bytes (17.5 KB measured in the crowded
/// crossing: the slope of the peak from 30,000 to 100,000 robots; rounded
/// up).
pub const PER_ROBOT: u64 = 20 << 10;
/// Each body a robot senses and keeps room for: one
/// [`mrsim_planners::Sensed`], its shape (up to 8 corners) held in it.
pub const SENSED: u64 = std::mem::size_of::<mrsim_planners::Sensed>() as u64;
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
    let bodies = robots + (scenario.obstacles.len() + scenario.people.len()) as u64;
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

/// What a run, or several at once, needs: in all (against the machine's
/// memory and a cgroup's limit, which every process shares) and in its
/// largest process (against an rlimit, which binds each process alone).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Need {
    /// Bytes of every process together.
    pub total: u64,
    /// Bytes of the largest process: the world, or the whole run in-process
    /// (the estimate less its agent processes).
    pub per_process: u64,
}

impl Estimate {
    /// What the run needs, in all and in its largest process.
    pub fn need(&self) -> Need {
        Need {
            total: self.bytes,
            per_process: self
                .bytes
                .saturating_sub(self.processes.saturating_mul(PER_AGENT_PROCESS)),
        }
    }
}

/// The bound among `limits` that `need` exceeds with the least room left
/// (`None`: it fits them all), with the need compared against it.
pub fn exceeded(need: Need, limits: &[Limit]) -> Option<(&Limit, u64)> {
    limits
        .iter()
        .map(|l| {
            let n = if l.kind.per_process() {
                need.per_process
            } else {
                need.total
            };
            (l, n)
        })
        .filter(|(l, n)| *n > l.room())
        .min_by_key(|(l, _)| l.room())
}

/// Refuses a run whose estimate exceeds any of `limits` (the machine's
/// available memory, a memory cgroup's limit, an rlimit:
/// [`mrsim_sys::memory::limits`]; none given: nothing refused), naming the
/// limit, both numbers and how to make the run fit.
pub fn check(
    origin: &str,
    scenario: &Scenario,
    transport: Transport,
    limits: &[Limit],
) -> Result<(), Invalid> {
    let e = estimate(scenario, transport);
    let Some((limit, need)) = exceeded(e.need(), limits) else {
        return Ok(());
    };
    let whole = if limit.kind.per_process() && e.processes > 0 {
        "this run's world process needs"
    } else {
        "this run needs"
    };
    Err(Invalid(format!(
        "{origin}: {whole} about {} of memory ({}), more than the {}: {}. To make it fit: {}",
        gib(need),
        breakdown(&e),
        limit_in_words(limit),
        consequence(limit),
        advice(&e, limit).join(", or ")
    )))
}

/// Refuses `runs` at once (a sweep's `--jobs`) whose estimates together
/// exceed any of `limits`: the `runs` largest of `estimates` against the
/// bounds every process shares, the largest one's biggest process against
/// the rlimits. The refusal names the limit, both numbers and how many runs
/// at once would fit.
pub fn check_at_once(
    origin: &str,
    estimates: &[Estimate],
    runs: usize,
    limits: &[Limit],
) -> Result<(), Invalid> {
    let mut totals: Vec<u64> = estimates.iter().map(|e| e.bytes).collect();
    totals.sort_unstable_by(|a, b| b.cmp(a));
    let together = |n: usize| {
        totals
            .iter()
            .take(n)
            .fold(0u64, |s, t| s.saturating_add(*t))
    };
    let per_process = estimates
        .iter()
        .map(|e| e.need().per_process)
        .max()
        .unwrap_or(0);
    let runs = runs.clamp(1, totals.len().max(1));
    let need = Need {
        total: together(runs),
        per_process,
    };
    let Some((limit, n)) = exceeded(need, limits) else {
        return Ok(());
    };
    let Some(largest) = estimates.iter().max_by_key(|e| e.bytes) else {
        return Ok(());
    };
    let fitting = (1..runs).rev().find(|&j| {
        exceeded(
            Need {
                total: together(j),
                per_process,
            },
            limits,
        )
        .is_none()
    });
    let mut advice = Vec::new();
    if !limit.kind.per_process() {
        advice.push(match fitting {
            Some(j) => format!("run {j} at once (--jobs {j})"),
            None => "run them one at a time (--jobs 1), which alone does not fit either".into(),
        });
    }
    if fitting.is_none() {
        advice.extend(self::advice(largest, limit));
    }
    let what = if limit.kind.per_process() {
        "the largest run's world process needs".to_string()
    } else {
        format!("{runs} runs at once need")
    };
    Err(Invalid(format!(
        "{origin}: {what} about {} of memory (the largest run: {}), more than the {}: {}. To \
         make it fit: {}",
        gib(n),
        breakdown(largest),
        limit_in_words(limit),
        consequence(limit),
        advice.join(", or ")
    )))
}

/// What an estimate is made of, in words.
fn breakdown(e: &Estimate) -> String {
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
    how
}

/// The bound and what it leaves, in words: `0.5 GiB its memory cgroup
/// leaves (...)`.
fn limit_in_words(l: &Limit) -> String {
    let room = gib(l.room());
    match &l.kind {
        LimitKind::Available => format!("{room} available (MemAvailable in /proc/meminfo)"),
        LimitKind::CgroupV1 { dir } => format!(
            "{room} its memory cgroup leaves (cgroup v1 memory.limit_in_bytes {} of {}, \
             less {} used: memory.usage_in_bytes)",
            gib(l.limit),
            dir.display(),
            gib(l.used)
        ),
        LimitKind::CgroupV2 { dir } => format!(
            "{room} its memory cgroup leaves (cgroup v2 memory.max {} of {}, less {} used: \
             memory.current)",
            gib(l.limit),
            dir.display(),
            gib(l.used)
        ),
        LimitKind::AddressSpace => format!(
            "{room} its address-space limit leaves (RLIMIT_AS, `ulimit -v`: {}, less {} \
             mapped already: VmSize)",
            gib(l.limit),
            gib(l.used)
        ),
        LimitKind::Data => format!(
            "{room} its data limit leaves (RLIMIT_DATA, `ulimit -d`: {}, less {} used \
             already: VmData)",
            gib(l.limit),
            gib(l.used)
        ),
    }
}

/// What would happen past the bound.
fn consequence(l: &Limit) -> &'static str {
    if l.kind.per_process() {
        "an allocation past it would fail and abort the run part-way, outputs and all"
    } else {
        "the kernel would kill it part-way, outputs and all"
    }
}

/// How to make a run of estimate `e` fit under `l`.
fn advice(e: &Estimate, l: &Limit) -> Vec<String> {
    let mut advice = vec!["run fewer robots ([generate] count)".to_string()];
    if e.seeing_all > 0 {
        advice.push("give the robots a `sensing_range` shorter than the scene".into());
    }
    if e.processes > 0 && !l.kind.per_process() {
        advice.push("drive more robots per agent process ([world] robots_per_agent)".into());
    }
    advice.push(
        match l.kind {
            LimitKind::Available => "run it on a machine with more memory free",
            LimitKind::CgroupV1 { .. } | LimitKind::CgroupV2 { .. } => {
                "give its container or job more memory (docker --memory, a Kubernetes \
                 memory limit, Slurm --mem, the cgroup's limit file named above)"
            }
            LimitKind::AddressSpace => "raise the limit (`ulimit -v unlimited`)",
            LimitKind::Data => "raise the limit (`ulimit -d unlimited`)",
        }
        .into(),
    );
    advice
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

    fn available(bytes: u64) -> Vec<Limit> {
        vec![Limit {
            kind: LimitKind::Available,
            limit: bytes,
            used: 0,
        }]
    }

    #[test]
    fn a_run_past_what_is_available_is_refused_naming_both_and_how_to_fit() {
        let s = scenario(1000, 1, "sensing_range = 5.0");
        let need = estimate(&s, Transport::Inproc).bytes;
        assert!(check("big.toml", &s, Transport::Inproc, &available(need)).is_ok());
        assert!(check("big.toml", &s, Transport::Inproc, &[]).is_ok());
        let err = check("big.toml", &s, Transport::Inproc, &available(need - 1))
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
        let err = check("big.toml", &s, Transport::Shm, &available(1 << 20))
            .expect_err("refused")
            .0;
        assert!(err.contains("1000 agent processes"), "{err}");
        assert!(err.contains("robots_per_agent"), "{err}");
        let all = scenario(1000, 1, "");
        let err = check("big.toml", &all, Transport::Inproc, &available(1 << 20))
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

    #[test]
    fn the_tightest_limit_exceeded_is_named_with_what_it_allows_and_what_is_used() {
        let s = scenario(1000, 1, "sensing_range = 5.0");
        let need = estimate(&s, Transport::Inproc).bytes;
        let limits = vec![
            Limit {
                kind: LimitKind::Available,
                limit: 20 << 30,
                used: 0,
            },
            Limit {
                kind: LimitKind::CgroupV1 {
                    dir: "/sys/fs/cgroup/memory/job".into(),
                },
                limit: 96 << 20,
                used: 64 << 20,
            },
            Limit {
                kind: LimitKind::CgroupV2 {
                    dir: "/sys/fs/cgroup/job".into(),
                },
                limit: 1 << 30,
                used: 0,
            },
        ];
        assert!(need > 32 << 20);
        let err = check("big.toml", &s, Transport::Inproc, &limits)
            .expect_err("refused")
            .0;
        assert!(
            err.contains(
                "more than the 0.0 GiB its memory cgroup leaves (cgroup v1 \
                 memory.limit_in_bytes 0.1 GiB of /sys/fs/cgroup/memory/job, less 0.1 GiB used"
            ),
            "{err}"
        );
        assert!(err.contains("docker --memory"), "{err}");
        assert!(!err.contains("MemAvailable"), "{err}");
        // Room for it all: nothing refused.
        let roomy: Vec<Limit> = limits
            .into_iter()
            .map(|l| Limit {
                used: 0,
                limit: need,
                ..l
            })
            .collect();
        assert!(check("big.toml", &s, Transport::Inproc, &roomy).is_ok());
    }

    #[test]
    fn an_rlimit_binds_the_largest_process_not_the_agent_processes_beside_it() {
        let s = scenario(1000, 1, "sensing_range = 5.0");
        let e = estimate(&s, Transport::Shm);
        let world = BASE + 1000 * PER_ROBOT;
        assert_eq!(e.need().per_process, world);
        let rlimit = |limit: u64| {
            vec![Limit {
                kind: LimitKind::AddressSpace,
                limit,
                used: 0,
            }]
        };
        // The whole run's estimate would not fit one process, but each
        // process has its own limit.
        assert!(e.bytes > world);
        assert!(check("big.toml", &s, Transport::Shm, &rlimit(world)).is_ok());
        let err = check("big.toml", &s, Transport::Shm, &rlimit(world - 1))
            .expect_err("refused")
            .0;
        assert!(
            err.starts_with("big.toml: this run's world process needs about"),
            "{err}"
        );
        assert!(err.contains("RLIMIT_AS, `ulimit -v`"), "{err}");
        assert!(err.contains("ulimit -v unlimited"), "{err}");
        assert!(!err.contains("robots_per_agent"), "{err}");
    }

    #[test]
    fn runs_at_once_are_refused_together_and_told_how_many_would_fit() {
        let s = scenario(1000, 1, "sensing_range = 5.0");
        let one = estimate(&s, Transport::Inproc);
        let four = vec![one; 4];
        let room = available(3 * one.bytes);
        assert!(check_at_once("sweep.toml", &four, 3, &room).is_ok());
        let err = check_at_once("sweep.toml", &four, 4, &room)
            .expect_err("refused")
            .0;
        assert!(
            err.starts_with("sweep.toml: 4 runs at once need about"),
            "{err}"
        );
        assert!(err.contains("run 3 at once (--jobs 3)"), "{err}");
        assert!(!err.contains("run fewer robots"), "{err}");
        // More workers than runs: only the runs there are count.
        assert!(check_at_once("sweep.toml", &four[..2], 8, &room).is_ok());
        // Not even one fits: the scenario's own advice.
        let err = check_at_once("sweep.toml", &four, 2, &available(one.bytes - 1))
            .expect_err("refused")
            .0;
        assert!(err.contains("--jobs 1), which alone does not fit"), "{err}");
        assert!(err.contains("run fewer robots"), "{err}");
    }
}
