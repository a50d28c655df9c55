"""`mrsim.rerun`: a realtime run made by the `mrsim` program, replayed in
Python from its recorded timing, byte for byte; a counterfactual with a
Python planner names it as the reason a replay may differ."""

import json
import subprocess

import pytest

import mrsim
from conftest import built_mrsim

SCENE = """name = "timed-pair"
[world]
dt = 0.1
substeps = 10
duration = 2.0
mode = "realtime"
seed = 3

[defaults]
radius = 0.3
max_speed = 1.0
max_accel = 4.0
planner = "orca"

[defaults.timing]
compute = { model = "uniform", min_ms = 30.0, max_ms = 180.0 }
command_loss = 0.05

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [5.0, 0.0]

[[robot]]
name = "r1"
start = [5.0, 0.2]
goal = [0.0, 0.2]
"""


class Straight:
    """Heads for the goal at half speed (orca would go at full speed)."""

    def __init__(self, params):
        pass

    def plan(self, obs):
        gx, gy = obs.goal[0] - obs.position[0], obs.goal[1] - obs.position[1]
        d = max((gx * gx + gy * gy) ** 0.5, 1e-9)
        return (0.5 * gx / d, 0.5 * gy / d)


@pytest.fixture
def recorded(repo, tmp_path):
    scene = tmp_path / "pair.toml"
    scene.write_text(SCENE)
    out = tmp_path / "realtime"
    subprocess.run(
        [built_mrsim(repo), "run", str(scene), "--out", str(out), "--quiet", "--no-report"],
        check=True,
    )
    return out


def test_a_realtime_run_reruns_in_python_byte_for_byte(recorded, tmp_path):
    robots = json.loads((recorded / "metrics.json").read_text())["robots"]
    misses = {name: r["deadline_misses"] for name, r in robots.items()}
    assert sum(misses.values()) > 0, "the recorded run had no misses to replay"
    again = mrsim.rerun(recorded, out=tmp_path / "again")
    assert again.not_deterministic == []
    assert (again.dir / "trajectory.csv").read_bytes() == (recorded / "trajectory.csv").read_bytes()
    assert {n: r["deadline_misses"] for n, r in again.metrics["robots"].items()} == misses


def test_a_counterfactual_with_a_python_planner_names_it(recorded, tmp_path):
    cf = mrsim.rerun(
        recorded,
        out=tmp_path / "cf",
        set=["robot.r1.planner=straight"],
        planners={"straight": Straight},
    )
    assert cf.not_deterministic == [("r1", "straight")]
    assert (cf.dir / "trajectory.csv").read_bytes() != (recorded / "trajectory.csv").read_bytes()


def test_a_folder_that_is_not_a_recorded_run_is_refused(tmp_path):
    with pytest.raises(ValueError, match="cannot rerun"):
        mrsim.rerun(tmp_path)
