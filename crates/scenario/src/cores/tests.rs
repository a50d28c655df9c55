//! The model's textbook cases: periodic tasks released at every multiple
//! of their period while free, each job's response time against its
//! implicit deadline (the next release).

use super::*;

const MS: u64 = 1_000_000;

/// A periodic task: CPU per job and period, ms.
#[derive(Clone, Copy)]
struct Periodic {
    c_ms: u64,
    t_ms: u64,
}

fn cpus(count: u32, scheduler: Scheduler) -> Cpus {
    Cpus {
        count,
        scheduler,
        world_ms: 0.0,
    }
}

fn task(name: &str, period_ticks: u32) -> Task {
    Task {
        name: name.into(),
        period_ticks,
        priority: None,
        reservation: None,
    }
}

/// What a run of periodic tasks gave: per task, the response time of each
/// job that ended (ms), and its misses: jobs that ended after their
/// deadline, and releases skipped because the task was still busy.
#[derive(Debug, Default, Clone)]
struct Outcome {
    responses: Vec<Vec<f64>>,
    misses: Vec<u32>,
}

impl Outcome {
    fn total_misses(&self) -> u32 {
        self.misses.iter().sum()
    }
}

/// Runs `set` on `model` until `horizon_ms`: task i releases a job of
/// `c_ms` at every multiple of `t_ms` at which it is free.
fn run(mut model: Cores, set: &[Periodic], horizon_ms: u64) -> Outcome {
    let n = set.len();
    let mut out = Outcome {
        responses: vec![Vec::new(); n],
        misses: vec![0; n],
    };
    let mut next: Vec<u64> = vec![0; n];
    let mut released_at: Vec<u64> = vec![0; n];
    loop {
        let t = (*next.iter().min().unwrap()).min(horizon_ms * MS);
        let mut done = Vec::new();
        model.run_until(t, |d| {
            done.push(d);
            None
        });
        for d in done {
            let r = d.at_ns - released_at[d.task];
            out.responses[d.task].push(r as f64 / MS as f64);
            if r > set[d.task].t_ms * MS {
                out.misses[d.task] += 1;
            }
        }
        if t >= horizon_ms * MS {
            break;
        }
        for i in 0..n {
            if next[i] == t {
                if model.busy(i) {
                    out.misses[i] += 1;
                } else {
                    model.release(i, set[i].c_ms * MS, t / (set[i].t_ms * MS));
                    released_at[i] = t;
                }
                next[i] += set[i].t_ms * MS;
            }
        }
    }
    out
}

#[test]
fn two_tasks_on_one_core_under_fifo_respond_as_the_response_time_analysis_says() {
    // tau1 = (C 20, T 50) above tau2 = (C 40, T 100). By hand (Joseph &
    // Pandya): R1 = 20; R2 = 40 + ceil(R2 / 50) 20: 40 -> 60 -> 80 -> 80.
    // tau2's first job: 20-50 and 70-80 of its 40 ms, done at 80.
    let mut hi = task("hi", 5);
    hi.priority = Some(Priority::Level(20));
    let mut lo = task("lo", 10);
    lo.priority = Some(Priority::Level(10));
    let model = Cores::new(&cpus(1, Scheduler::Fifo), &[lo, hi]).unwrap();
    let set = [
        Periodic {
            c_ms: 40,
            t_ms: 100,
        },
        Periodic { c_ms: 20, t_ms: 50 },
    ];
    let out = run(model, &set, 1000);
    assert!(out.responses[1].iter().all(|&r| r == 20.0), "{out:?}");
    assert_eq!(out.responses[0].iter().cloned().fold(0.0, f64::max), 80.0);
    assert_eq!(out.responses[0][0], 80.0);
    assert_eq!(out.total_misses(), 0);
}

