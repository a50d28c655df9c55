#!/usr/bin/env bash
# Soak test (not a CI test): a long realtime run with many agents, reporting
# the world's and one agent's resident memory (VmRSS) and open files at the
# start and at the end, and the run's deadline misses and lost agents.
#
#   cargo build --release
#   scripts/soak.sh            # 10 minutes, 64 agents (BENCHMARKS.md, "Soak")
#   scripts/soak.sh 2          # 2 minutes
#
# Scenario: scenarios/bench/circle-64.toml in realtime at 50 ms ticks, with
# max_speed 0.1 m/s so the robots are still crossing the circle (102 m) when
# the run ends: every agent plans every tick for the whole run.
set -euo pipefail
cd "$(dirname "$0")/.."
minutes=${1:-10}
bin=target/release/mrsim
[ -x "$bin" ] || { echo "build first: cargo build --release" >&2; exit 2; }
secs=$((minutes * 60))
run="soak$$"
out=$(mktemp -d /tmp/mrsim-soak-XXXXXX)

"$bin" run scenarios/bench/circle-64.toml --mode realtime --run "$run" --out "$out" --quiet \
    --set world.duration="$secs" --set world.dt=0.05 --set world.substeps=2 \
    --set 'robot.*.max_speed=0.1' &
launcher=$!

pid_of() { # the mrsim process whose command line contains "$1"
    for p in /proc/[0-9]*; do
        if { tr '\0' ' ' <"$p/cmdline"; } 2>/dev/null | grep -q -- "$1"; then
            basename "$p"
            return 0
        fi
    done
    return 1
}
sample() { # label pid
    local rss fds
    rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$2/status")
    fds=$(ls "/proc/$2/fd" | wc -l)
    printf '%-6s %-12s pid %-7s VmRSS %7s kB  open files %4s\n' "$3" "$1" "$2" "$rss" "$fds"
}

# Let every agent join and the run settle.
sleep 15
world=$(pid_of "world scenarios/bench/circle-64.toml") || { echo "no world" >&2; exit 1; }
agent=$(pid_of "agent --robot g00 --run $run") || { echo "no agent g00" >&2; exit 1; }
sample world "$world" start
sample "agent g00" "$agent" start
sleep $((secs - 25))
sample world "$world" end
sample "agent g00" "$agent" end
status=0
wait "$launcher" || status=$?
echo "launcher exit status: $status; run folder: $out"
python3 - "$out/metrics.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
r = m["robots"].values()
misses = sum(x["deadline_misses"] for x in r)
worst = max(x["deadline_misses"] for x in r)
p99 = sorted(x["latency_us"]["p99"] for x in r)
print(f'ticks {m["ticks"]}  realtime_factor {m["realtime_factor"]:.4f}  agents_lost {m["agents_lost"]}  '
      f'commands_rejected {m["commands_rejected"]}')
print(f'deadline misses: {misses} of {m["ticks"] * len(m["robots"])} commands '
      f'(worst agent {worst}); latency p99 over agents: median {p99[len(p99)//2]:.0f} us, max {p99[-1]:.0f} us')
PY
