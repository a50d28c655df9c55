"""The cmd_vel -> odom round trip of mrsim's ROS 2 agent, seen from a ROS 2
node over rmw_zenoh (played with eclipse-zenoh and rosbags, as in
python/tests/test_ros2.py).

    python python/bench/ros2_roundtrip.py [--robots 10] [--hz 20] [--seconds 20] [--mode realtime]

A scene of N holonomic robots with planner = "ros2" runs at HZ (dt = 1/HZ);
this node answers every robot's odom with a cmd_vel at once. The round trip
of a robot is the wall time from the node publishing its cmd_vel to the
node receiving that robot's next odom: in lockstep, the world's step plus
both hops; in realtime, the node answers at once, so the next odom comes
with the next tick: one period plus the lateness of the tick's odom
(printed as well, as the trip minus one period). Printed: count, median,
90th and 99th percentile, max, in ms; then whether the run was whole: the
robots that joined, the agents the world lost, and the ROS 2 agent's
counts (cmd_vel taken, lockstep ticks missed, realtime ticks stale).
"""

import json

import argparse
import pathlib
import socket
import subprocess
import sys
import tempfile
import threading
import time

import zenoh
from rosbags.typesys import Stores, get_typestore
from zenoh.ext import Int64, z_serialize

REPO = pathlib.Path(__file__).resolve().parents[2]
TS = get_typestore(Stores.ROS2_JAZZY)


def key(topic, ros_type):
    pkg, sub, name = ros_type.split("/")
    return f"0/{topic.strip('/')}/{pkg}::{sub}::dds_::{name}_/{TS.hash_rihs01(ros_type)}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--robots", type=int, default=10)
    ap.add_argument("--hz", type=float, default=20.0)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--mode", choices=["realtime", "lockstep"], default="realtime")
    ap.add_argument("--mrsim", default=str(REPO / "target" / "release" / "mrsim"))
    a = ap.parse_args()
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("listen/endpoints", f'["tcp/127.0.0.1:{port}"]')
    conf.insert_json5("scouting/multicast/enabled", "false")
    session = zenoh.open(conf)
    Twist = TS.types["geometry_msgs/msg/Twist"]
    Vector3 = TS.types["geometry_msgs/msg/Vector3"]
    stop = bytes(TS.serialize_cdr(
        Twist(linear=Vector3(x=0.0, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=0.0)),
        "geometry_msgs/msg/Twist",
    ))
    names = [f"r{i}" for i in range(a.robots)]
    sent = {}
    trips = []
    seq = [1]
    lock = threading.Lock()

    def on_odom(name):
        k = key(f"/{name}/cmd_vel", "geometry_msgs/msg/Twist")

        def on(sample):
            now = time.perf_counter()
            with lock:
                if name in sent:
                    trips.append(now - sent.pop(name))
                att = z_serialize((Int64(seq[0]), Int64(time.time_ns()), bytes(16)))
                seq[0] += 1
                sent[name] = time.perf_counter()
            session.put(k, stop, attachment=att)

        return on

    subs = [
        session.declare_subscriber(key(f"/{n}/odom", "nav_msgs/msg/Odometry"), on_odom(n))
        for n in names
    ]
    scene = f"""name = "ros2-roundtrip"
length_unit = "m"
[world]
dt = {1.0 / a.hz}
duration = {a.seconds}
mode = "{a.mode}"
stall_timeout = 5.0
arena = {{ min = [-50.0, -50.0], max = [50.0, 50.0] }}
[defaults]
planner = "ros2"
radius = 0.2
"""
    for i, n in enumerate(names):
        scene += f'\n[[robot]]\nname = "{n}"\nstart = [{2.0 * i}, 0.0]\ngoal = [{2.0 * i}, 40.0]\n'
    with tempfile.TemporaryDirectory() as d:
        p = pathlib.Path(d) / "scene.toml"
        p.write_text(scene)
        r = subprocess.run(
            [a.mrsim, "run", str(p), "--out", str(pathlib.Path(d) / "out"), "--quiet",
             "--ros2-connect", f"tcp/127.0.0.1:{port}"],
            capture_output=True, text=True,
        )
        if r.returncode != 0:
            sys.exit(f"mrsim run failed:\n{r.stderr}")
        out = pathlib.Path(d) / "out"
        metrics = json.loads((out / "metrics.json").read_text())
        counts = json.loads((out / "ros2.json").read_text())["robots"].values()
        joined = {json.loads(line).get("robot") for line in (out / "events.jsonl").open()
                  if '"agent_joined"' in line}
    del subs
    session.close()
    t = sorted(x * 1e3 for x in trips)
    if not t:
        sys.exit("no round trip measured")
    q = lambda f: t[min(len(t) - 1, int(f * len(t)))]
    print(f"{a.robots} robots, {a.hz:g} Hz, {a.mode}: {len(t)} round trips, "
          f"median {q(0.5):.2f} ms, p90 {q(0.9):.2f} ms, p99 {q(0.99):.2f} ms, max {t[-1]:.2f} ms")
    if a.mode == "realtime":
        p = 1e3 / a.hz
        print(f"  minus one period ({p:.1f} ms): median {q(0.5) - p:.2f} ms, "
              f"p99 {q(0.99) - p:.2f} ms, max {t[-1] - p:.2f} ms")
    ticks = metrics["ticks"]
    print(f"  {len(joined)} of {a.robots} robots joined, {metrics['agents_lost']} agents lost; "
          f"{ticks} ticks, {len(t)} of {a.robots * (ticks - 1)} odoms answered and followed by the next; "
          f"cmd_vel taken {sum(c['accepted'] for c in counts)}, "
          f"ticks missed {sum(c['missed'] for c in counts)}, stale {sum(c['stale'] for c in counts)}")


if __name__ == "__main__":
    main()
