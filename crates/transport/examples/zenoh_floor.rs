//! The floor of a bare Zenoh round trip on this machine, for comparison
//! with `mrsim bench --transport zenoh` (BENCHMARKS.md, "Zenoh").
//!
//! `cargo run --release -p mrsim-transport --example zenoh_floor [N]`
//! starts itself again as an echo process (a client session, as an agent
//! is), then sends N pings (default 2000) of 64 bytes (a command's size)
//! from a peer session that listens on loopback (as the world does) and
//! times each until its pong is back, on this process's clock. The echo
//! answers from Zenoh's callback (no hand-over to another thread), so this
//! is what Zenoh itself costs per round trip, with the settings the
//! transport uses (express, real-time priority, blocking congestion
//! control; with `MRSIM_FLOOR_LOW_LATENCY=1`, Zenoh's low-latency
//! transport on both sides).

use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::qos::{CongestionControl, Priority};

fn config(mode: &str, endpoint: &str) -> zenoh::Config {
    let mut c = zenoh::Config::default();
    let key = if mode == "peer" {
        "listen/endpoints"
    } else {
        "connect/endpoints"
    };
    let set = [
        ("mode", format!("\"{mode}\"")),
        ("scouting/multicast/enabled", "false".to_string()),
        (key, format!("[\"{endpoint}\"]")),
    ];
    // MRSIM_FLOOR_LOW_LATENCY=1: Zenoh's low-latency transport, as the
    // transport uses when every message fits a batch.
    let low_latency = std::env::var_os("MRSIM_FLOOR_LOW_LATENCY").is_some_and(|v| v == "1");
    let ll = [
        ("transport/unicast/qos/enabled", "false".to_string()),
        ("transport/unicast/lowlatency", "true".to_string()),
    ];
    let extra = if low_latency { &ll[..] } else { &[][..] };
    for (k, v) in set.iter().chain(extra).cloned() {
        if let Err(e) = c.insert_json5(k, &v) {
            eprintln!("zenoh_floor: config {k}: {e}");
            std::process::exit(2);
        }
    }
    c
}

fn echo(endpoint: &str) -> zenoh::Result<()> {
    let s = zenoh::open(config("client", endpoint)).wait()?;
    let pong = s
        .declare_publisher("mrsim-floor/pong")
        .express(true)
        .priority(Priority::RealTime)
        .congestion_control(CongestionControl::Block)
        .wait()?;
    let _sub = s
        .declare_subscriber("mrsim-floor/ping")
        .callback(move |sample| {
            let _ = pong.put(sample.payload().clone()).wait();
        })
        .wait()?;
    // Until the pinging process ends (it kills this one).
    loop {
        std::thread::sleep(Duration::from_secs(1));
    }
}

fn main() -> zenoh::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("echo") {
        let endpoint = args.get(2).cloned().unwrap_or_default();
        return echo(&endpoint);
    }
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(2000);
    let port = std::net::TcpListener::bind("127.0.0.1:0")?
        .local_addr()?
        .port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let s = zenoh::open(config("peer", &endpoint)).wait()?;
    let got = Arc::new((Mutex::new(0u64), Condvar::new()));
    let g = got.clone();
    let _sub = s
        .declare_subscriber("mrsim-floor/pong")
        .callback(move |_| {
            let (m, cv) = &*g;
            *m.lock().unwrap_or_else(|p| p.into_inner()) += 1;
            cv.notify_one();
        })
        .wait()?;
    let ping = s
        .declare_publisher("mrsim-floor/ping")
        .express(true)
        .priority(Priority::RealTime)
        .congestion_control(CongestionControl::Block)
        .wait()?;
    let mut child = std::process::Command::new(std::env::current_exe()?)
        .args(["echo", &endpoint])
        .spawn()?;
    let (m, cv) = &*got;
    let wait_for = |count: u64, limit: Duration| -> bool {
        let start = Instant::now();
        let mut g = m.lock().unwrap_or_else(|p| p.into_inner());
        while *g < count {
            let left = limit.saturating_sub(start.elapsed());
            if left.is_zero() {
                return false;
            }
            g = cv
                .wait_timeout(g, left)
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
        true
    };
    // Until the echo is connected and subscribed.
    let mut warm = 0;
    loop {
        ping.put(vec![0u8; 64]).wait()?;
        warm += 1;
        if wait_for(1, Duration::from_millis(200)) {
            break;
        }
        if warm > 100 {
            let _ = child.kill();
            eprintln!("zenoh_floor: the echo process never answered");
            std::process::exit(1);
        }
    }
    // Late pongs of the warm-up pings, then a clean count.
    std::thread::sleep(Duration::from_millis(300));
    let base = *m.lock().unwrap_or_else(|p| p.into_inner());
    let mut rtt = Vec::with_capacity(n);
    for i in 0..n as u64 {
        let t = Instant::now();
        ping.put(vec![0u8; 64]).wait()?;
        if !wait_for(base + i + 1, Duration::from_secs(2)) {
            eprintln!("zenoh_floor: pong {i} lost");
            break;
        }
        rtt.push(t.elapsed().as_secs_f64() * 1e6);
    }
    let _ = child.kill();
    let _ = child.wait();
    rtt.sort_by(f64::total_cmp);
    let q = |p: f64| {
        rtt.get(((rtt.len() as f64 - 1.0) * p) as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    println!(
        "zenoh round trip, peer <-> client on loopback, 64 B, {} samples: p50 {:.0} us, p99 {:.0} us, max {:.0} us",
        rtt.len(),
        q(0.5),
        q(0.99),
        q(1.0)
    );
    Ok(())
}
