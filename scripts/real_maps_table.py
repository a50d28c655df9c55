#!/usr/bin/env python3
"""Outcomes of differential-drive robots swapping places on real maps.

Each scene given is run three times, in lockstep in-process (deterministic:
the table measures outcomes, not speed, so a busy machine gives the same
numbers; the world's `stall_timeout` is raised to STALL s, as on a busy
machine an agent building its route on a large map can take longer than
the default 2 s to its first command, and a robot whose agent is lost
brakes for as long as the wall clock says: a row where any agent was
lost says so, as its numbers depend on the machine's load): dwa from the
laser scan, orca, and dwa on true states, all on
unicycles following their `route = "shortest"`. The scene's `[defaults]`
must hold a `planner = ...` line (and may hold a `params = ...` line),
which are replaced for each run. A comment line `# source: ...` in the
scene names where its map comes from (the table's source column).

Prints a Markdown table: map, source, robots, planner, goals reached,
robot-robot contacts (the world's collision events between two robots),
and the deepest any robot came inside a map wall (its centre's distance to
the nearest wall segment less its radius, over every tick of
trajectory.csv; 0 when none did).

`--lane right` (or `left`) adds that `lane` to every scene's `[defaults]`.

Run from the repository root after `cargo build --release`:
    python3 scripts/real_maps_table.py [--lane right] SCENE.toml [SCENE.toml ...]
"""

import json
import math
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MRSIM = os.path.join(ROOT, "target", "release", "mrsim")
# (label, planner, params line)
VARIANTS = [
    ("dwa (scan)", "dwa", 'params = { obstacles = "scan" }'),
    ("orca", "orca", ""),
    ("dwa (truth)", "dwa", 'params = { obstacles = "truth" }'),
]
CELL = 1.0  # wall buckets, in the scene's length unit
STALL = 120.0  # s a lockstep world waits for an agent's command


def variant(src, planner, params):
    """The scene with its defaults' planner and params replaced."""
    head, sep, rest = src.partition("[defaults]")
    if not sep:
        raise SystemExit("the scene has no [defaults] table")
    body, nxt, tail = rest.partition("\n[")
    body = re.sub(r"(?m)^params\s*=.*\n", "", body)
    body, n = re.subn(r'(?m)^planner\s*=.*$', 'planner = "%s"\n%s' % (planner, params), body)
    if n != 1:
        raise SystemExit("the scene's [defaults] has no planner line")
    return head + sep + body + nxt + tail


def seg_dist(p, a, b):
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    ll = dx * dx + dy * dy
    t = 0.0 if ll == 0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / ll))
    return math.hypot(p[0] - ax - t * dx, p[1] - ay - t * dy)


def wall_depth(out):
    """The deepest any robot came inside a map wall (0 if none), and who."""
    scen = json.load(open(os.path.join(out, "scenario.json")))
    n_map = scen.get("map", {}).get("walls", 0)
    walls = [w["segment"] for w in scen["walls"][len(scen["walls"]) - n_map:]]
    radius = {r["name"]: r["radius"] for r in scen["robots"]}
    reach = max(radius.values()) + 0.01
    buckets = {}
    for k, (a, b) in enumerate(walls):
        lo = [min(a[i], b[i]) - reach for i in (0, 1)]
        hi = [max(a[i], b[i]) + reach for i in (0, 1)]
        for i in range(math.floor(lo[0] / CELL), math.floor(hi[0] / CELL) + 1):
            for j in range(math.floor(lo[1] / CELL), math.floor(hi[1] / CELL) + 1):
                buckets.setdefault((i, j), []).append(k)
    deepest, who = 0.0, "-"
    with open(os.path.join(out, "trajectory.csv")) as f:
        cols = f.readline().strip().split(",")
        ib, ik, ix, iy = (cols.index(c) for c in ("body", "kind", "x", "y"))
        for line in f:
            row = line.split(",")
            if row[ik] != "robot":
                continue
            p = (float(row[ix]), float(row[iy]))
            r = radius[row[ib]]
            for k in buckets.get((math.floor(p[0] / CELL), math.floor(p[1] / CELL)), ()):
                d = r - seg_dist(p, *walls[k])
                if d > deepest:
                    deepest, who = d, row[ib]
    return deepest, who


def source_of(src):
    m = re.search(r"(?m)^#\s*source:\s*(.+)$", src)
    return m.group(1).strip() if m else "-"


def map_of(src):
    m = re.search(r'(?m)^file\s*=\s*"([^"]+)"', src)
    return os.path.splitext(os.path.basename(m.group(1)))[0] if m else "-"


def absolute_map(src, scene):
    """The scene with its map's `file` made absolute (the variant is
    written elsewhere; a relative path is relative to the scene)."""
    base = os.path.dirname(os.path.abspath(scene))

    def fix(m):
        path = m.group(2)
        if not os.path.isabs(path):
            path = os.path.normpath(os.path.join(base, path))
        return '%s"%s"' % (m.group(1), path.replace("\\", "/"))

    return re.sub(r'(?m)^(file\s*=\s*)"([^"]+)"', fix, src)


def run(scene, label, planner, params, tmp, lane=None):
    src = open(scene).read()
    tag = "%s-%s" % (os.path.splitext(os.path.basename(scene))[0], re.sub(r"\W+", "-", label))
    path = os.path.join(tmp, tag + ".toml")
    with open(path, "w") as f:
        f.write(variant(absolute_map(src, scene), planner, params + ('\nlane = "%s"' % lane if lane else "")))
    out = os.path.join(tmp, tag)
    p = subprocess.run(
        [MRSIM, "run", path, "--out", out, "--mode", "lockstep", "--transport", "inproc", "--quiet",
         "--set", "world.stall_timeout=%g" % STALL],
        capture_output=True,
        text=True,
    )
    if p.returncode != 0 or not os.path.exists(os.path.join(out, "metrics.json")):
        return "| %s | %s | | %s | failed: %s | | |" % (
            map_of(src), source_of(src), label, " ".join(p.stderr.strip().splitlines()[-1:]))
    robots = json.load(open(os.path.join(out, "metrics.json")))["robots"]
    names = set(robots)
    rr = 0
    lost = set()
    for line in open(os.path.join(out, "events.jsonl")):
        e = json.loads(line)
        if e.get("type") == "collision" and e["a"] in names and e["b"] in names:
            rr += 1
        if e.get("type") == "agent_lost":
            lost.add(e.get("robot"))
    reached = sum(1 for r in robots.values() if r.get("reached_goal"))
    depth, _ = wall_depth(out)
    note = " (agents lost: %s; not deterministic)" % ", ".join(sorted(lost)) if lost else ""
    return "| %s | %s | %d | %s | %d/%d (%.0f %%)%s | %d | %.2f mm |" % (
        map_of(src), source_of(src), len(robots), label, reached, len(robots),
        100.0 * reached / len(robots), note, rr, 1000.0 * depth)


def main():
    scenes = sys.argv[1:]
    lane = None
    if scenes[:1] == ["--lane"]:
        if len(scenes) < 2 or scenes[1] not in ("right", "left", "none"):
            raise SystemExit("--lane takes right, left or none")
        lane, scenes = scenes[1], scenes[2:]
    if not scenes:
        raise SystemExit(__doc__)
    print("| map | source | robots | planner | goals reached | robot-robot contacts | deepest into a wall |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:
            for label, planner, params in VARIANTS:
                print(run(scene, label, planner, params, tmp, lane), flush=True)


if __name__ == "__main__":
    main()
