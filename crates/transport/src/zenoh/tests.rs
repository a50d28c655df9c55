//! The world's side against a raw Zenoh session on loopback: what comes
//! from the network that is not a well-formed message of this run is
//! refused and counted, a flood is bounded, and another run's traffic is
//! never seen.

use super::wire;
use super::{ZenohOptions, ZenohWorld};
use crate::{Capacity, Namespace, WorldTransport};
use mrsim_proto::CommandMsg;
use std::time::{Duration, Instant};
use zenoh::Wait;

fn free_endpoint() -> String {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    format!("tcp/127.0.0.1:{port}")
}

fn world(run: &str, endpoint: &str) -> ZenohWorld {
    let opts = ZenohOptions {
        endpoint: Some(endpoint.to_string()),
        config_file: None,
    };
    ZenohWorld::create(
        &Namespace::new(run).expect("run id"),
        &opts,
        Capacity::grouped(2, 1),
        4,
        1000,
    )
    .expect("world session")
}

fn client(endpoint: &str) -> zenoh::Session {
    let opts = ZenohOptions {
        endpoint: Some(endpoint.to_string()),
        config_file: None,
    };
    super::open(&opts, super::Role::Client).expect("client session")
}

/// Drains until `done` holds for what came so far, or 10 s.
fn drain_until(
    w: &mut ZenohWorld,
    got: &mut Vec<CommandMsg>,
    done: impl Fn(&ZenohWorld, usize) -> bool,
) {
    let start = Instant::now();
    while !done(w, got.len()) && start.elapsed() < Duration::from_secs(10) {
        w.wait(Duration::from_millis(50)).expect("wait");
        w.drain_commands(&mut |c, _| got.push(c)).expect("drain");
    }
}

#[test]
fn garbage_floods_and_other_runs_never_reach_the_world_loop() {
    let ep = free_endpoint();
    let mut w = world("zt-garbage", &ep);
    let c = client(&ep);
    let good = CommandMsg {
        robot_id: 1,
        tick: 3,
        ..Default::default()
    };
    // Another run on the same address, then garbage on this run's keys.
    c.put("mrsim/zt-other/command", wire::encode(&good))
        .wait()
        .expect("put");
    c.put("mrsim/zt-garbage/command", b"garbage".to_vec())
        .wait()
        .expect("put");
    c.put("mrsim/zt-garbage/join", vec![0u8; 3])
        .wait()
        .expect("put");
    c.put("mrsim/zt-garbage/command", wire::encode(&good))
        .wait()
        .expect("put");
    let mut got = Vec::new();
    drain_until(&mut w, &mut got, |w, n| {
        n >= 1 && w.counts().commands_malformed + w.counts().joins_malformed >= 2
    });
    let same = |c: &CommandMsg| (c.robot_id, c.tick) == (good.robot_id, good.tick);
    assert!(
        got.len() == 1 && same(&got[0]),
        "only the well-formed command of this run: {got:?}"
    );
    let counts = w.counts();
    assert_eq!(
        (
            counts.commands_malformed,
            counts.joins_malformed,
            counts.dropped
        ),
        (1, 1, 0)
    );
    let mut joins = 0;
    w.drain_joins(&mut |_| joins += 1).expect("joins");
    assert_eq!(joins, 0);

    // A flood without the world draining: bounded, the rest counted.
    let limit = Capacity::grouped(2, 1).messages() * 8 + 256;
    let sent = limit + 500;
    for _ in 0..sent {
        c.put("mrsim/zt-garbage/command", wire::encode(&good))
            .wait()
            .expect("put");
    }
    let start = Instant::now();
    while (w.counts().dropped as usize) < sent - limit && start.elapsed() < Duration::from_secs(10)
    {
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut n = 0;
    w.drain_commands(&mut |_, _| n += 1).expect("drain");
    assert_eq!(n, limit, "the inbox holds its limit");
    assert_eq!(w.counts().dropped as usize, sent - limit);
}
