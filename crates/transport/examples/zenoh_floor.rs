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
//! control, Zenoh's runtime threads as mrsim sets them for the world and
//! for an agent unless `ZENOH_RUNTIME` is set; with `MRSIM_FLOOR_LOW_LATENCY=1`, Zenoh's
//! low-latency transport on both sides).
//!
//! `MRSIM_FLOOR_HANDOVER=1` makes the echo answer from a thread of its
//! own that the callback wakes, as an agent's loop is woken (one
//! hand-over and its context switches more per round trip). It also
//! prints the CPU time both processes spent per round trip, a figure that
//! holds on a busy machine where the round trip's time does not.

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

/// Whether environment variable `name` is `1`.
fn flag(name: &str) -> bool {
    std::env::var_os(name).is_some_and(|v| v == "1")
}

fn echo(endpoint: &str) -> zenoh::Result<()> {
    let s = zenoh::open(config("client", endpoint)).wait()?;
    let pong = s
        .declare_publisher("mrsim-floor/pong")
        .express(true)
        .priority(Priority::RealTime)
        .congestion_control(CongestionControl::Block)
        .wait()?;
    if flag("MRSIM_FLOOR_HANDOVER") {
        // The callback keeps the newest ping and wakes this thread, which
        // answers (an agent's loop, less its planning).
        let inbox = Arc::new((Mutex::new(None::<zenoh::bytes::ZBytes>), Condvar::new()));
        let i = inbox.clone();
        let _sub = s
            .declare_subscriber("mrsim-floor/ping")
            .callback(move |sample| {
                let (m, cv) = &*i;
                *m.lock().unwrap_or_else(|p| p.into_inner()) = Some(sample.payload().clone());
                cv.notify_one();
            })
            .wait()?;
        let (m, cv) = &*inbox;
        loop {
            let mut g = m.lock().unwrap_or_else(|p| p.into_inner());
            while g.is_none() {
                g = cv.wait(g).unwrap_or_else(|p| p.into_inner());
            }
            let ping = g.take();
            drop(g);
            if let Some(p) = ping {
                let _ = pong.put(p).wait();
            }
        }
    }
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

/// CPU seconds (user and system) of this process (`who`: `RUSAGE_SELF`).
fn cpu_s(who: libc::c_int) -> f64 {
    // SAFETY: getrusage writes only the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(who, &mut u) } != 0 {
        return f64::NAN;
    }
    let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
    t(u.ru_utime) + t(u.ru_stime)
}

fn main() -> zenoh::Result<()> {
    use mrsim_transport::zenoh::RUNTIME_ENV;
    // Zenoh's runtime threads as mrsim sets them: an agent's in the echo,
    // the world's here (the echo inherits only a ZENOH_RUNTIME of the user).
    let args: Vec<String> = std::env::args().collect();
    let is_echo = args.get(1).map(String::as_str) == Some("echo");
    let users_runtime = std::env::var_os(RUNTIME_ENV).is_some();
    // SAFETY: first thing in main, before any thread exists.
    unsafe {
        if is_echo {
            mrsim_transport::zenoh::default_runtime();
        } else {
            mrsim_transport::zenoh::world_runtime();
        }
    }
    if is_echo {
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
    let mut echo_cmd = std::process::Command::new(std::env::current_exe()?);
    echo_cmd.args(["echo", &endpoint]);
    if !users_runtime {
        echo_cmd.env_remove(RUNTIME_ENV);
    }
    let mut child = echo_cmd.spawn()?;
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
    let cpu_before = cpu_s(libc::RUSAGE_SELF);
    let child_cpu_before = child_cpu_s(child.id());
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
    let cpu_ping = cpu_s(libc::RUSAGE_SELF) - cpu_before;
    let cpu_echo = child_cpu_s(child.id()) - child_cpu_before;
    let _ = child.kill();
    let _ = child.wait();
    let per = |s: f64| s / rtt.len().max(1) as f64 * 1e6;
    println!(
        "cpu per round trip: {:.1} us (pinging peer {:.1}, echoing client {:.1})",
        per(cpu_ping + cpu_echo),
        per(cpu_ping),
        per(cpu_echo)
    );
    rtt.sort_by(f64::total_cmp);
    let q = |p: f64| {
        rtt.get(((rtt.len() as f64 - 1.0) * p) as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    println!(
        "zenoh round trip, peer <-> client on loopback{}, 64 B, {} samples: p50 {:.0} us, p99 {:.0} us, max {:.0} us",
        if flag("MRSIM_FLOOR_HANDOVER") {
            ", echoed from a thread the callback wakes"
        } else {
            ""
        },
        rtt.len(),
        q(0.5),
        q(0.99),
        q(1.0)
    );
    Ok(())
}

/// CPU seconds (user and system) of process `pid` so far, from
/// /proc/PID/stat (the echo runs until killed: its rusage would come only
/// after).
fn child_cpu_s(pid: u32) -> f64 {
    let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
        return f64::NAN;
    };
    // Fields after the command name (which may hold spaces), in `)`.
    let Some((_, rest)) = stat.rsplit_once(')') else {
        return f64::NAN;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the line, 11 and 12 here.
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok());
    // SAFETY: sysconf has no preconditions.
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) } as f64;
    match (ticks(11), ticks(12)) {
        (Some(u), Some(s)) if hz > 0.0 => (u + s) / hz,
        _ => f64::NAN,
    }
}
