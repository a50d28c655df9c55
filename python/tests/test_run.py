"""mrsim.run with planners written in Python, and what a bad one does."""

import numpy as np
import pytest

import mrsim


class Toward:
    """Heads straight for the goal at its speed (params: speed)."""

    def __init__(self, params):
        self.speed = params.get("speed", 1.0)

    def plan(self, obs):
        d = obs.goal - obs.position
        n = max(np.hypot(*d), 1e-9)
        return d / n * min(self.speed, obs.max_speed, n)


def crossing(repo):
    return repo / "scenarios" / "crossing.toml"


def test_a_python_planner_drives_its_robot_to_the_goal_beside_built_in_ones(repo, tmp_path):
    seen = []

    class Recording(Toward):
        def plan(self, obs):
            seen.append((obs.tick, obs.others_position.shape, obs.walls.shape))
            return super().plan(obs)

    result = mrsim.run(
        crossing(repo),
        planners={"toward": Recording},
        set=["planner=orca", "robot.a3.planner=toward", "robot.a3.params.speed=0.8"],
        out=tmp_path / "run",
    )
    assert result.dir == tmp_path / "run"
    assert (result.dir / "trajectory.csv").is_file()
    assert result.metrics["robots"]["a3"]["reached_goal"]
    assert result.metrics["robots"]["b0"]["reached_goal"]
    ticks = [t for t, _, _ in seen]
    assert ticks[:3] == [0, 1, 2]
    # The walls are the arena's four sides; the others are n x 2.
    assert seen[0][2] == (4, 4) and seen[0][1][1] == 2


def test_the_robots_params_reach_the_planner_and_force_commands_are_applied(repo, tmp_path):
    got = {}

    class Push:
        command = "force"

        def __init__(self, params):
            got.update(params)

        def plan(self, obs):
            d = obs.goal - obs.position
            return 2.0 * d / max(np.hypot(*d), 1e-9) - 2.0 * obs.velocity

    result = mrsim.run(
        crossing(repo),
        planners={"push": Push},
        set=["planner=orca", "robot.a0.planner=push", "robot.a0.params.gain=3"],
        out=tmp_path / "run",
    )
    assert got == {"gain": 3.0}
    assert result.metrics["robots"]["a0"]["reached_goal"]


def failing(repo, tmp_path, plan, **kw):
    class P:
        def __init__(self, params):
            pass

    P.plan = lambda self, obs: plan(obs)
    with pytest.raises(mrsim.PlannerError) as e:
        mrsim.run(
            crossing(repo),
            planners={"p": P},
            set=["robot.b1.planner=p"],
            out=tmp_path / "run",
            **kw,
        )
    return e.value


def test_a_planner_that_raises_stops_the_run_naming_robot_tick_and_exception(repo, tmp_path):
    def plan(obs):
        if obs.tick == 7:
            raise KeyError("lost my map")
        return (0.0, 0.0)

    e = failing(repo, tmp_path, plan)
    assert (e.robot, e.tick) == ("b1", 7)
    assert "KeyError" in str(e) and "lost my map" in str(e)
    # The outputs so far are written.
    lines = (tmp_path / "run" / "trajectory.csv").read_text().splitlines()
    assert len(lines) > 7


def test_a_planner_that_returns_nan_stops_the_run(repo, tmp_path):
    e = failing(repo, tmp_path, lambda obs: (np.nan, 0.0) if obs.tick == 3 else (0.0, 0.0))
    assert (e.robot, e.tick) == ("b1", 3)
    assert "non-finite" in str(e)


@pytest.mark.parametrize("answer", [(1.0, 2.0, 3.0), "go", None, np.zeros((1, 2))])
def test_a_planner_that_returns_the_wrong_shape_stops_the_run(repo, tmp_path, answer):
    e = failing(repo, tmp_path, lambda obs: answer)
    assert (e.robot, e.tick) == ("b1", 0)
    assert "expected two numbers" in str(e)


