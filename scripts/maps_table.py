#!/usr/bin/env python3
"""Outcomes of every planner, holonomic and unicycle, on the shipped maps.

Runs scenarios/maps/office-turtlebots.toml (eight TurtleBot3-like robots
swapping rooms with route = "shortest") once per planner and kinematics,
in lockstep in-process (deterministic: the table measures outcomes, not
speed, so a busy machine gives the same numbers), and prints a Markdown
table: goals reached, robot-robot contacts, robot-wall contacts, the mean
and the largest time to goal of the robots that arrived.

Run from the repository root after `cargo build --release`:
    python3 scripts/maps_table.py [PLANNER ...]
"""

import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "scenarios", "maps", "office-turtlebots.toml")
MRSIM = os.path.join(ROOT, "target", "release", "mrsim")
# (label, planner, params line)
PLANNERS = [
    ("dwa (scan)", "dwa", 'params = { obstacles = "scan" }'),
    ("dwa (truth)", "dwa", 'params = { obstacles = "truth" }'),
    ("orca", "orca", ""),
    ("social-force", "social-force", ""),
    ("hydro", "hydro", ""),
    ("trajectory-guided", "trajectory-guided", ""),
    ("homing", "homing", ""),
]


def scene(planner, params, kinematics):
    src = open(SCENE).read()
    src = src.replace(
        'planner = "dwa"\nparams = { obstacles = "scan" }',
        'planner = "%s"\n%s' % (planner, params),
    )
    src = src.replace('kinematics = "unicycle"', 'kinematics = "%s"' % kinematics)
    src = src.replace('file = "office.yaml"', 'file = "%s"' % os.path.join(ROOT, "scenarios", "maps", "office.yaml"))
    return src


def run(label, planner, params, kinematics, tmp):
    path = os.path.join(tmp, "%s-%s.toml" % (planner, kinematics))
    with open(path, "w") as f:
        f.write(scene(planner, params, kinematics))
    out = os.path.join(tmp, "%s-%s-%d" % (planner, kinematics, abs(hash(label))))
    p = subprocess.run(
        [MRSIM, "run", path, "--out", out, "--mode", "lockstep", "--transport", "inproc", "--quiet"],
        capture_output=True,
        text=True,
    )
    if p.returncode != 0 or not os.path.exists(os.path.join(out, "metrics.json")):
        return "| %s | %s | failed: %s |||||" % (label, kinematics, p.stderr.strip().splitlines()[-1:])
    m = json.load(open(os.path.join(out, "metrics.json")))
    robots = m["robots"]
    names = set(robots)
    rr = rw = 0
    for line in open(os.path.join(out, "events.jsonl")):
        e = json.loads(line)
        if e.get("type") != "collision":
            continue
        if e["a"] in names and e["b"] in names:
            rr += 1
        else:
            rw += 1
    times = [r["time_to_goal"] for r in robots.values() if r.get("reached_goal")]
    reached = len(times)
    mean = "%.1f" % (sum(times) / reached) if reached else "-"
    worst = "%.1f" % max(times) if reached else "-"
    return "| %s | %s | %d/%d | %d | %d | %s | %s |" % (
        label, kinematics, reached, len(robots), rr, rw, mean, worst)


def main():
    wanted = set(sys.argv[1:])
    print("| planner | robots | goals reached | robot-robot contacts | robot-wall contacts | mean time to goal, s | last arrival, s |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for label, planner, params in PLANNERS:
            if wanted and planner not in wanted and label not in wanted:
                continue
            for kinematics in ("holonomic", "unicycle"):
                print(run(label, planner, params, kinematics, tmp), flush=True)


if __name__ == "__main__":
    main()
