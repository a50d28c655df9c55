#!/bin/sh
# Enki beside mrsim on the crossing scene: builds a small Enki program from
# Debian's libenki-dev (scripts/enki_peer.cc: a disc per robot with a
# go-to-goal controller, one thread, no walls), gives it the very starts and
# goals mrsim generates for the scene (read from the scenario.json of a
# one-tick mrsim run) and prints Enki's real-time factor for each robot
# count. Outside the product: nothing here is built by cargo.
#
#   apt-get install libenki-dev g++      # once
#   cargo build --release -p mrsim
#   scripts/enki_peer.sh [COUNTS...]     # default: 1000 10000 100000
#
# Environment: MRSIM (default target/release/mrsim), DT (default 0.1, the
# scale table's), STEPS_<count> (steps to time; default 300 at 1,000, 10 at
# 10,000, 1 at 100,000: Enki tests every pair of bodies each step).
# rtf_cpu (simulated time over the process's CPU time) holds on a loaded
# machine; rtf_wall only on a quiet one.
set -eu
cd "$(dirname "$0")/.."
MRSIM=${MRSIM:-target/release/mrsim}
DT=${DT:-0.1}
SCENE=scenarios/bench/crossing-1000.toml
[ -x "$MRSIM" ] || { echo "no mrsim at $MRSIM: cargo build --release -p mrsim" >&2; exit 2; }
[ -e /usr/include/enki/PhysicalEngine.h ] || { echo "Enki's headers are missing: apt-get install libenki-dev" >&2; exit 2; }
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
g++ -O2 -std=c++17 scripts/enki_peer.cc -lenki -o "$WORK/enki_peer"
[ $# -gt 0 ] || set -- 1000 10000 100000
for n in "$@"; do
    case $n in
        1000) steps=300 ;;
        10000) steps=10 ;;
        *) steps=1 ;;
    esac
    eval "steps=\${STEPS_$n:-$steps}"
    # The scale table's arena: 4 km across up to 10,000 robots, 40 km above
    # (the crossing's streams grow with the count: 20,000 reach 7.5 km).
    if [ "$n" -gt 10000 ]; then a=40000; else a=4000; fi
    "$MRSIM" run "$SCENE" --transport inproc --quiet --no-report --out "$WORK/run-$n" \
        --set generate.count="$n" --set world.dt="$DT" --set world.duration="$DT" \
        --set "world.arena.min=[-$a,-$a]" --set "world.arena.max=[$a,$a]" >/dev/null
    python3 - "$WORK/run-$n/scenario.json" "$WORK/places-$n.txt" "$WORK/robot-$n.txt" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
robots = s["robots"]
with open(sys.argv[2], "w") as f:
    for r in robots:
        f.write("%r %r %r %r\n" % (*r["start"], *r["goal"]))
r = robots[0]
if any((q["radius"], q["max_speed"], q["goal_tolerance"]) != (r["radius"], r["max_speed"], r["goal_tolerance"]) for q in robots):
    sys.exit("robots of different sizes, speeds or tolerances: not the crossing scene")
open(sys.argv[3], "w").write("%r %r %r\n" % (r["max_speed"], r["radius"], r["goal_tolerance"]))
PY
    read -r speed radius tolerance < "$WORK/robot-$n.txt"
    echo "enki n=$n $("$WORK/enki_peer" "$WORK/places-$n.txt" "$DT" "$steps" "$speed" "$radius" "$tolerance")"
    rm -rf "$WORK/run-$n"
done
