#!/usr/bin/env bash
# What one wake-up of an agent touches (not a CI test): the 64-robot bench
# crossing (mrsim bench's scene, chung-1) in realtime at 20 Hz for 10 s, robot
# g00's agent under valgrind's lackey, the other 63 as usual; the trace is cut
# at each futex wait on the doorbell and each wake-up's distinct cache lines
# and pages of code and data counted (scripts/wake_pages.py). Counts, not
# times: the same on a loaded machine. 20 Hz leaves the traced agent time to
# answer every tick; a wake-up's work does not depend on the rate.
#
#   cargo build --release -p mrsim
#   scripts/wake_pages.sh [path/to/mrsim]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/mrsim}
[ -x "$bin" ] || { echo "build first: cargo build --release -p mrsim" >&2; exit 2; }
command -v valgrind >/dev/null || { echo "needs valgrind" >&2; exit 2; }
sym=$(nm "$bin" | awk '/_ZN15mrsim_transport3shm8doorbell10futex_wait/ && !s {s = $1} END {print s}')
[ -n "$sym" ] || { echo "$bin: no doorbell futex_wait symbol" >&2; exit 2; }
# valgrind loads a position-independent program at 0x108000.
split=$(printf '%x' $((0x108000 + 0x$sym)))
dir=$(mktemp -d -t mrsim-wake-XXXXXX)
trap 'rm -rf "$dir"' EXIT
run="wake$$"
cat >"$dir/crossing-64.toml" <<'TOML'
name = "wake-pages-crossing-64"
description = "mrsim bench's 64-robot crossing, realtime at 20 Hz"
length_unit = "m"

[world]
dt = 0.05
substeps = 1
duration = 10
mode = "realtime"
on_deadline_miss = "hold"
deadline = 1
seed = 1
arena = { min = [-29, -29], max = [29, 29] }

[defaults]
radius = 0.25
max_speed = 1.0
max_accel = 2.0
sensing_range = 3
goal_tolerance = 0.1

[generate]
kind = "crossing"
count = 64
radius = 3
planner = "chung-1"
TOML
"$bin" world "$dir/crossing-64.toml" --run "$run" --start-timeout 120 --out "$dir/out" \
    >"$dir/world.log" 2>&1 &
sleep 1
valgrind --tool=lackey --trace-mem=yes --log-fd=9 \
    "$bin" agent --robot g00 --run "$run" --timeout 120 9>"$dir/trace" >/dev/null 2>&1 &
# The traced agent reads the setup slowly; the others join once it has.
sleep 15
for i in $(seq 1 63); do
    "$bin" agent --robot "$(printf g%02d "$i")" --run "$run" --timeout 120 >/dev/null 2>&1 &
done
wait
python3 scripts/wake_pages.py "$split" <"$dir/trace"