#[test]
fn a_rate_monotonic_set_under_the_liu_and_layland_bound_never_misses() {
    // U = 10/40 + 15/60 + 20/100 = 0.7 < 3 (2^(1/3) - 1) = 0.7798, one core,
    // priorities from the periods alone (dt 10 ms: 4, 6 and 10 ticks).
    let set = [
        Periodic {
            c_ms: 20,
            t_ms: 100,
        },
        Periodic { c_ms: 10, t_ms: 40 },
        Periodic { c_ms: 15, t_ms: 60 },
    ];
    let u: f64 = set.iter().map(|p| p.c_ms as f64 / p.t_ms as f64).sum();
    assert!(u < 3.0 * (2f64.powf(1.0 / 3.0) - 1.0));
    let tasks = [task("a", 10), task("b", 4), task("c", 6)];
    assert_eq!(fifo_levels(&tasks), vec![97, 99, 98]);
    let model = Cores::new(&cpus(1, Scheduler::Fifo), &tasks).unwrap();
    // Two hyperperiods (600 ms each).
    let out = run(model, &set, 1200);
    assert_eq!(out.total_misses(), 0, "{out:?}");
    assert_eq!(out.responses[1].len(), 30);
    // The lowest's worst response, by hand (the critical instant at 0):
    // R = 20 + ceil(R/40) 10 + ceil(R/60) 15: 20 -> 45 -> 55 -> 55.
    let worst = out.responses[0].iter().cloned().fold(0.0, f64::max);
    assert_eq!(worst, 55.0);
}

#[test]
fn rate_monotonic_robots_of_equal_periods_take_a_level_each_in_name_order() {
    // The kernel runs equal SCHED_FIFO levels by arrival; distinct levels
    // make it run them in the model's order (period, then name).
    let tasks = [task("g2", 1), task("g0", 1), task("g1", 1), task("slow", 2)];
    assert_eq!(fifo_levels(&tasks), vec![97, 99, 98, 96]);
    let mut fixed = task("fixed", 1);
    fixed.priority = Some(Priority::Level(50));
    assert_eq!(fifo_levels(&[fixed, task("a", 1)]), vec![50, 99]);
}

#[test]
fn a_set_above_the_cores_capacity_misses_under_every_scheduler() {
    // Three tasks of 80 ms every 100 ms on two cores: U = 2.4 > 2.
    let set = [Periodic {
        c_ms: 80,
        t_ms: 100,
    }; 3];
    for scheduler in [Scheduler::Fair, Scheduler::Fifo, Scheduler::Deadline] {
        let tasks: Vec<Task> = ["a", "b", "c"]
            .iter()
            .map(|n| Task {
                reservation: Some(Reservation {
                    runtime_ms: 80.0,
                    period_ms: 100.0,
                }),
                ..task(n, 1)
            })
            .collect();
        let model = Cores::new(&cpus(2, scheduler), &tasks).unwrap();
        let out = run(model, &set, 1000);
        assert!(out.total_misses() > 0, "{scheduler:?}: {out:?}");
    }
}

#[test]
fn global_edf_misses_at_a_utilisation_close_to_one_on_two_cores_dhalls_effect() {
    // Two light tasks (2 ms every 100 ms) and one heavy (100 ms every 101
    // ms): U = 0.02 + 0.02 + 0.990 = 1.03, half of the two cores. EDF runs
    // the light ones first (deadline 100 < 101) on both cores, and the
    // heavy one, starting at 2 ms, ends at 102 > 101.
    let res = |c: f64, t: f64| {
        Some(Reservation {
            runtime_ms: c,
            period_ms: t,
        })
    };
    let tasks = [
        Task {
            reservation: res(2.0, 100.0),
            ..task("l1", 1)
        },
        Task {
            reservation: res(2.0, 100.0),
            ..task("l2", 1)
        },
        Task {
            reservation: res(100.0, 101.0),
            ..task("h", 1)
        },
    ];
    let set = [
        Periodic { c_ms: 2, t_ms: 100 },
        Periodic { c_ms: 2, t_ms: 100 },
        Periodic {
            c_ms: 100,
            t_ms: 101,
        },
    ];
    let u: f64 = set.iter().map(|p| p.c_ms as f64 / p.t_ms as f64).sum();
    assert!(u < 1.05, "{u}");
    let model = Cores::new(&cpus(2, Scheduler::Deadline), &tasks).unwrap();
    let out = run(model, &set, 150);
    assert_eq!(out.responses[2].first(), Some(&102.0), "{out:?}");
    assert!(out.misses[2] > 0);
    assert_eq!(out.misses[0] + out.misses[1], 0);
}

