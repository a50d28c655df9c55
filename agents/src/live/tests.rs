//! `Live` over an in-process world side: one robot and a group.
use super::*;
use mrsim_proto::{JoinReply, PROTOCOL_VERSION, command_kind};
use mrsim_transport::WorldTransport;
use mrsim_transport::inproc::{InprocAgent, InprocWorld};
use std::sync::atomic::AtomicBool;

/// A world side with one robot `a` (planner `external`) and its
/// agent's side, the setup published.
fn world() -> (InprocWorld, InprocAgent) {
    world_of(&["a"])
}

/// A world side with robots `names` (planner `external`, side by side) and
/// one agent's side for all of them, the setup published.
fn world_of(names: &[&str]) -> (InprocWorld, InprocAgent) {
    let robots: String = names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let y = 5.0 + 2.0 * i as f64;
            format!(
                "[[robot]]\nname = \"{name}\"\nstart = [1.0, {y}]\ngoal = [9.0, {y}]\n\
                 planner = \"external\"\nparams = {{ gain = 2.0 }}\n"
            )
        })
        .collect();
    let text = format!(
        "name = \"live\"\n[world]\narena = {{ min = [0.0, 0.0], max = [10.0, 10.0] }}\n{robots}"
    );
    let scenario = mrsim_scenario::parse(&text, "live.toml")
        .expect("scenario")
        .scenario;
    let (mut world, mut sides) =
        mrsim_transport::inproc::channels(1, Arc::new(AtomicBool::new(false)));
    let setup = serde_json::json!({"run_id": "live", "out_dir": null, "scenario": scenario});
    world
        .publish_setup(setup.to_string().as_bytes())
        .expect("setup");
    let side = sides.pop().expect("one side");
    (world, side)
}

/// Answers the first join request with token 7.
fn admit(world: &mut InprocWorld) {
    admit_all(world, &["a"]);
}

/// Answers one join request for each robot of `names`: robot id its index
/// there, token 7 plus the id.
fn admit_all(world: &mut InprocWorld, names: &[&str]) {
    let mut asked = Vec::new();
    while asked.len() < names.len() {
        world.wait(Duration::from_millis(10)).expect("wait");
        world.drain_joins(&mut |r| asked.push(r)).expect("joins");
    }
    for r in asked {
        let id = names
            .iter()
            .position(|n| *n == r.robot.as_str())
            .expect("a robot of the run");
        world
            .reply_join(&JoinReply {
                nonce: r.nonce,
                accepted: 1,
                robot_id: id as u32,
                token: 7 + id as u64,
                protocol_version: PROTOCOL_VERSION,
                world_pid: std::process::id(),
                reason: Default::default(),
            })
            .expect("reply");
    }
}

fn commands(world: &mut InprocWorld) -> Vec<mrsim_proto::CommandMsg> {
    let mut got = Vec::new();
    world
        .drain_commands(&mut |c, _| got.push(c))
        .expect("drain");
    got
}

