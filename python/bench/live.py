"""A Python live agent against Rust agents in one realtime run: the extra
round trip of answering a tick from Python.

    python python/bench/live.py [--robots 64] [--seconds 5] [--hz 100]

Starts `mrsim run` (target/release/mrsim, or $MRSIM_BIN) on the circle-64
bench scene at the given rate, robot g00 external, every other robot on
ORCA in its own Rust agent process; this process joins as g00 and answers
each tick with a go-to-goal velocity. Prints the round-trip latency (world's
snapshot published -> command received, metrics.json latency_us) of the
Python robot and the median over the Rust ones, p50 and p99.
"""

import argparse
import json
import os
import pathlib
import subprocess
import tempfile

import numpy as np

import mrsim

REPO = pathlib.Path(__file__).resolve().parents[2]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robots", type=int, default=64)
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--hz", type=float, default=100.0)
    a = p.parse_args()
    exe = os.environ.get("MRSIM_BIN") or str(REPO / "target" / "release" / "mrsim")
    out = pathlib.Path(tempfile.mkdtemp()) / "run"
    run_id = f"pybench{os.getpid()}"
    cmd = [
        exe, "run", str(REPO / "scenarios" / "bench" / "circle-64.toml"),
        "--mode", "realtime", "--set", f"generate.count={a.robots}",
        "--set", f"world.dt={1.0 / a.hz}", "--set", "world.substeps=1",
        "--set", f"world.duration={a.seconds}",
        "--set", "robot.g00.planner=external",
        "--run", run_id, "--out", str(out), "--quiet",
    ]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        agent = mrsim.Agent(run_id, "g00", timeout=120)
        for obs in agent:
            d = obs.goal - obs.position
            n = max(np.hypot(*d), 1e-9)
            try:
                agent.reply(d / n * min(obs.max_speed, n))
            except RuntimeError:
                pass
        _, err = proc.communicate(timeout=300)
        if proc.returncode != 0:
            raise SystemExit(f"mrsim run failed: {err}")
    finally:
        proc.kill()
    robots = json.loads((out / mrsim.FILES["metrics"]).read_text())["robots"]
    py = robots["g00"]["latency_us"]
    rust = [r["latency_us"] for name, r in robots.items() if name != "g00"]
    med = {q: float(np.median([r[q] for r in rust])) for q in ("p50", "p99")}
    print(f"{a.robots} robots, {a.hz:g} Hz realtime, {a.seconds:g} s ({out})")
    print(f"  Python agent  p50 {py['p50']:8.1f} us  p99 {py['p99']:8.1f} us  misses {robots['g00']['deadline_misses']}")
    print(f"  Rust agents   p50 {med['p50']:8.1f} us  p99 {med['p99']:8.1f} us  (median over {len(rust)})")
    print(f"  extra         p50 {py['p50'] - med['p50']:8.1f} us  p99 {py['p99'] - med['p99']:8.1f} us")


if __name__ == "__main__":
    main()