/// Four robots of 42 ms every 100 ms and one whose every call wants 1 s,
/// on two cores.
fn hog_and_four() -> (Vec<Task>, Vec<Periodic>) {
    let res = |c: f64| {
        Some(Reservation {
            runtime_ms: c,
            period_ms: 100.0,
        })
    };
    let mut tasks: Vec<Task> = ["r1", "r2", "r3", "r4"]
        .iter()
        .map(|n| Task {
            reservation: res(45.0),
            ..task(n, 1)
        })
        .collect();
    tasks.insert(
        0,
        Task {
            reservation: res(15.0),
            ..task("hog", 1)
        },
    );
    let mut set = vec![
        Periodic {
            c_ms: 42,
            t_ms: 100
        };
        5
    ];
    set[0] = Periodic {
        c_ms: 1000,
        t_ms: 100,
    };
    (tasks, set)
}

#[test]
fn a_reservation_throttles_an_overrunning_robot_and_the_others_keep_every_deadline() {
    let (tasks, set) = hog_and_four();
    let model = Cores::new(&cpus(2, Scheduler::Deadline), &tasks).unwrap();
    let out = run(model.clone(), &set, 2000);
    assert_eq!(out.misses[1..].iter().sum::<u32>(), 0, "{out:?}");
    assert!(out.misses[0] > 0);
    // The hog gets its runtime per period and no more: 15 ms in each of
    // the 20 periods, so its 1 s job is not done within 2 s.
    assert!(out.responses[0].is_empty(), "{out:?}");
    let mut m = model;
    m.release(0, 1000 * MS, 0);
    let mut ended = None;
    m.run_until(20_000 * MS, |d| {
        ended = Some(d.at_ns);
        None
    });
    // 1000 ms at 15 ms per 100 ms: 66 full periods and 10 ms into the 67th.
    assert_eq!(ended, Some(6_600 * MS + 10 * MS));
    // Under fair the same five share the cores: 42 ms at 2/5 of a core
    // takes 105 ms, and every one of the four misses.
    let fair = Cores::new(&cpus(2, Scheduler::Fair), &tasks).unwrap();
    let out = run(fair, &set, 2000);
    assert!(out.misses[1..].iter().all(|&k| k > 0), "{out:?}");
}

#[test]
fn fair_sharing_gives_each_of_n_jobs_m_over_n_of_a_core() {
    let tasks: Vec<Task> = ["a", "b", "c"].iter().map(|n| task(n, 1)).collect();
    let mut m = Cores::new(&cpus(2, Scheduler::Fair), &tasks).unwrap();
    for i in 0..3 {
        m.release(i, 20 * MS, 0);
    }
    let mut ends = Vec::new();
    m.run_until(1000 * MS, |d| {
        ends.push(d.at_ns);
        None
    });
    // Three jobs of 20 ms on two cores: each at 2/3, all end at 30 ms.
    assert_eq!(ends, vec![30 * MS; 3]);
    // Fewer jobs than cores: each has a core.
    m.release(0, 20 * MS, 1);
    let mut ends = Vec::new();
    m.run_until(2000 * MS, |d| {
        ends.push(d.at_ns);
        None
    });
    assert_eq!(ends, vec![1020 * MS]);
}