#[test]
fn a_live_robot_gets_each_tick_owned_and_answers_it_once_with_its_token() {
    let (mut world, mut side) = world();
    let agent = std::thread::spawn(move || {
        let mut live = Live::join(&mut side, &AgentOptions::new("a"))
            .expect("join")
            .expect("not interrupted");
        assert_eq!(live.robot(), "a");
        assert!(live.params().contains_key("gain"));
        let mut seen = Vec::new();
        loop {
            match live.next(&mut side, Duration::from_secs(5)).expect("next") {
                Next::Observation(obs) => {
                    let view = obs.view();
                    assert_eq!((view.goal.x, view.goal.y), (9.0, 5.0));
                    assert_eq!(view.walls.len(), 4, "the arena's walls");
                    seen.push(obs.tick);
                    live.reply(&mut side, Command::Velocity(Vec2::new(1.0, 0.0)))
                        .expect("reply");
                    assert!(matches!(
                        live.reply(&mut side, Command::Velocity(Vec2::zeros())),
                        Err(AgentError::NothingToAnswer)
                    ));
                }
                Next::Idle => {}
                Next::Finished => break,
                other => panic!("{other:?}"),
            }
        }
        live.finish(AgentExit::Finished).expect("finish");
        seen
    });
    admit(&mut world);
    world.joins_answered().expect("answered");
    // The ready command, then one answer per tick.
    let mut ready = Vec::new();
    while ready.is_empty() {
        world.wait(Duration::from_millis(10)).expect("wait");
        ready = commands(&mut world);
    }
    assert_eq!(ready[0].kind, command_kind::READY);
    let bodies = [BodyState {
        position: [1.0, 5.0],
        ..Default::default()
    }];
    for tick in 0..3 {
        let header = SnapshotHeader {
            tick,
            ..Default::default()
        };
        world.publish_snapshot(&header, &bodies).expect("snapshot");
        let mut got = Vec::new();
        while got
            .iter()
            .all(|c: &mrsim_proto::CommandMsg| c.tick != tick || c.kind == command_kind::READY)
        {
            world.wait(Duration::from_millis(10)).expect("wait");
            got.extend(commands(&mut world));
        }
        let answer = got
            .iter()
            .find(|c| c.kind == command_kind::VELOCITY)
            .expect("answer");
        assert_eq!(
            (answer.tick, answer.token, answer.value),
            (tick, 7, [1.0, 0.0])
        );
    }
    let end = SnapshotHeader {
        finished: 1,
        ..Default::default()
    };
    world.publish_snapshot(&end, &[]).expect("the end");
    assert_eq!(agent.join().expect("agent thread"), [0, 1, 2]);
}

#[test]
fn a_live_group_hands_out_each_robots_tick_in_turn_and_answers_each_with_its_own_token() {
    let (mut world, mut side) = world_of(&["a", "b"]);
    let agent = std::thread::spawn(move || {
        let opts = [AgentOptions::new("a"), AgentOptions::new("b")];
        let seats = crate::join::join_seats(&mut side, &opts)
            .expect("join")
            .expect("not interrupted");
        let mut live = Live::start(&mut side, seats, Duration::from_millis(300)).expect("start");
        let mut seen = Vec::new();
        loop {
            match live.next(&mut side, Duration::from_secs(5)).expect("next") {
                Next::Observation(obs) => {
                    seen.push((obs.tick, obs.me.id));
                    let cmd = Command::Velocity(Vec2::new(f64::from(obs.me.id) + 1.0, 0.0));
                    live.reply(&mut side, cmd).expect("reply");
                }
                Next::Idle => {}
                Next::Finished => break,
                other => panic!("{other:?}"),
            }
        }
        live.finish(AgentExit::Finished).expect("finish");
        seen
    });
    admit_all(&mut world, &["a", "b"]);
    world.joins_answered().expect("answered");
    let mut ready = Vec::new();
    while ready.len() < 2 {
        world.wait(Duration::from_millis(10)).expect("wait");
        ready.extend(commands(&mut world));
    }
    assert!(ready.iter().all(|c| c.kind == command_kind::READY));
    let bodies = [5.0, 7.0].map(|y| BodyState {
        position: [1.0, y],
        ..Default::default()
    });
    for tick in 0..2 {
        let header = SnapshotHeader {
            tick,
            ..Default::default()
        };
        world.publish_snapshot(&header, &bodies).expect("snapshot");
        let mut answers = Vec::new();
        while answers.len() < 2 {
            world.wait(Duration::from_millis(10)).expect("wait");
            answers.extend(
                commands(&mut world)
                    .into_iter()
                    .filter(|c| c.kind == command_kind::VELOCITY),
            );
        }
        answers.sort_by_key(|c| c.robot_id);
        let got: Vec<_> = answers
            .iter()
            .map(|c| (c.tick, c.robot_id, c.token, c.value))
            .collect();
        assert_eq!(got, [(tick, 0, 7, [1.0, 0.0]), (tick, 1, 8, [2.0, 0.0])]);
    }
    let end = SnapshotHeader {
        finished: 1,
        ..Default::default()
    };
    world.publish_snapshot(&end, &[]).expect("the end");
    assert_eq!(
        agent.join().expect("agent thread"),
        [(0, 0), (0, 1), (1, 0), (1, 1)]
    );
}