def test_a_planner_that_never_returns_stops_the_run_after_the_limit(repo, tmp_path):
    import json
    import threading

    # The limit is on the wall clock: 1 s is many times what an answer of
    # (0, 0) takes on a busy machine, GIL waits included.
    def plan(obs):
        if obs.tick == 2:
            threading.Event().wait()  # never set: the call never returns
        return (0.0, 0.0)

    e = failing(repo, tmp_path, plan, plan_timeout=1.0)
    assert (e.robot, e.tick) == ("b1", 2)
    assert "did not return within the limit of 1.000 s" in str(e)
    # The outputs so far are written: the ticks before, and the metrics.
    lines = (tmp_path / "run" / "trajectory.csv").read_text().splitlines()
    assert len(lines) > 2 * 8
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["interrupted"] and metrics["ticks"] >= 2


def test_a_non_positive_plan_timeout_is_refused(repo, tmp_path):
    for t in [0.0, -1.0, float("nan")]:
        with pytest.raises(ValueError, match="plan_timeout"):
            mrsim.run(crossing(repo), plan_timeout=t, out=tmp_path / "run")


def test_a_planner_that_returns_infinity_stops_the_run(repo, tmp_path):
    e = failing(repo, tmp_path, lambda obs: (0.0, -np.inf) if obs.tick == 4 else (0.0, 0.0))
    assert (e.robot, e.tick) == ("b1", 4)
    assert "non-finite" in str(e)


def test_a_planner_class_without_plan_is_refused_before_the_run(repo, tmp_path):
    class NoPlan:
        def __init__(self, params):
            pass

    with pytest.raises(ValueError, match="NoPlan has no plan"):
        mrsim.run(crossing(repo), planners={"noplan": NoPlan}, set=["robot.a0.planner=noplan"],
                  out=tmp_path / "run")
    assert not (tmp_path / "run").exists()


def test_a_planner_whose_constructor_raises_is_refused_before_the_run(repo, tmp_path):
    class Broken:
        def __init__(self, params):
            raise ValueError("needs a map")

    with pytest.raises(ValueError, match="needs a map"):
        mrsim.run(crossing(repo), planners={"broken": Broken}, set=["robot.a0.planner=broken"],
                  out=tmp_path / "run")
    assert not (tmp_path / "run").exists()


def test_an_unknown_planner_name_is_refused_naming_the_known_ones(repo, tmp_path):
    with pytest.raises(ValueError, match="toward"):
        mrsim.run(crossing(repo), planners={"toward": Toward}, set=["robot.a0.planner=towards"],
                  out=tmp_path / "run")


def test_a_python_planner_on_a_unicycle_sees_its_heading_and_its_laser_scan(repo, tmp_path):
    seen = []

    class Looking:
        """Asks to go north, across its heading: the unicycle must turn."""

        def __init__(self, params):
            pass

        def plan(self, obs):
            seen.append(
                (obs.kinematics, obs.heading, obs.scan_ranges, obs.scan_angle_min,
                 obs.scan_angle_increment)
            )
            return np.array([0.0, 0.5])

    result = mrsim.run(
        repo / "scenarios" / "lidar-demo.toml",
        planners={"looking": Looking},
        set=["robot.scout.planner=looking", "world.duration=2"],
        out=tmp_path / "run",
    )
    assert result.metrics["ticks"] > 0
    kinematics, heading, ranges, angle_min, increment = seen[0]
    assert kinematics == "unicycle"
    # A unicycle starts facing its goal: from (-4, -1) to (4, 1).
    assert heading == pytest.approx(np.arctan2(2.0, 8.0), abs=1e-9)
    assert ranges.shape == (360,)
    assert increment == pytest.approx(2 * np.pi / 360)
    # The beam pointing straight back (in the robot's frame) meets the
    # room's west wall, x = -5, 1 m behind the start along x: 1 / cos(heading)
    # away, give or take the 1 cm noise.
    back = np.argmin(np.cos(angle_min + increment * np.arange(360)))
    assert ranges[back] == pytest.approx(1.0 / np.cos(heading), abs=0.05)
    # Asked to go north, it turns left: the heading is the world's.
    assert seen[-1][1] > heading + 0.1


