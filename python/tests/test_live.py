"""mrsim.Agent: a Python program driving a robot of a real run (the world
and the other robots' agents as processes, over shared memory)."""

import gc
import json
import os
import subprocess
import sys
import threading
import time
import warnings
import weakref

import numpy as np
import pytest

import mrsim


def mrsim_binary(repo):
    exe = os.environ.get("MRSIM_BIN") or str(repo / "target" / "release" / "mrsim")
    if not os.path.exists(exe):
        pytest.fail(f"{exe} not found: build it first (cargo build --release)")
    return exe


def start_run(repo, tmp_path, run_id, *args):
    """`mrsim run crossing.toml` with robot a0 external, the others on ORCA."""
    cmd = [
        mrsim_binary(repo), "run", str(repo / "scenarios" / "crossing.toml"),
        "--set", "planner=orca", "--set", "robot.a0.planner=external",
        "--run", run_id, "--out", str(tmp_path / "run"), "--quiet", *args,
    ]  # fmt: skip
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finish(proc):
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, f"mrsim run failed ({proc.returncode}): {out}\n{err}"


def toward(obs):
    d = obs.goal - obs.position
    n = max(np.hypot(*d), 1e-9)
    return d / n * min(obs.max_speed, n)


def run_id(tag):
    return f"py{tag}{os.getpid()}"


def test_a_python_agent_drives_its_robot_through_a_lockstep_run(repo, tmp_path):
    proc = start_run(repo, tmp_path, run_id("lock"))
    try:
        with mrsim.Agent(run_id("lock"), "a0", timeout=60) as agent:
            assert agent.robot == "a0"
            ticks = []
            for obs in agent:
                ticks.append(obs.tick)
                assert obs.others_position.shape == (len(obs.others_radius), 2)
                assert set(obs.others_kind) <= {0}
                assert obs.walls.shape == (4, 4)
                agent.reply(toward(obs))
        finish(proc)
    finally:
        proc.kill()
    assert ticks[:3] == [0, 1, 2] and ticks == sorted(ticks)
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["robots"]["a0"]["reached_goal"]
    assert metrics["robots"]["a0"]["commands_rejected"] == 0


def test_a_late_reply_in_realtime_is_a_miss_and_the_run_goes_on(repo, tmp_path):
    proc = start_run(repo, tmp_path, run_id("rt"), "--mode", "realtime", "--set", "world.duration=2.0")
    try:
        with mrsim.Agent(run_id("rt"), "a0", timeout=60) as agent:
            late = None
            for obs in agent:
                if late is None and obs.tick >= 3:
                    late = obs.tick
                    time.sleep(0.35)  # three and a half ticks of 0.1 s
                try:
                    agent.reply(toward(obs))
                except RuntimeError:
                    pass  # a reply for a tick the world has left may be refused
        finish(proc)
    finally:
        proc.kill()
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["robots"]["a0"]["deadline_misses"] >= 1
    assert metrics["ticks"] >= 19


def test_in_realtime_an_agent_that_never_answers_again_misses_every_tick_and_the_run_goes_on(
    repo, tmp_path
):
    proc = start_run(repo, tmp_path, run_id("hang"), "--mode", "realtime", "--set", "world.duration=2.0")
    try:
        with mrsim.Agent(run_id("hang"), "a0", timeout=60) as agent:
            for obs in agent:
                if obs.tick == 3:
                    # As a planner stuck from here on: no answer until the
                    # run has ended.
                    finish(proc)
                    break
                agent.reply(toward(obs))
    finally:
        proc.kill()
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["ticks"] >= 19 and not metrics["interrupted"]
    # Every tick from the one left unanswered on is a miss.
    assert metrics["robots"]["a0"]["deadline_misses"] >= metrics["ticks"] - 4
    assert metrics["robots"]["b0"]["deadline_misses"] < metrics["ticks"] - 4


def test_joining_no_run_times_out_and_an_unknown_command_kind_is_refused(repo):
    with pytest.raises(RuntimeError):
        mrsim.Agent(run_id("none"), "a0", timeout=0.5)
    with pytest.raises(ValueError, match="velocity"):
        mrsim.Agent(run_id("none"), "a0", command="torque")


def test_a_bad_reply_is_refused_in_python_and_never_reaches_the_world(repo, tmp_path):
    proc = start_run(repo, tmp_path, run_id("bad"))
    refused = []
    try:
        with mrsim.Agent(run_id("bad"), "a0", timeout=60) as agent:
            for obs in agent:
                if obs.tick == 2:
                    for bad in [(np.nan, 0.0), (0.0, np.inf), (1.0, 2.0, 3.0), "go"]:
                        with pytest.raises(ValueError) as e:
                            agent.reply(bad)
                        refused.append(str(e.value))
                # The tick is still open: the good answer is taken.
                agent.reply(toward(obs))
        finish(proc)
    finally:
        proc.kill()
    assert len(refused) == 4
    assert "non-finite" in refused[0] and "non-finite" in refused[1], refused
    assert "expected two numbers" in refused[2] and "expected two numbers" in refused[3], refused
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["robots"]["a0"]["commands_rejected"] == 0
    assert metrics["robots"]["a0"]["reached_goal"]


def test_a_closed_agent_leaves_the_run_and_may_be_freed_on_any_thread(repo, tmp_path):
    proc = start_run(repo, tmp_path, run_id("close"), "--mode", "realtime", "--set", "world.duration=1.0")
    try:
        agent = mrsim.Agent(run_id("close"), "a0", timeout=60)
        with agent:
            obs = next(agent)
            agent.reply(toward(obs))
        # Leaving the block closed it: the run goes on without the robot
        # (its ticks are misses).
        assert agent.robot == ""
        assert list(agent) == []
        with pytest.raises(RuntimeError, match="nothing to answer"):
            agent.reply((0.0, 0.0))
        agent.close()  # again: nothing
        finish(proc)
    finally:
        proc.kill()
    # The last reference dropped on another thread (as the garbage collector
    # may do): nothing to warn about, nothing leaked.
    unraisable = []
    hook, sys.unraisablehook = sys.unraisablehook, unraisable.append
    try:
        with warnings.catch_warnings(record=True) as warned:
            warnings.simplefilter("always")
            held, gone = [agent], weakref.ref(agent)
            del agent, obs
            freer = threading.Thread(target=held.clear)
            freer.start()
            freer.join()
            assert gone() is None, "freed by the other thread"
            gc.collect()
    finally:
        sys.unraisablehook = hook
    assert unraisable == [] and warned == []
