//! The tick loop's roles over the in-memory transport and its clock.

use super::admission::{Admission, Agent, Event, TickWindow, Verdict};
use super::fake::{FakeClock, FakeTransport, Responder, join_request, velocity};
use super::*;
use mrsim_proto::FixedStr;
use mrsim_proto::flags;

fn scenario(mode: &str) -> mrsim_scenario::Scenario {
    let src = format!(
        r#"
[world]
dt = 0.1
duration = 5.0
mode = "{mode}"
stall_timeout = 0.5

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [4.0, 0.0]

[[robot]]
name = "r1"
start = [0.0, 3.0]
goal = [4.0, 3.0]
"#
    );
    mrsim_scenario::parse(&src, "inline.toml")
        .expect("valid scenario")
        .scenario
}

/// A loop over the fake transport, its outputs in a fresh folder.
fn with_loop<R>(mode: &str, test: impl FnOnce(&mut Loop<'_>, &FakeTransport) -> R) -> R {
    let scenario = scenario(mode);
    let world = World::new(&scenario).expect("world");
    let dir = std::env::temp_dir().join(format!(
        "mrsim-world-loop-{}-{}",
        std::process::id(),
        now_ns()
    ));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let names = vec!["r0".to_string(), "r1".to_string()];
    let tracker = Tracker::new(&scenario, world.walls());
    let rec = Recorder::start(&dir, names, tracker).expect("recorder");
    let timings = TimingRecorder::start(2).expect("timings");
    let handle = FakeTransport::default();
    let mut link = handle.clone();
    let clock: FakeClock = link.clock();
    let opts = RunOptions {
        out_dir: dir.clone(),
        run_id: "test".into(),
        transport: "fake".into(),
        start_timeout: None,
        verbose: false,
        routes: Default::default(),
        group_room: None,
    };
    let out = {
        let mut lp = Loop::new(world, &mut link, &clock, opts, rec, timings);
        test(&mut lp, &handle)
    };
    let _ = std::fs::remove_dir_all(&dir);
    out
}

/// Joins both robots (as threads of this process, which the liveness
/// check leaves alone) and returns their tokens.
fn join_both(lp: &mut Loop<'_>, fake: &FakeTransport) -> [u64; 2] {
    let own = std::process::id();
    fake.join("r0", own, 1);
    fake.join("r1", own, 2);
    lp.drain().expect("drain");
    [1, 2].map(|nonce| {
        let r = fake.reply(nonce).expect("a reply");
        assert_eq!(r.accepted, 1, "{}", r.reason.as_str());
        r.token
    })
}

/// Robot `robot`'s agent, answering every tick with `token`.
fn answering(robot: u32, token: u64) -> Responder {
    Responder {
        robot,
        token,
        value: [0.5, 0.0],
    }
}

#[test]
fn a_join_is_accepted_with_a_token_and_the_same_process_asking_again_gets_the_same_one() {
    with_loop("lockstep", |lp, fake| {
        let [t0, t1] = join_both(lp, fake);
        assert!(t0 != 0 && t1 != 0 && t0 != t1);
        let own = std::process::id();
        fake.join("r0", own, 3);
        lp.drain().expect("drain");
        assert_eq!(fake.reply(3).map(|r| r.token), Some(t0));
        assert!(matches!(lp.admission.agents()[0], Agent::Live { token, .. } if token == t0));
        assert_eq!(lp.recording.acc[0].agent_pid, Some(own));
    });
}

#[test]
fn a_second_join_for_a_driven_robot_is_refused_with_a_reason() {
    with_loop("lockstep", |lp, fake| {
        let [t0, _] = join_both(lp, fake);
        fake.join("r0", u32::MAX - 7, 9);
        lp.drain().expect("drain");
        let r = fake.reply(9).expect("a reply");
        assert_eq!(r.accepted, 0);
        assert_eq!(r.token, 0);
        assert!(
            r.reason.as_str().contains("already driven by process"),
            "{}",
            r.reason.as_str()
        );
        // The robot keeps its agent.
        assert!(matches!(lp.admission.agents()[0], Agent::Live { token, .. } if token == t0));
    });
}

#[test]
fn joins_for_unknown_robots_or_other_protocols_are_refused_and_say_why() {
    let mut a = Admission::new(vec!["r0".into(), "r1".into()], 42);
    let mut req = join_request("nobody", 7, 1);
    let (reply, events) = a.join(&req, 5, |_| true);
    assert_eq!(reply.accepted, 0);
    assert_eq!(reply.world_pid, 42);
    assert!(reply.reason.as_str().contains("robots: r0, r1"));
    assert!(matches!(&events[..], [Event::JoinRefused { robot, .. }] if robot == "nobody"));
    req.robot = FixedStr::new("r0");
    req.protocol_version += 1;
    let (reply, _) = a.join(&req, 5, |_| true);
    assert_eq!(reply.accepted, 0);
    assert!(reply.reason.as_str().contains("protocol version"));
    assert!(a.any_waiting());
}

#[test]
fn a_process_joining_as_more_robots_than_the_world_holds_is_refused_and_told_why() {
    let names: Vec<String> = (0..12).map(|i| format!("r{i}")).collect();
    let mut a = Admission::new(names, 42).with_room(Some(8));
    let mut req = join_request("r3", 7, 1);
    req.group = 12;
    let (reply, events) = a.join(&req, 5, |_| true);
    assert_eq!(reply.accepted, 0);
    assert!(
        reply.reason.as_str().contains("joins as 12 robots")
            && reply.reason.as_str().contains("commands of 8 robots"),
        "{}",
        reply.reason.as_str()
    );
    assert!(matches!(&events[..], [Event::JoinRefused { robot, .. }] if robot == "r3"));
    // A group that fits is taken.
    req.group = 8;
    let (reply, _) = a.join(&req, 5, |_| true);
    assert_eq!(reply.accepted, 1);
}

#[test]
fn a_new_process_for_a_robot_whose_agent_died_records_the_loss_then_the_rejoin() {
    let mut a = Admission::new(vec!["r0".into()], 42);
    let req = |pid, nonce| join_request("r0", pid, nonce);
    let (first, events) = a.join(&req(10, 1), 5, |_| true);
    assert_eq!(events, [Event::Joined { robot: 0, pid: 10 }]);
    // Process 10 is gone: process 11 takes the robot over.
    let (second, events) = a.join(&req(11, 2), 6, |pid| pid != 10);
    assert_eq!(second.accepted, 1);
    assert_ne!(second.token, first.token);
    assert!(matches!(
        &events[..],
        [
            Event::Lost {
                robot: 0,
                pid: 10,
                ..
            },
            Event::Rejoined {
                robot: 0,
                pid: 11,
                by_command: false
            },
        ]
    ));
}

#[test]
fn a_command_with_the_wrong_token_or_tick_is_rejected_and_counted() {
    with_loop("lockstep", |lp, fake| {
        let [t0, t1] = join_both(lp, fake);
        lp.window = lp.schedule.window(3, 1_000);
        let sent = 2_000;
        fake.send(velocity(0, t0 ^ 2, 3, sent)); // not its token
        fake.send(velocity(1, t1, 4, sent)); // a future tick
        fake.send(velocity(1, t1, 2, sent)); // a past tick
        fake.send(velocity(9, t1, 3, sent)); // no such robot
        fake.send(velocity(0, t0, 3, 500)); // sent before the tick existed
        lp.drain().expect("drain");
        assert_eq!(lp.recording.counts.rejected, 5);
        assert_eq!(lp.recording.counts.rejected_unknown, 1);
        assert_eq!(lp.recording.acc[0].rejected, 2);
        assert_eq!(lp.recording.acc[1].rejected, 2);
        assert!(lp.admission.got.iter().all(Option::is_none));
        // The right one is taken, a second one in the tick is not.
        fake.send(velocity(0, t0, 3, sent));
        fake.send(velocity(0, t0, 3, sent + 1));
        lp.drain().expect("drain");
        assert!(lp.admission.got[0].is_some());
        assert_eq!(lp.recording.acc[0].rejected, 3);
    });
}

#[test]
fn garbage_is_rejected_but_counts_as_an_answer_and_the_robot_brakes() {
    let mut a = Admission::new(vec!["r0".into()], 42);
    let (reply, _) = a.join(&join_request("r0", 10, 1), 5, |_| true);
    let now = TickWindow {
        tick: 0,
        published_ns: 0,
        deadline_ns: u64::MAX,
        realtime: false,
    };
    let mut c = velocity(0, reply.token, 0, 1);
    c.value[1] = f64::NAN;
    assert!(matches!(
        a.command(&c, now),
        Verdict::Rejected { robot: Some(0), .. }
    ));
    assert!(a.garbage[0]);
    assert!(a.all_answered());
    assert!(a.silent().is_empty());
}

#[test]
fn lockstep_waits_for_every_live_agent_and_not_at_all_when_all_have_answered() {
    with_loop("lockstep", |lp, fake| {
        let [t0, t1] = join_both(lp, fake);
        fake.state().responders = vec![answering(0, t0), answering(1, t1)];
        let start = lp.clock.now();
        let mut contacts = Vec::new();
        for _ in 0..3 {
            assert!(!lp.tick(start, false, &mut contacts).expect("tick"));
        }
        assert_eq!(fake.waited(), Duration::ZERO);
        assert_eq!(lp.window.tick, 3);
        assert_eq!(fake.state().snapshots.len(), 3);
        assert!(
            lp.world.states()[0].position[0] > 0.0,
            "the command moved it"
        );
        assert_eq!(lp.recording.costs.allin.percentiles().count, 3);
        assert!(lp.recording.acc.iter().all(|a| a.deadline_misses == 0));
    });
}

#[test]
fn a_stalled_agent_is_lost_after_the_stall_timeout_and_rejoins_when_it_answers_again() {
    with_loop("lockstep", |lp, fake| {
        let [t0, t1] = join_both(lp, fake);
        fake.state().responders = vec![answering(0, t0)];
        let start = lp.clock.now();
        let mut contacts = Vec::new();
        lp.tick(start, false, &mut contacts).expect("tick");
        // It waited for r1 the whole stall timeout, in slices, and no more.
        let waited = fake.waited();
        assert!(waited >= Duration::from_millis(500), "{waited:?}");
        assert!(waited < Duration::from_millis(520), "{waited:?}");
        assert!(matches!(lp.admission.agents()[1], Agent::Lost { .. }));
        assert_eq!(lp.recording.counts.agents_lost, 1);
        assert_eq!(lp.recording.acc[1].lost, 1);
        assert_ne!(lp.world.states()[1].flags & flags::LOST, 0);
        // The next tick does not wait for the lost agent.
        lp.tick(start, false, &mut contacts).expect("tick");
        assert_eq!(fake.waited(), waited);
        // It answers again: live, unflagged, driving.
        fake.state().responders.push(answering(1, t1));
        lp.tick(start, false, &mut contacts).expect("tick");
        assert!(matches!(lp.admission.agents()[1], Agent::Live { .. }));
        assert_eq!(lp.world.states()[1].flags & flags::LOST, 0);
        assert!(lp.admission.got[1].is_some());
    });
}

#[test]
fn realtime_late_commands_are_misses_not_rejections() {
    let mut a = Admission::new(vec!["r0".into()], 42);
    let (reply, _) = a.join(&join_request("r0", 10, 1), 5, |_| true);
    let now = TickWindow {
        tick: 5,
        published_ns: 1_000,
        deadline_ns: 2_000,
        realtime: true,
    };
    let t = reply.token;
    // Sent after the deadline, though taken in at once.
    assert_eq!(
        a.command(&velocity(0, t, 5, 2_001), now),
        Verdict::Late { robot: 0 }
    );
    // An answer to the previous tick.
    assert_eq!(
        a.command(&velocity(0, t, 4, 900), now),
        Verdict::Late { robot: 0 }
    );
    // In lockstep the same is a past tick.
    let lockstep = TickWindow {
        deadline_ns: u64::MAX,
        realtime: false,
        ..now
    };
    assert!(matches!(
        a.command(&velocity(0, t, 4, 900), lockstep),
        Verdict::Rejected { .. }
    ));
    assert_eq!(
        a.command(&velocity(0, t, 5, 1_500), now),
        Verdict::Accepted {
            robot: 0,
            rejoined: None
        }
    );
}

#[test]
fn realtime_counts_a_silent_agent_as_a_miss_at_the_deadline_and_keeps_it() {
    with_loop("realtime", |lp, fake| {
        let [t0, _] = join_both(lp, fake);
        fake.state().responders = vec![answering(0, t0)];
        let start = lp.clock.now();
        let mut contacts = Vec::new();
        lp.tick(start, false, &mut contacts).expect("tick");
        // Waited until the deadline (dt x deadline = 0.1 s), then moved on.
        let waited = fake.waited();
        assert!(waited >= Duration::from_millis(100), "{waited:?}");
        assert!(waited < Duration::from_millis(110), "{waited:?}");
        assert_eq!(lp.recording.acc[1].deadline_misses, 1);
        assert_eq!(lp.recording.acc[0].deadline_misses, 0);
        assert!(matches!(lp.admission.agents()[1], Agent::Live { .. }));
        assert_eq!(lp.recording.counts.agents_lost, 0);
        // Its late answer to tick 0, taken in during tick 1, is late.
        let published = fake.state().snapshots[0].published_ns;
        let late = velocity(1, lp.admission_token(1), 0, published + 1);
        fake.send(late);
        lp.tick(start, false, &mut contacts).expect("tick");
        assert_eq!(lp.recording.counts.late, 1);
        assert_eq!(lp.recording.acc[1].late, 1);
    });
}

impl Loop<'_> {
    fn admission_token(&self, i: usize) -> u64 {
        match self.admission.agents()[i] {
            Agent::Live { token, .. } | Agent::Lost { token, .. } => token,
            Agent::Waiting => 0,
        }
    }
}
