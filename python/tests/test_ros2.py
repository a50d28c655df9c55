"""ROS 2 over rmw_zenoh without a ROS install: this file plays a ROS 2 node
the way rmw_zenoh_cpp makes one, with implementations nobody on mrsim wrote:
`eclipse-zenoh` (the transport, and zenoh.ext's serializer for the 33-byte
attachment and advanced subscriber for transient-local topics), `rosbags`
(CDR of the ROS 2 Jazzy message definitions and their RIHS01 type hashes)
and `xxhash` (XXH3-128, from which rmw_zenoh takes a publisher's GID). Against a real `mrsim run` of robots with
planner = "ros2".

These packages are required (CI installs them): a missing one fails here,
it is never skipped.
"""

import csv
import json
import math
import os
import queue
import socket
import subprocess
import threading
import time

import pytest
import xxhash
import zenoh
from rosbags.typesys import Stores, get_typestore
from zenoh.ext import Int64, z_deserialize, z_serialize

from conftest import built_mrsim

TS = get_typestore(Stores.ROS2_JAZZY)
TYPES = {
    "twist": "geometry_msgs/msg/Twist",
    "odom": "nav_msgs/msg/Odometry",
    "scan": "sensor_msgs/msg/LaserScan",
    "tf": "tf2_msgs/msg/TFMessage",
    "clock": "rosgraph_msgs/msg/Clock",
    "map": "nav_msgs/msg/OccupancyGrid",
}


def dds(ros_type):
    """`pkg/msg/Type` as rmw_zenoh names it in keys: `pkg::msg::dds_::Type_`."""
    pkg, sub, name = ros_type.split("/")
    return f"{pkg}::{sub}::dds_::{name}_"


def key(domain, topic, ros_type):
    """rmw_zenoh's key expression of a topic (docs/design.md)."""
    return f"{domain}/{topic.strip('/')}/{dds(ros_type)}/{TS.hash_rihs01(ros_type)}"


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class RosNode:
    """A ROS 2 node over rmw_zenoh, written from rmw_zenoh's design document:
    a Zenoh peer the bridge connects to, a node token, a token per publisher
    and subscriber, samples with the 33-byte attachment."""

    def __init__(self, port, name="py_nav", domain=0):
        conf = zenoh.Config()
        conf.insert_json5("mode", '"peer"')
        conf.insert_json5("listen/endpoints", f'["tcp/127.0.0.1:{port}"]')
        conf.insert_json5("scouting/multicast/enabled", "false")
        self.session = zenoh.open(conf)
        self.domain = domain
        self.zid = str(self.session.zid())
        self.name = name
        self.next_id = 1
        self.tokens = [
            self.session.liveliness().declare_token(
                f"@ros2_lv/{domain}/{self.zid}/0/0/NN/%/%/{name}"
            )
        ]
        self.subs = []
        self.seq = {}

    def _token(self, kind, topic, ros_type, qos):
        eid = self.next_id
        self.next_id += 1
        k = (
            f"@ros2_lv/{self.domain}/{self.zid}/0/{eid}/{kind}/%/%/{self.name}/"
            f"{topic.replace('/', '%')}/{dds(ros_type)}/{TS.hash_rihs01(ros_type)}/{qos}"
        )
        self.tokens.append(self.session.liveliness().declare_token(k))
        return eid

    def subscribe(self, topic, ros_type, on):
        self._token("MS", topic, ros_type, "::,10:,:,:,,")

        def handler(sample):
            on(str(sample.key_expr), sample.payload.to_bytes(), sample.attachment)

        self.subs.append(
            self.session.declare_subscriber(key(self.domain, topic, ros_type), handler)
        )

    def publisher(self, topic, ros_type):
        eid = self._token("MP", topic, ros_type, "::,10:,:,:,,")
        gid = eid.to_bytes(16, "little")
        k = key(self.domain, topic, ros_type)
        self.seq[k] = 1

        def put(payload, attachment=True, under=None):
            att = None
            if attachment:
                att = z_serialize((Int64(self.seq[k]), Int64(time.time_ns()), gid))
                self.seq[k] += 1
            self.session.put(under or k, payload, attachment=att)

        return put

    def close(self):
        for t in self.tokens:
            t.undeclare()
        self.session.close()


