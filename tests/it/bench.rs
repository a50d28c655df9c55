//! `mrsim bench` on a tiny run: the output's shape (fields, one row per
//! combination, csv, plot), never its timing.

use crate::common::*;

/// `mrsim bench --baseline` runs the `mrsim-baseline` program next to
/// `mrsim`. A workspace build has it (its package's own test makes cargo
/// build it before any test runs); a build of this package alone does not,
/// so it is built here, into the same target folder and profile.
fn build_baseline() {
    let mrsim = std::path::Path::new(env!("CARGO_BIN_EXE_mrsim"));
    let profile_dir = mrsim.parent().expect("the binary's folder");
    if profile_dir.join("mrsim-baseline").is_file() {
        return;
    }
    let target = profile_dir.parent().expect("the target folder");
    let mut cargo = std::process::Command::new(env!("CARGO"));
    cargo
        .args(["build", "-p", "mrsim-baseline"])
        .env("CARGO_TARGET_DIR", target)
        .current_dir(root());
    if profile_dir.file_name().is_some_and(|n| n == "release") {
        cargo.arg("--release");
    }
    let status = cargo.status().expect("start cargo");
    assert!(status.success(), "cargo build -p mrsim-baseline: {status}");
}

#[test]
fn a_tiny_bench_writes_one_row_per_combination_with_every_documented_field() {
    build_baseline();
    let out = fresh_dir("bench");
    let o = mrsim()
        .args([
            "bench",
            "--agents",
            "4,8",
            "--duration",
            "1",
            "--rate",
            "50",
            "--transport",
            "shm,inproc",
            "--baseline",
            "--cpus",
            "0",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("start mrsim");
    assert_ok(&o);
    let text = std::fs::read_to_string(out.join("bench.json")).expect("bench.json");
    let doc: serde_json::Value = serde_json::from_str(&text).expect("bench.json parses");
    let rows = doc["rows"].as_array().expect("rows");
    let combos: Vec<(u64, &str)> = rows
        .iter()
        .map(|r| {
            (
                r["agents"].as_u64().expect("agents"),
                r["transport"].as_str().expect("transport"),
            )
        })
        .collect();
    assert_eq!(
        combos,
        vec![(4, "shm"), (4, "inproc"), (8, "shm"), (8, "inproc")]
    );
    for r in rows {
        assert_eq!(r["rate_hz"], 50.0);
        for k in ["p50", "p99", "p999", "max"] {
            assert!(
                r["roundtrip_us"][k].as_f64().is_some_and(|x| x > 0.0),
                "roundtrip_us.{k}: {r:#}"
            );
        }
        // Null only if no tick had every reply in time (a very busy machine).
        for k in ["p50", "p99"] {
            for f in ["allin_us", "baseline_allin_us", "baseline_roundtrip_us"] {
                let v = r[f]
                    .get(k)
                    .unwrap_or_else(|| panic!("{f}.{k} missing: {r:#}"));
                assert!(
                    v.is_null() || v.as_f64().is_some_and(|x| x > 0.0),
                    "{f}.{k}: {r:#}"
                );
            }
        }
        let miss = r["miss_rate"].as_f64().expect("miss_rate");
        assert!((0.0..=1.0).contains(&miss));
        for k in [
            "jitter_us_p99",
            "world_cpu_pct",
            "agents_cpu_pct",
            "world_rss_mb",
        ] {
            assert!(r[k].as_f64().is_some_and(|x| x >= 0.0), "{k}: {r:#}");
        }
        assert!(r["world_rss_mb"].as_f64().unwrap_or(0.0) > 0.0);
        // From /proc/stat: a share of the wall time, or null without it.
        let steal = &r["steal_pct"];
        assert!(
            steal.is_null() || steal.as_f64().is_some_and(|x| x >= 0.0),
            "steal_pct: {r:#}"
        );
        match r["transport"].as_str() {
            Some("shm") => assert!(r["agent_rss_mb"].as_f64().is_some_and(|x| x > 0.0), "{r:#}"),
            _ => assert!(
                r["agent_rss_mb"].is_null(),
                "in-process agents have no RSS of their own"
            ),
        }
        assert_eq!(r["cpus"], serde_json::json!([0]));
    }
    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5, "{csv}");
    for col in [
        "agents",
        "transport",
        "roundtrip_us_p99",
        "allin_us_p50",
        "miss_rate",
        "baseline_allin_us_p99",
        "baseline_roundtrip_us_p99",
    ] {
        assert!(
            lines[0].split(',').any(|c| c == col),
            "{col} missing from {}",
            lines[0]
        );
    }
    let svg = std::fs::read_to_string(out.join("bench.svg")).expect("bench.svg");
    assert!(
        svg.contains("<svg") && svg.contains("<polyline"),
        "two lines drawn"
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("transport")
            && stdout.lines().filter(|l| l.contains("inproc")).count() >= 2,
        "{stdout}"
    );
}

#[test]
fn a_bench_with_an_unknown_planner_is_refused_before_anything_runs() {
    let out = fresh_dir("bench-bad");
    let o = mrsim()
        .args(["bench", "--agents", "4", "--planner", "nope", "--out"])
        .arg(&out)
        .output()
        .expect("start mrsim");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nope"));
    assert!(!out.join("bench.json").exists());
}

/// Waits up to `secs` for `n` live `mrsim spin --parent PID` processes.
fn wait_for_load(parent: u32, n: usize, secs: u64) -> Vec<u32> {
    let pid = parent.to_string();
    let start = std::time::Instant::now();
    loop {
        let found = find_processes(&["spin", "--parent", &pid]);
        if found.len() == n {
            return found;
        }
        assert!(
            start.elapsed() < std::time::Duration::from_secs(secs),
            "{} load processes of bench {parent} after {secs} s, not {n}",
            found.len()
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn a_bench_under_stress_measures_every_load_and_repetition_and_leaves_no_load_behind() {
    let out = fresh_dir("bench-stress");
    let child = mrsim()
        .args([
            "bench",
            "--agents",
            "4",
            "--duration",
            "1",
            "--rate",
            "50",
            "--transport",
            "shm",
            "--stress",
            "0,1",
            "--repeat",
            "2",
            "--cpus",
            "0",
            "--out",
        ])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start mrsim");
    // The load of the second level runs while it is measured.
    let load = wait_for_load(child.id(), 1, 120);
    let o = child.wait_with_output().expect("bench ends");
    assert_ok(&o);
    for pid in load {
        assert!(process_gone(pid), "load process {pid} outlived the bench");
    }
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).expect("bench.json"))
            .expect("bench.json parses");
    let rows = doc["rows"].as_array().expect("rows");
    let got: Vec<(u64, u64)> = rows
        .iter()
        .map(|r| {
            (
                r["stress"].as_u64().expect("stress"),
                r["repeat"].as_u64().expect("repeat"),
            )
        })
        .collect();
    assert_eq!(got, [(0, 1), (0, 2), (1, 1), (1, 2)]);
    // Every run in its own folder.
    let dirs: std::collections::BTreeSet<&str> =
        rows.iter().filter_map(|r| r["run_dir"].as_str()).collect();
    assert_eq!(dirs.len(), 4);
    // Without a baseline there is no overhead to give.
    assert!(doc.get("overhead").is_none(), "{doc:#}");
    // The load figure: one line (shm, 4 agents) in each of its four panels.
    let svg = std::fs::read_to_string(out.join("stress.svg")).expect("stress.svg");
    assert!(svg.contains("shm, 4 agents"), "legend");
    assert!(out.join("stress.png").is_file());
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("stress.svg"), "{stdout}");
}

#[test]
fn an_interrupted_bench_leaves_no_load_behind() {
    let out = fresh_dir("bench-stress-int");
    let mut child = mrsim()
        .args([
            "bench",
            "--agents",
            "2",
            "--duration",
            "2",
            "--rate",
            "20",
            "--transport",
            "inproc",
            "--stress",
            "2",
            "--cpus",
            "0",
            "--out",
        ])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start mrsim");
    let load = wait_for_load(child.id(), 2, 60);
    // Ctrl-C on the bench alone (not its process group): it dies at once,
    // without a chance to clean up.
    send_signal(child.id(), libc::SIGINT);
    let _ = child.wait();
    let start = std::time::Instant::now();
    while !load.iter().all(|&p| process_gone(p)) {
        assert!(
            start.elapsed() < std::time::Duration::from_secs(10),
            "load processes {load:?} outlived the interrupted bench"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// The named sections and the function symbols of an ELF64 little-endian
/// file, read from its section headers and symbol table.
struct Elf {
    /// Section names by index.
    sections: Vec<String>,
    /// Function symbols: name and the index of their section.
    functions: Vec<(String, usize)>,
}

fn read_elf(path: &std::path::Path) -> Elf {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = std::fs::File::open(path).expect("open the binary");
    let mut at = |offset: u64, len: usize| {
        let mut buf = vec![0u8; len];
        f.seek(SeekFrom::Start(offset)).expect("seek");
        f.read_exact(&mut buf).expect("read");
        buf
    };
    let u16_ = |b: &[u8], i: usize| u16::from_le_bytes([b[i], b[i + 1]]) as usize;
    let u32_ = |b: &[u8], i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap()) as usize;
    let u64_ = |b: &[u8], i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap());
    let head = at(0, 64);
    assert_eq!(
        &head[..6],
        b"\x7fELF\x02\x01",
        "an ELF64 little-endian file"
    );
    let (shoff, shentsize, shnum, shstrndx) = (
        u64_(&head, 0x28),
        u16_(&head, 0x3a),
        u16_(&head, 0x3c),
        u16_(&head, 0x3e),
    );
    let table = at(shoff, shentsize * shnum);
    let header = |i: usize| &table[i * shentsize..(i + 1) * shentsize];
    let contents = |at: &mut dyn FnMut(u64, usize) -> Vec<u8>, i: usize| {
        let h = header(i);
        at(u64_(h, 0x18), u64_(h, 0x20) as usize)
    };
    let name_at = |strings: &[u8], i: usize| {
        let end = strings[i..].iter().position(|&c| c == 0).unwrap_or(0);
        String::from_utf8_lossy(&strings[i..i + end]).into_owned()
    };
    let shstr = contents(&mut at, shstrndx);
    let sections = (0..shnum)
        .map(|i| name_at(&shstr, u32_(header(i), 0)))
        .collect::<Vec<_>>();
    let symtab = (0..shnum)
        .find(|&i| u32_(header(i), 4) == 2)
        .expect("a symbol table");
    let strings = contents(&mut at, u32_(header(symtab), 0x28));
    let symbols = contents(&mut at, symtab);
    let functions = symbols
        .chunks_exact(24)
        .filter(|s| s[4] & 0xf == 2)
        .map(|s| (name_at(&strings, u32_(s, 0)), u16_(s, 6)))
        .collect();
    Elf {
        sections,
        functions,
    }
}

#[test]
fn the_code_of_an_agents_wake_up_lies_side_by_side_at_the_start_of_the_text() {
    let elf = read_elf(std::path::Path::new(env!("CARGO_BIN_EXE_mrsim")));
    let wake = elf.sections.iter().position(|s| s == ".text.wake");
    if option_env!("MRSIM_WAKE_LAYOUT").is_none() {
        assert_eq!(wake, None, "no layout was asked for, yet there is one");
        return;
    }
    let wake = wake.expect("the binary has the wake-up's section (link/wake.ld)");
    // One function of each step of a wake-up: the wait, the snapshot's
    // receipt, the observation, the planner, the command's send.
    for name in [
        "mrsim_agents4live5Ticks6listen",
        "mrsim_transport3shm8doorbell10futex_wait",
        "Subscriber$LT$Service$C$$u5b$Payload$u5d$$C$UserHeader$GT$7receive",
        "mrsim_agents7observe8Observer13observe_among",
        "mrsim_planners..chung..Chung$u20$as$u20$mrsim_planners..Planner$GT$4plan",
        "mrsim_transport3shm5agent12send_command",
        "Publisher$LT$Service$C$Payload$C$UserHeader$GT$9send_copy",
    ] {
        let found: Vec<_> = elf
            .functions
            .iter()
            .filter(|(n, _)| n.contains(name))
            .collect();
        assert!(!found.is_empty(), "no function {name} in the binary");
        assert!(
            found.iter().any(|(_, s)| *s == wake),
            "{name} is not in .text.wake: link/wake.ld no longer names it"
        );
    }
}