def test_a_python_planner_sees_a_turned_rectangle_obstacle_with_its_vertices(repo, tmp_path):
    seen = []

    class Standing:
        def __init__(self, params):
            pass

        def plan(self, obs):
            seen.append(
                (obs.others_id, obs.others_radius, obs.others_heading, obs.others_vertices)
            )
            return np.zeros(2)

    scenario = tmp_path / "box.toml"
    # A 2 x 1 box at (3, 0) turned a quarter turn (its length along y) and a
    # disc post behind the robot.
    scenario.write_text(
        """
[world]
duration = 0.3
[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [0.0, 3.0]
planner = "standing"
[[obstacle]]
name = "box"
start = [3.0, 0.0]
shape = { kind = "rectangle", length = 2.0, width = 1.0 }
heading_deg = 90
motion = { model = "static" }
[[obstacle]]
name = "post"
start = [-3.0, 0.0]
radius = 0.4
motion = { model = "static" }
"""
    )
    mrsim.run(scenario, planners={"standing": Standing}, out=tmp_path / "run")
    ids, radius, heading, vertices = seen[0]
    assert list(ids) == [1, 2]
    assert radius == pytest.approx([np.sqrt(1.25), 0.4])
    assert heading == pytest.approx([np.pi / 2, 0.0])
    assert isinstance(vertices, list) and len(vertices) == 2
    box, post = vertices
    # Its corners (-1, -0.5), (1, -0.5), (1, 0.5), (-1, 0.5) in its frame,
    # turned a quarter turn about (3, 0), counter-clockwise.
    assert box.shape == (4, 2)
    assert box == pytest.approx(np.array([[3.5, -1.0], [3.5, 1.0], [2.5, 1.0], [2.5, -1.0]]))
    # A disc has none.
    assert post.shape == (0, 2)


CAR = """
[world]
dt = 0.1
duration = 60.0

[[robot]]
name = "car"
start = [0.0, 0.0]
goal = [30.0, 0.0]
planner = "pursuit"
kinematics = "ackermann"
shape = { kind = "rectangle", length = 4.6, width = 1.6 }
wheelbase = 3.0
max_steering_deg = 30
max_speed = 4.0
goal_tolerance = 1.0
"""


def test_a_python_planner_drives_a_car_by_its_speed_and_steering(tmp_path):
    seen = []

    class Pursuit:
        """A full turn at full lock left, then pure pursuit of the goal."""

        command = "ackermann"

        def __init__(self, params):
            pass

        def plan(self, obs):
            seen.append((obs.kinematics, obs.wheelbase, obs.max_steering, obs.radius, obs.steering))
            if obs.time < 12.0:
                return (2.0, obs.max_steering)
            d = obs.goal - obs.position
            dist = np.hypot(*d)
            alpha = (np.arctan2(d[1], d[0]) - obs.heading + np.pi) % (2 * np.pi) - np.pi
            steering = np.arctan(2.0 * obs.wheelbase * np.sin(alpha) / max(dist, 1e-9))
            return (min(obs.max_speed, dist), steering)

    (tmp_path / "car.toml").write_text(CAR)
    result = mrsim.run(tmp_path / "car.toml", planners={"pursuit": Pursuit}, out=tmp_path / "run")
    assert result.metrics["robots"]["car"]["reached_goal"]
    kinematics, wheelbase, max_steering, radius, _ = seen[0]
    assert (kinematics, wheelbase) == ("ackermann", 3.0)
    assert abs(max_steering - np.radians(30)) < 1e-12
    # A planner of the car's own commands sees the car, not the tracking
    # controller's disc enlarged by its bound.
    assert abs(radius - np.hypot(2.3, 0.8)) < 1e-9
    # The wheels came to full lock at the world's rate, and the car turned
    # with them: its heading in trajectory.csv went past a quarter turn.
    assert max(s for *_, s in seen) == pytest.approx(np.radians(30))
    rows = (result.dir / "trajectory.csv").read_text().splitlines()
    assert rows[0].endswith(",theta")
    assert max(float(r.split(",")[-1]) for r in rows[1:]) > np.pi / 2


def test_a_python_planner_sees_people_as_bodies_of_kind_person(repo, tmp_path):
    kinds = set()

    class Recording(Toward):
        def plan(self, obs):
            kinds.update(mrsim.KINDS[k] for k in obs.others_kind)
            return super().plan(obs)

    result = mrsim.run(
        repo / "scenarios" / "people" / "crossing.toml",
        planners={"toward": Recording},
        set=["robot.r0.planner=toward", "world.duration=5"],
        out=tmp_path / "run",
    )
    assert (result.dir / "trajectory.csv").is_file()
    # r0 senses the other robots and the people walking the hall.
    assert kinds == {"robot", "person"}