#[test]
fn the_worlds_own_cpu_takes_a_core_at_each_tick_start_above_every_agent() {
    let c = Cpus {
        count: 1,
        scheduler: Scheduler::Fifo,
        world_ms: 30.0,
    };
    let mut m = Cores::new(&c, &[task("a", 1)]).unwrap();
    m.world_tick();
    m.release(0, 50 * MS, 0);
    let mut ends = Vec::new();
    m.run_until(200 * MS, |d| {
        ends.push(d.at_ns);
        None
    });
    assert_eq!(ends, vec![80 * MS]);
    // Two cores: the agent has the other one.
    let mut m = Cores::new(&Cpus { count: 2, ..c }, &[task("a", 1)]).unwrap();
    m.world_tick();
    m.release(0, 50 * MS, 0);
    let mut ends = Vec::new();
    m.run_until(200 * MS, |d| {
        ends.push(d.at_ns);
        None
    });
    assert_eq!(ends, vec![50 * MS]);
}

#[test]
fn a_job_released_at_a_completion_goes_on_without_a_wake_up() {
    let tasks = [task("a", 1)];
    let mut m = Cores::new(&cpus(1, Scheduler::Fifo), &tasks).unwrap();
    m.release(0, 10 * MS, 0);
    let mut ends = Vec::new();
    m.run_until(100 * MS, |d| {
        ends.push((d.tag, d.at_ns));
        (d.tag == 0).then_some((5 * MS, 1))
    });
    assert_eq!(ends, vec![(0, 10 * MS), (1, 15 * MS)]);
}

#[test]
fn deadline_without_a_reservation_is_refused() {
    let e = Cores::new(&cpus(2, Scheduler::Deadline), &[task("r9", 1)]).unwrap_err();
    assert_eq!(e, CoresError::NoReservation("r9".into()));
}

/// Three robots with `timing` under `cpus`.
fn scene(cpus: &str, timing: &str) -> crate::Scenario {
    let src = format!(
        "[world]\ndt = 0.1\n\n[world.cpus]\n{cpus}\n\n[defaults.timing]\n{timing}\n\n\
         [[robot]]\nname = \"a\"\nstart = [0, 0]\ngoal = [5, 0]\n\n\
         [[robot]]\nname = \"b\"\nstart = [0, 2]\ngoal = [5, 2]\n\n\
         [[robot]]\nname = \"c\"\nstart = [0, 4]\ngoal = [5, 4]\n"
    );
    crate::parse(&src, "t.toml").unwrap().scenario
}

#[test]
fn with_a_core_per_robot_the_model_reads_and_sends_as_each_clerk_alone() {
    let s = scene(
        "count = 3",
        "compute = { model = \"uniform\", min_ms = 20, max_ms = 260, cpu = true }\nsnapshot_loss = 0.1",
    );
    let mut model = Contention::of(&s).unwrap().unwrap();
    let mut clerks: Vec<crate::timing::Clerk> = (0..3)
        .map(|i| {
            crate::timing::Clerk::new(
                s.robots[i].timing.clone().unwrap(),
                s.world.seed,
                i as u64,
                0.1,
            )
        })
        .collect();
    let mut expected = Vec::new();
    let mut got = Vec::new();
    let mut reads = 0;
    for k in 0..300u64 {
        model.tick(k, |_| 0);
        got.extend(model.sends().iter().map(|c| (c.robot, c.tick, c.sent_ns)));
        for (i, clerk) in clerks.iter_mut().enumerate() {
            let plan = matches!(clerk.turn(k), crate::timing::Turn::Plan { .. });
            assert_eq!(model.reads(i), plan, "robot {i} tick {k}");
            if let crate::timing::Turn::Plan { start_ns } = clerk.turn(k) {
                reads += 1;
                expected.push((i, k, clerk.planned(k, start_ns, 0).sent_ns));
            }
        }
    }
    assert!(reads > 300, "{reads}");
    // The same calls; the model lists them as they end.
    got.sort_by_key(|&(i, k, _)| (i, k));
    expected.sort_by_key(|&(i, k, _)| (i, k));
    // Only each robot's last call may still run at the end.
    let ended: Vec<_> = expected
        .iter()
        .copied()
        .filter(|&(i, k, _)| got.iter().any(|&(j, t, _)| (j, t) == (i, k)))
        .collect();
    assert_eq!(got, ended);
    assert!(expected.len() - got.len() <= 3);
}