def twist(v=0.0, w=0.0, vy=0.0):
    Twist = TS.types["geometry_msgs/msg/Twist"]
    Vector3 = TS.types["geometry_msgs/msg/Vector3"]
    return bytes(TS.serialize_cdr(
        Twist(linear=Vector3(x=v, y=vy, z=0.0), angular=Vector3(x=0.0, y=0.0, z=w)),
        "geometry_msgs/msg/Twist",
    ))


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def write_scene(tmp_path, robots, duration=30.0, extra="", arena="arena = { min = [-5.0, -5.0], max = [5.0, 5.0] }",
                mode="lockstep", dt=0.1):
    body = f"""name = "ros2-test"
length_unit = "m"

[world]
dt = {dt}
substeps = 10
duration = {duration}
mode = "{mode}"
seed = 1
stall_timeout = 5.0
{arena}
{extra}
"""
    for r in robots:
        body += "\n[[robot]]\n" + "\n".join(f"{k} = {v}" for k, v in r.items()) + "\n"
    p = tmp_path / "ros2.toml"
    p.write_text(body)
    return p


def start_run(repo, scene, out, port, *extra):
    return subprocess.Popen(
        [built_mrsim(repo), "run", str(scene), "--out", str(out), "--quiet",
         "--ros2-connect", f"tcp/127.0.0.1:{port}", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def stop(proc):
    """Ends a run (SIGTERM: the launcher stops the world and its agents)."""
    proc.terminate()
    try:
        proc.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()


def finish(proc, timeout=120):
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.terminate()
        out, err = proc.communicate()
        pytest.fail(f"mrsim run did not end:\n{err}")
    return proc.returncode, out, err


UNICYCLE = {
    "planner": '"ros2"',
    "kinematics": '"unicycle"',
    "radius": 0.2,
    "max_speed": 1.0,
    "max_accel": 2.0,
    "max_angular_speed": 2.0,
    "max_angular_accel": 4.0,
    "goal_tolerance": 0.15,
}


def test_a_ros2_node_drives_a_unicycle_to_its_goal_by_cmd_vel_reading_odom_and_clock(repo, tmp_path):
    port = free_port()
    node = RosNode(port)
    scene = write_scene(
        tmp_path, [dict(UNICYCLE, name='"r0"', start="[-2.0, -1.0]", goal="[2.0, 1.5]")]
    )
    goal = (2.0, 1.5)
    odoms = queue.Queue()
    clocks = []
    node.subscribe("/clock", TYPES["clock"], lambda k, p, a: clocks.append(
        TS.deserialize_cdr(p, TYPES["clock"]).clock))
    node.subscribe("/r0/odom", TYPES["odom"], lambda k, p, a: odoms.put(
        TS.deserialize_cdr(p, TYPES["odom"])))
    cmd = node.publisher("/r0/cmd_vel", TYPES["twist"])
    out = tmp_path / "out"
    proc = start_run(repo, scene, out, port)
    answered = 0
    try:
        while proc.poll() is None:
            try:
                o = odoms.get(timeout=0.5)
            except queue.Empty:
                continue
            # The odometry of a tick that /clock announces (the two topics'
            # callbacks may run in either order here).
            stamp = (o.header.stamp.sec, o.header.stamp.nanosec)
            until = time.monotonic() + 2.0
            while stamp not in {(c.sec, c.nanosec) for c in list(clocks)}:
                assert time.monotonic() < until, (stamp, clocks[-3:])
                time.sleep(0.001)
            x, y = o.pose.pose.position.x, o.pose.pose.position.y
            yaw = yaw_of(o.pose.pose.orientation)
            dx, dy = goal[0] - x, goal[1] - y
            err = math.atan2(dy, dx) - yaw
            err = math.atan2(math.sin(err), math.cos(err))
            dist = math.hypot(dx, dy)
            v = max(0.0, min(0.8, dist) * math.cos(err))
            cmd(twist(v, max(-2.0, min(2.0, 3.0 * err))))
            answered += 1
    except BaseException:
        stop(proc)
        node.close()
        raise
    code, stdout, err = finish(proc)
    node.close()
    assert code == 0, err
    assert answered > 20, err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["robots_arrived"] == 1 if "robots_arrived" in metrics else True, metrics
    rows = list(csv.DictReader((out / "trajectory.csv").open()))
    last = [r for r in rows if r["body"] == "r0"][-1]
    assert math.hypot(float(last["x"]) - goal[0], float(last["y"]) - goal[1]) < 0.3, last
    stats = json.loads((out / "ros2.json").read_text())["robots"]["r0"]
    assert stats["accepted"] >= answered - 1 and stats["bad_attachment"] == 0, stats
    assert stats["undecodable"] == stats["wrong_type"] == stats["non_finite"] == 0, stats


def test_every_message_mrsim_sends_decodes_with_rosbags_to_the_values_of_trajectory_csv(repo, tmp_path):
    port = free_port()
    node = RosNode(port)
    r0 = dict(UNICYCLE, name='"r0"', start="[-2.0, 0.0]", goal="[2.0, 0.0]",
              sensor='{ kind = "lidar", beams = 36, range = 3.0 }')
    r1 = dict(UNICYCLE, name='"r1"', start="[0.0, -2.0]", goal="[0.0, 2.0]")
    del r1["kinematics"], r1["max_angular_speed"], r1["max_angular_accel"]
    scene = write_scene(tmp_path, [r0, r1], duration=2.0)
    got = {name: [] for name in ["clock", "tf", "r0/odom", "r0/scan", "r1/odom"]}
    atts = []
    lock = threading.Lock()

    def keep(name, ros_type):
        def on(k, p, a):
            with lock:
                got[name].append((k, TS.deserialize_cdr(p, ros_type)))
                atts.append((k, a.to_bytes() if a is not None else None))
        return on

    node.subscribe("/clock", TYPES["clock"], keep("clock", TYPES["clock"]))
    node.subscribe("/tf", TYPES["tf"], keep("tf", TYPES["tf"]))
    node.subscribe("/r0/odom", TYPES["odom"], keep("r0/odom", TYPES["odom"]))
    node.subscribe("/r0/scan", TYPES["scan"], keep("r0/scan", TYPES["scan"]))
    node.subscribe("/r1/odom", TYPES["odom"], keep("r1/odom", TYPES["odom"]))
    cmds = {r: node.publisher(f"/{r}/cmd_vel", TYPES["twist"]) for r in ["r0", "r1"]}
    # Answer every tick of both robots with a constant command.
    seen = {"r0": 0, "r1": 0}
    out = tmp_path / "out"
    proc = start_run(repo, scene, out, port)
    try:
        while proc.poll() is None:
            time.sleep(0.005)
            with lock:
                n = {"r0": len(got["r0/odom"]), "r1": len(got["r1/odom"])}
            for r in ["r0", "r1"]:
                if n[r] > seen[r]:
                    seen[r] = n[r]
                    cmds[r](twist(0.5, 0.3) if r == "r0" else twist(0.0, 0.0, 0.4))
    except BaseException:
        stop(proc)
        node.close()
        raise
    code, _, err = finish(proc)
    node.close()
    assert code == 0, err
    rows = list(csv.DictReader((out / "trajectory.csv").open()))
    by = {(r["body"], round(float(r["time"]), 6)): r for r in rows}
    assert len(got["clock"]) >= 15 and got["r0/scan"] and got["tf"], {k: len(v) for k, v in got.items()}
    for name in ["r0", "r1"]:
        odoms = got[f"{name}/odom"]
        assert len(odoms) >= 15
        for k, o in odoms:
            assert k == key(0, f"/{name}/odom", TYPES["odom"])
            t = o.header.stamp.sec + o.header.stamp.nanosec * 1e-9
            row = by[(name, round(t, 6))]
            assert o.header.frame_id == f"{name}/odom" and o.child_frame_id == f"{name}/base_link"
            assert o.pose.pose.position.x == pytest.approx(float(row["x"]), abs=1e-6)
            assert o.pose.pose.position.y == pytest.approx(float(row["y"]), abs=1e-6)
            yaw = yaw_of(o.pose.pose.orientation)
            theta = float(row.get("theta") or 0.0)
            assert math.cos(yaw - theta) == pytest.approx(1.0, abs=1e-9)
            # The body-frame velocity, turned back into the world frame.
            lx, ly = o.twist.twist.linear.x, o.twist.twist.linear.y
            vx = math.cos(yaw) * lx - math.sin(yaw) * ly
            vy = math.sin(yaw) * lx + math.cos(yaw) * ly
            assert vx == pytest.approx(float(row["vx"]), abs=1e-6)
            assert vy == pytest.approx(float(row["vy"]), abs=1e-6)
            assert len(o.pose.covariance) == 36
    # The robot r1 (holonomic) moved along +y as its cmd_vel said.
    assert got["r1/odom"][-1][1].pose.pose.position.y > -2.0 + 0.1
    clock_times = [c.clock.sec + c.clock.nanosec * 1e-9 for _, c in got["clock"]]
    assert clock_times == sorted(clock_times)
    assert clock_times[1] - clock_times[0] == pytest.approx(0.1, abs=1e-9)
    for k, tf in got["tf"]:
        for tr in tf.transforms:
            assert tr.header.frame_id.endswith("/odom") and tr.child_frame_id.endswith("/base_link")
            t = tr.header.stamp.sec + tr.header.stamp.nanosec * 1e-9
            row = by[(tr.header.frame_id.split("/")[0], round(t, 6))]
            assert tr.transform.translation.x == pytest.approx(float(row["x"]), abs=1e-6)
    k, scan = got["r0/scan"][-1]
    assert k == key(0, "/r0/scan", TYPES["scan"])
    assert len(scan.ranges) == 36 and scan.range_max == pytest.approx(3.0)
    assert scan.angle_max == pytest.approx(scan.angle_min + 35 * scan.angle_increment, rel=1e-5)
    # Every sample carries rmw_zenoh's attachment: seq from 1 per publisher,
    # the GID XXH3-128 of the publisher's liveliness token (low 64 bits
    # first, each half little-endian: the 128-bit value little-endian).
    tokens = json.loads((out / "ros2.json").read_text())["tokens"]

    def gid_of(k):
        parts = k.split("/")
        topic = "%".join(parts[1:-2])
        mine = [t for t in tokens if f"/MP/%/%/mrsim_r0/%{topic}/{parts[-2]}/{parts[-1]}/" in t]
        assert len(mine) == 1, (k, tokens)
        return xxhash.xxh3_128_intdigest(mine[0].encode()).to_bytes(16, "little")

    firsts = {}
    for k, a in atts:
        assert a is not None and len(a) == 33, (k, a)
        seq, stamp, gid = z_deserialize(tuple[Int64, Int64, bytes], zenoh.ZBytes(a))
        assert len(gid) == 16 and stamp > 1.6e18
        assert gid == gid_of(k), k
        firsts.setdefault(k, seq)
    assert 1 in firsts.values()


def test_the_map_goes_out_as_an_occupancy_grid(repo, tmp_path):
    port = free_port()
    node = RosNode(port)
    maps = (repo / "scenarios" / "maps" / "office.yaml").resolve()
    scene = write_scene(
        tmp_path,
        [dict(UNICYCLE, name='"r0"', start="[-7.5, 5.5]", goal="[-7.0, 5.5]")],
        duration=1.0,
        extra=f'\n[map]\nfile = "{maps}"\n',
        arena="",
    )
    grids = []
    node.subscribe("/map", TYPES["map"], lambda k, p, a: grids.append(TS.deserialize_cdr(p, TYPES["map"])))
    out = tmp_path / "out"
    proc = start_run(repo, scene, out, port)
    code, _, err = finish(proc)
    node.close()
    assert code == 0, err
    assert grids, err
    g = grids[0]
    text = maps.read_text()
    assert g.header.frame_id == "map"
    assert len(g.data) == g.info.width * g.info.height > 0
    assert g.info.resolution == pytest.approx(0.05)
    values = set(int(v) for v in g.data)
    assert values <= {-1} | set(range(0, 101)) and 0 in values and 100 in values


def test_keys_and_liveliness_tokens_are_the_documented_rmw_zenoh_forms(repo, tmp_path):
    port = free_port()
    node = RosNode(port)
    r0 = dict(UNICYCLE, name='"r0"', start="[-2.0, 0.0]", goal="[2.0, 0.0]",
              sensor='{ kind = "lidar", beams = 8, range = 3.0 }')
    scene = write_scene(tmp_path, [r0], duration=2.0)
    out = tmp_path / "out"
    cmd = node.publisher("/r0/cmd_vel", TYPES["twist"])
    # Answer only once the tokens are read: until then, the world waits.
    answer = threading.Event()
    node.subscribe("/r0/odom", TYPES["odom"], lambda k, p, a: answer.is_set() and cmd(twist(0.1, 0.0)))
    proc = start_run(repo, scene, out, port)
    tokens = set()
    deadline = time.monotonic() + 60
    while proc.poll() is None and time.monotonic() < deadline:
        for reply in node.session.liveliness().get("@ros2_lv/0/**", timeout=1.0):
            if reply.ok is not None:
                tokens.add(str(reply.ok.key_expr))
        if any("/MP/" in t and "%r0%scan" in t for t in tokens):
            break
        time.sleep(0.05)
    answer.set()
    code, _, err = finish(proc)
    node.close()
    assert code == 0, err
    mine = [t for t in tokens if f"/{node.zid}/" not in t]
    zids = {t.split("/")[2] for t in mine}
    assert len(zids) == 1, mine
    z = zids.pop()
    assert all(c in "0123456789abcdef" for c in z)
    h = TS.hash_rihs01

    def ep(eid, kind, topic, ros_type, qos):
        return (f"@ros2_lv/0/{z}/0/{eid}/{kind}/%/%/mrsim_r0/{topic.replace('/', '%')}/"
                f"{dds(ros_type)}/{h(ros_type)}/{qos}")

    expected = {
        f"@ros2_lv/0/{z}/0/0/NN/%/%/mrsim_r0",
        ep(1, "MP", "/clock", TYPES["clock"], "2::,1:,:,:,,"),
        ep(2, "MP", "/tf", TYPES["tf"], "::,100:,:,:,,"),
        ep(3, "MP", "/r0/odom", TYPES["odom"], "::,10:,:,:,,"),
        ep(4, "MS", "/r0/cmd_vel", TYPES["twist"], "::,10:,:,:,,"),
        ep(5, "MP", "/r0/scan", TYPES["scan"], "2::,5:,:,:,,"),
    }
    assert set(mine) == expected, sorted(mine)
    stats = json.loads((out / "ros2.json").read_text())
    assert set(stats["tokens"]) == expected
    assert set(stats["keys"]) == {
        key(0, "/clock", TYPES["clock"]), key(0, "/tf", TYPES["tf"]),
        key(0, "/r0/odom", TYPES["odom"]), key(0, "/r0/cmd_vel", TYPES["twist"]),
        key(0, "/r0/scan", TYPES["scan"]),
    }


def test_the_type_hashes_mrsim_uses_are_rosbags_rihs01_hashes(repo):
    src = (repo / "crates" / "ros2" / "src" / "names.rs").read_text()
    for ros_type in TYPES.values():
        h = TS.hash_rihs01(ros_type)
        block = src.split(f'ros: "{ros_type}",', 1)
        assert len(block) == 2, ros_type
        assert f'hash: "{h}"' in block[1].split("};", 1)[0], (ros_type, h)


def test_bad_cmd_vel_is_counted_the_robot_brakes_and_the_world_runs_on(repo, tmp_path):
    port = free_port()
    node = RosNode(port)
    scene = write_scene(
        tmp_path, [dict(UNICYCLE, name='"r0"', start="[0.0, 0.0]", goal="[3.0, 0.0]")], duration=6.0
    )
    odoms = queue.Queue()
    node.subscribe("/r0/odom", TYPES["odom"], lambda k, p, a: odoms.put(TS.deserialize_cdr(p, TYPES["odom"])))
    cmd = node.publisher("/r0/cmd_vel", TYPES["twist"])
    clock_pub = node.publisher("/r0/cmd_vel", TYPES["clock"])
    Clock = TS.types["rosgraph_msgs/msg/Clock"]
    Time = TS.types["builtin_interfaces/msg/Time"]
    bad = [
        lambda: cmd(b"\x00\x01\x00\x00garbage"),
        lambda: cmd(twist(float("nan"), 0.0)),
        lambda: cmd(twist(1e12, 0.0)),
        lambda: clock_pub(bytes(TS.serialize_cdr(Clock(clock=Time(sec=1, nanosec=0)), TYPES["clock"]))),
    ]
    # Ticks 0-9 at 0.6 m/s (good), ticks 10-19 one bad sample each, tick 20
    # a flood of 300 good twists without attachments, then bad ones again.
    # In lockstep each tick takes the first sample after its /clock, so the
    # flood's first 200 (the samples of one second a robot may take) answer
    # the ticks that pass while they arrive, one or a few a tick: the robot
    # drives on until the 201st is seen, then brakes. The run goes on for 40
    # ticks after the flood, the tail of it braked.
    out = tmp_path / "out"
    proc = start_run(repo, scene, out, port)
    n = 0
    try:
        while proc.poll() is None:
            try:
                odoms.get(timeout=0.5)
            except queue.Empty:
                continue
            if n < 10:
                cmd(twist(0.6, 0.0))
            elif n == 20:
                for _ in range(300):
                    cmd(twist(0.6, 0.0), attachment=False)
            else:
                bad[n % len(bad)]()
            n += 1
    except BaseException:
        stop(proc)
        node.close()
        raise
    code, _, err = finish(proc)
    node.close()
    assert code == 0, err
    rows = [r for r in csv.DictReader((out / "trajectory.csv").open()) if r["body"] == "r0"]
    # The world ran every tick of the scene.
    assert float(rows[-1]["time"]) == pytest.approx(6.0, abs=0.11), rows[-1]
    speed = [math.hypot(float(r["vx"]), float(r["vy"])) for r in rows]
    shown = " ".join(f"{v:.2f}" for v in speed)
    # It got going on the good commands, and braked to a stop on the bad.
    assert max(speed[:12]) > 0.5, shown
    # It stands still over the last second of the run.
    assert max(speed[-10:]) < 0.05, shown
    braking = speed[12:21]
    assert all(b <= a + 1e-9 for a, b in zip(braking, braking[1:])), speed
    s = json.loads((out / "ros2.json").read_text())["robots"]["r0"]
    for k in ["undecodable", "non_finite", "absurd", "wrong_type", "flooded", "bad_attachment"]:
        assert s[k] > 0, (k, s)
    assert "not a geometry_msgs/msg/Twist" in err and "NaN" in err and "another type" in err, err


@pytest.mark.parametrize("mode", ["lockstep", "realtime"])
def test_one_ros2_agent_drives_ten_robots_every_one_joining_and_answering_every_tick(repo, tmp_path, mode):
    # Ten robots, one ROS 2 agent: it sends ten join requests, ten ready
    # commands and, each tick, ten commands to the world at once; every one
    # must arrive (none lost to a buffer sized for one robot per agent).
    port = free_port()
    node = RosNode(port)
    names = [f"r{i}" for i in range(10)]
    robots = [
        {"name": f'"{n}"', "planner": '"ros2"', "radius": 0.2, "max_speed": 1.0, "max_accel": 4.0,
         "start": f"[{-4.5 + i}, -3.0]", "goal": f"[{-4.5 + i}, 4.0]"}
        for i, n in enumerate(names)
    ]
    duration = 2.0
    dt = 0.1 if mode == "lockstep" else 0.05
    scene = write_scene(tmp_path, robots, duration=duration, mode=mode, dt=dt)
    cmds = {n: node.publisher(f"/{n}/cmd_vel", TYPES["twist"]) for n in names}
    answered = {n: 0 for n in names}

    def answer(n):
        def on(k, p, a):
            # Every odom answered at once: holonomic, 0.5 m/s along +y.
            cmds[n](twist(0.0, 0.0, 0.5))
            answered[n] += 1
        return on

    for n in names:
        node.subscribe(f"/{n}/odom", TYPES["odom"], answer(n))
    out = tmp_path / "out"
    proc = start_run(repo, scene, out, port)
    code, _, err = finish(proc, timeout=240)
    node.close()
    assert code == 0, err
    metrics = json.loads((out / "metrics.json").read_text())
    ticks = round(duration / dt)
    assert metrics["agents_lost"] == 0, err
    assert all(metrics["robots"][n]["lost"] == 0 for n in names), metrics["robots"]
    events = [json.loads(line) for line in (out / "events.jsonl").open()]
    joined = {e["robot"] for e in events if e["type"] == "agent_joined"}
    assert joined == set(names), events[:20]
    stats = json.loads((out / "ros2.json").read_text())["robots"]
    rows = list(csv.DictReader((out / "trajectory.csv").open()))
    for n in names:
        s = stats[n]
        assert s["accepted"] > 0 and s["undecodable"] == s["wrong_type"] == 0, (n, s)
        if mode == "lockstep":
            # Every tick answered, each with a cmd_vel sent after its /clock.
            assert s["ticks"] == ticks and s["missed"] == 0, (n, s)
        mine = [r for r in rows if r["body"] == n]
        assert float(mine[-1]["y"]) > -3.0 + 0.2, (n, mine[-1])
        assert answered[n] > 0


BAD_KINDS = ["undecodable", "non_finite", "absurd", "wrong_type", "flooded"]


@pytest.mark.parametrize("kind", BAD_KINDS)
def test_each_kind_of_bad_cmd_vel_alone_makes_the_robot_brake_while_the_world_runs_on(repo, tmp_path, kind):
    # Realtime: each tick the agent sends the robot's last cmd_vel. From
    # t = 1 s every odom is answered by a good twist (0.6 m/s) and right
    # after it one bad sample of `kind` (a flood: 300 good twists without
    # attachments a tick); if that sample were ignored the robot would go on
    # at 0.6 m/s, so its stopping is this kind's doing.
    port = free_port()
    node = RosNode(port)
    duration = 4.0
    scene = write_scene(
        tmp_path, [dict(UNICYCLE, name='"r0"', start="[-4.0, 0.0]", goal="[4.0, 0.0]")],
        duration=duration, mode="realtime",
    )
    cmd = node.publisher("/r0/cmd_vel", TYPES["twist"])
    other = node.publisher("/r0/cmd_vel", TYPES["clock"])
    Clock = TS.types["rosgraph_msgs/msg/Clock"]
    Time = TS.types["builtin_interfaces/msg/Time"]
    bad = {
        "undecodable": lambda: cmd(b"\x00\x01\x00\x00garbage"),
        "non_finite": lambda: cmd(twist(float("nan"), 0.0)),
        "absurd": lambda: cmd(twist(1e12, 0.0)),
        "wrong_type": lambda: other(bytes(TS.serialize_cdr(Clock(clock=Time(sec=1, nanosec=0)), TYPES["clock"]))),
        "flooded": lambda: [cmd(twist(0.6, 0.0), attachment=False) for _ in range(300)],
    }[kind]

    def on_odom(k, p, a):
        o = TS.deserialize_cdr(p, TYPES["odom"])
        t = o.header.stamp.sec + o.header.stamp.nanosec * 1e-9
        cmd(twist(0.6, 0.0))
        if t >= 1.0:
            bad()

    node.subscribe("/r0/odom", TYPES["odom"], on_odom)
    out = tmp_path / "out"
    proc = start_run(repo, scene, out, port)
    code, _, err = finish(proc)
    node.close()
    assert code == 0, err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["agents_lost"] == 0, metrics
    rows = [r for r in csv.DictReader((out / "trajectory.csv").open()) if r["body"] == "r0"]
    # The world ran to the end of the scene.
    assert float(rows[-1]["time"]) == pytest.approx(duration, abs=0.11), rows[-1]
    speed = {round(float(r["time"]), 6): math.hypot(float(r["vx"]), float(r["vy"])) for r in rows}
    before = [v for t, v in speed.items() if 0.5 <= t < 1.0]
    after = [v for t, v in speed.items() if t >= 2.5]
    assert before and max(before) > 0.5, speed
    assert after and max(after) < 0.05, speed
    s = json.loads((out / "ros2.json").read_text())["robots"]["r0"]
    assert s[kind] > 0, s
    assert all(s[k] == 0 for k in BAD_KINDS if k != kind), s
    assert s["accepted"] > 0, s


def test_a_subscriber_that_comes_after_the_map_was_published_still_gets_it(repo, tmp_path):
    # /map is transient local: published once, kept in the publisher's
    # cache. A subscriber declared later gets it the way rmw_zenoh's
    # transient-local subscriber does (eclipse-zenoh's AdvancedSubscriber
    # with history and late-publisher detection, as rmw_zenoh declares
    # it), while a volatile subscriber declared at the same time gets
    # nothing (the map is not published again).
    port = free_port()
    node = RosNode(port)
    maps = (repo / "scenarios" / "maps" / "office.yaml").resolve()
    scene = write_scene(
        tmp_path,
        [dict(UNICYCLE, name='"r0"', start="[-7.5, 5.5]", goal="[-7.0, 5.5]")],
        duration=6.0,
        extra=f'\n[map]\nfile = "{maps}"\n',
        arena="",
        mode="realtime",
    )
    clocks = []
    node.subscribe("/clock", TYPES["clock"], lambda k, p, a: clocks.append(1))
    out = tmp_path / "out"
    proc = start_run(repo, scene, out, port)
    late, volatile, tokens = [], [], set()
    try:
        # The run is under way: the map went out before its first tick.
        deadline = time.monotonic() + 60
        while len(clocks) < 10:
            assert proc.poll() is None and time.monotonic() < deadline, proc.poll()
            time.sleep(0.05)
        mk = key(0, "/map", TYPES["map"])
        for reply in node.session.liveliness().get(f"{mk}/@adv/**", timeout=2.0):
            if reply.ok is not None:
                tokens.add(str(reply.ok.key_expr))
        # Held: dropping a subscriber undeclares it.
        keep = [
            node.session.declare_subscriber(mk, lambda s: volatile.append(1)),
            zenoh.ext.declare_advanced_subscriber(
                node.session, mk,
                lambda s: late.append((str(s.key_expr), s.payload.to_bytes(),
                                       s.attachment.to_bytes() if s.attachment is not None else None)),
                history=zenoh.ext.HistoryConfig(detect_late_publishers=True, max_samples=1),
                recovery=zenoh.ext.RecoveryConfig(heartbeat=True),
                subscriber_detection=True,
            ),
        ]
        until = time.monotonic() + 10
        while not late and proc.poll() is None and time.monotonic() < until:
            time.sleep(0.05)
    except BaseException:
        stop(proc)
        node.close()
        raise
    code, _, err = finish(proc)
    node.close()
    assert code == 0, err
    assert late, err
    k, payload, att = late[0]
    assert k == mk
    g = TS.deserialize_cdr(payload, TYPES["map"])
    assert g.header.frame_id == "map" and len(g.data) == g.info.width * g.info.height > 0
    # rmw_zenoh's attachment: the first sample of the publisher.
    seq, stamp, gid = z_deserialize(tuple[Int64, Int64, bytes], zenoh.ZBytes(att))
    assert seq == 1 and len(gid) == 16
    assert volatile == [], "the map was published again"
    # The cache's token: zenoh-ext's form, under the map's key.
    assert len(tokens) == 1, tokens
    t = tokens.pop()
    assert t.startswith(f"{mk}/@adv/pub/") and t.endswith("/_"), t
    stats = json.loads((out / "ros2.json").read_text())
    assert t in stats["tokens"]
    assert any(x.endswith("%map/nav_msgs::msg::dds_::OccupancyGrid_/"
                          f"{TS.hash_rihs01(TYPES['map'])}/:1:,1:,:,:,,") for x in stats["tokens"]), stats["tokens"]