#[test]
fn three_robots_on_one_core_share_it_and_read_less_often_than_each_alone() {
    let s = scene(
        "count = 1\nscheduler = \"fair\"",
        "compute = { ms = 60, cpu = true }",
    );
    let mut model = Contention::of(&s).unwrap().unwrap();
    let mut sends = Vec::new();
    for k in 0..4u64 {
        model.tick(k, |_| 0);
        sends.extend(
            model
                .sends()
                .iter()
                .map(|c| (c.robot, c.tick, c.sent_ns / MS)),
        );
    }
    // Three jobs of 60 ms on one core: each at 1/3, all end at 180 ms, 80
    // ms into tick 1: each reads tick 1 then, and the three end at 360 ms,
    // 260 ms after tick 1's publication.
    assert_eq!(
        sends,
        vec![
            (0, 0, 180),
            (1, 0, 180),
            (2, 0, 180),
            (0, 1, 260),
            (1, 1, 260),
            (2, 1, 260)
        ]
    );
}

#[test]
fn a_scenario_without_cpus_or_without_cpu_robots_has_no_contention() {
    let s = scene("count = 2", "compute = { ms = 60 }");
    assert!(Contention::of(&s).unwrap().is_none());
    let mut s = scene("count = 2", "compute = { ms = 60, cpu = true }");
    assert!(Contention::of(&s).unwrap().is_some());
    s.world.cpus = None;
    assert!(Contention::of(&s).unwrap().is_none());
}

/// The scan over every task that the ready queue of [`Cores::run_until`]
/// replaced (fifo and deadline, jobs of some demand): each event picks the
/// `c` runnable jobs of smallest key from all the tasks, and every task is
/// looked at for its replenishment and its end. Kept to hold the two
/// together.
fn run_until_scan(
    model: &mut Cores,
    until_ns: u64,
    mut done: impl FnMut(Done) -> Option<(u64, u64)>,
) {
    loop {
        let c = model.agent_cores();
        let mut candidates: Vec<usize> = (0..model.slots.len())
            .filter(|&i| {
                let s = &model.slots[i];
                s.job.is_some() && s.server.is_none_or(|v| !v.throttled)
            })
            .collect();
        candidates.sort_by_key(|&i| model.key(i));
        candidates.truncate(c);
        let running = candidates;
        let mut step = until_ns.saturating_sub(model.now);
        if model.world_left > 0 {
            step = step.min(model.world_left);
        }
        for &i in &running {
            let s = &model.slots[i];
            if let Some(job) = s.job {
                step = step.min(job.left);
            }
            if let Some(v) = s.server {
                step = step.min(v.budget);
            }
        }
        for s in &model.slots {
            if let Some(v) = s.server
                && v.throttled
            {
                step = step.min(v.deadline.saturating_sub(model.now));
            }
        }
        model.world_left -= step.min(model.world_left);
        for &i in &running {
            let s = &mut model.slots[i];
            if let Some(job) = s.job.as_mut() {
                job.left -= step.min(job.left);
            }
            if let Some(v) = s.server.as_mut() {
                v.budget -= step.min(v.budget);
            }
        }
        model.now += step;
        let now = model.now;
        for s in &mut model.slots {
            if let Some(v) = s.server.as_mut()
                && v.throttled
                && v.deadline <= now
            {
                v.throttled = false;
                v.deadline += v.period;
                v.budget = v.runtime;
            }
        }
        for &i in &running {
            if let Some(v) = model.slots[i].server.as_mut()
                && v.budget == 0
            {
                v.throttled = true;
            }
        }
        for i in 0..model.slots.len() {
            let Some(job) = model.slots[i].job else {
                continue;
            };
            if job.left == 0 {
                model.slots[i].job = None;
                if let Some((demand, tag)) = done(Done {
                    task: i,
                    tag: job.tag,
                    at_ns: now,
                }) {
                    model.arrive(i, demand, tag, false);
                }
            }
        }
        if now >= until_ns
            && !model
                .slots
                .iter()
                .any(|s| s.job.is_some_and(|j| j.left == 0))
        {
            return;
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    #[test]
    fn the_ready_queue_decides_every_end_as_the_scan_over_every_task(
        deadline in proptest::bool::ANY,
        count in 1u32..4,
        world_ms in 0u32..3,
        tasks in proptest::collection::vec((1u64..40, 1u64..5, 1u8..99, 1u64..30), 1..12),
        chain in proptest::bool::ANY,
    ) {
        let scheduler = if deadline { Scheduler::Deadline } else { Scheduler::Fifo };
        let set: Vec<Task> = tasks
            .iter()
            .enumerate()
            .map(|(i, &(_, period, level, runtime))| Task {
                name: format!("r{}", i % 5),
                period_ticks: period as u32,
                priority: (level % 3 != 0).then_some(Priority::Level(level)),
                reservation: Some(Reservation {
                    runtime_ms: runtime as f64,
                    period_ms: (period * 10) as f64,
                }),
            })
            .collect();
        let c = Cpus { count, scheduler, world_ms: f64::from(world_ms) };
        let mut fast = Cores::new(&c, &set).expect("model");
        let mut slow = fast.clone();
        let mut ends = (Vec::new(), Vec::new());
        for tick in 0..60u64 {
            for (i, &(demand_ms, period, _, _)) in tasks.iter().enumerate() {
                if tick % period == 0 && !fast.busy(i) {
                    fast.release(i, demand_ms * MS / 4, tick);
                    slow.release(i, demand_ms * MS / 4, tick);
                }
            }
            fast.world_tick();
            slow.world_tick();
            let until = (tick + 1) * 10 * MS;
            let again = |d: Done| (chain && d.task.is_multiple_of(2) && d.tag.is_multiple_of(3))
                .then_some((2 * MS, d.tag + 1000));
            fast.run_until(until, |d| { ends.0.push(d); again(d) });
            run_until_scan(&mut slow, until, |d| { ends.1.push(d); again(d) });
            proptest::prop_assert_eq!(&ends.0, &ends.1, "tick {}", tick);
        }
    }
}

#[test]
fn under_fifo_a_core_kept_busy_is_throttled_for_the_last_50_ms_of_every_second() {
    // One job of 2 s of CPU on one core: 0.95 s of it in each of the first
    // two windows, the last 0.1 s in the third: it ends at 2.1 s. Under
    // deadline (a reservation of the whole core) and fair it ends at 2 s.
    let end = |scheduler: Scheduler| {
        let mut t = task("a", 1);
        t.reservation = Some(Reservation {
            runtime_ms: 3000.0,
            period_ms: 3000.0,
        });
        let mut model = Cores::new(&cpus(1, scheduler), &[t]).unwrap();
        model.release(0, 2000 * MS, 0);
        let mut at = None;
        model.run_until(5000 * MS, |d| {
            at = Some(d.at_ns);
            None
        });
        at.expect("ended")
    };
    assert_eq!(end(Scheduler::Fifo), 2100 * MS);
    assert_eq!(end(Scheduler::Deadline), 2000 * MS);
    assert_eq!(end(Scheduler::Fair), 2000 * MS);
}

#[test]
fn under_fifo_idle_cores_step_over_the_throttling_windows_to_the_next_job() {
    // Idle from 0 to 100 s (no job): the model steps straight to the job
    // released at 100.5 s, which finds the window's whole bandwidth: its
    // 0.9 s of CPU ends at 101.4 s, inside the window of 100-101 s plus
    // 0.4 s of the next (0.5 s of window left, less than 0.95 s used).
    let mut model = Cores::new(&cpus(1, Scheduler::Fifo), &[task("a", 1)]).unwrap();
    model.run_until(100_500 * MS, |_| None);
    model.release(0, 900 * MS, 0);
    let mut at = None;
    model.run_until(200_000 * MS, |d| {
        at = Some(d.at_ns);
        None
    });
    assert_eq!(at, Some(101_400 * MS));
    // And a drain to the end of time returns (an idle model has no events).
    model.run_until(u64::MAX / 4, |_| None);
}
