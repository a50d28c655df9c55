"""mrsim from Python: your own planners, live agents, and multi-robot
navigation environments.

- :func:`mrsim.run`: an in-process lockstep run of a scenario in which
  robots may be driven by planners written in Python.
- :class:`mrsim.Agent`: drive a robot (``planner = "external"``) of a
  running world from Python, over shared memory.
- :func:`mrsim.sweep`: the runs of ``mrsim sweep`` on any
  ``concurrent.futures`` executor (a Dask cluster's), one row per run.
- :class:`mrsim.gym.NavEnv`: one learning robot among robots driven by
  mrsim's built-in planners (Gymnasium); :class:`mrsim.gym.NavVectorEnv`
  a batch of them stepped in one call; :class:`mrsim.gym.CrowdNavEnv`
  (``mrsim/CrowdNav-v0``) CrowdNav's episode and reward for its robot.
- :class:`mrsim.pettingzoo.ParallelNavEnv`: every robot a learning agent
  (PettingZoo parallel API).
- :class:`mrsim.Sim`: the stepping engine the environments are built on.
- :func:`mrsim.load_rows`: a run folder's CSV or JSONL file, read up to a
  cut run's torn last row (reported) and refusing any other bad row.
"""

import json
from importlib import resources as _resources
from pathlib import Path
from typing import NamedTuple, Optional

from ._mrsim import FILES, Agent, Observation, PlannerError, Sim, rerun_inproc, run_inproc
from ._folder import Rows, load_rows

__all__ = [
    "FILES",
    "KINDS",
    "Agent",
    "Observation",
    "PlannerError",
    "Rerun",
    "Rows",
    "Run",
    "Sim",
    "load_rows",
    "rerun",
    "run",
    "scenario_path",
    "sweep",
]


KINDS = ("robot", "obstacle", "person")
"""The body kinds by their code, as ``Sim.kinds()`` and
``Observation.others_kind`` give it: ``KINDS[2]`` is ``"person"``, a
pedestrian the world moves (trajectory.csv's ``kind`` column says the same
names)."""


def scenario_path(name: str = "circle-16") -> str:
    """The path of a scenario shipped with the package (``circle-16``)."""
    return str(_resources.files(__package__).joinpath("scenarios", f"{name}.toml"))


class Run(NamedTuple):
    """What :func:`run` gives back."""

    metrics: dict
    """metrics.json of the run, as a dict."""
    dir: Path
    """The run folder (trajectory.csv, events.jsonl, metrics.json, ...)."""


def run(scenario=None, planners=None, out=None, set=(), render=False, plan_timeout=None) -> Run:
    """Runs ``scenario`` (a path; None: the built-in demo) in this process,
    in lockstep, and returns its metrics and run folder.

    ``planners`` maps names to Python planners: a class (or any callable)
    called with the robot's ``params`` as a dict, whose instances have
    ``plan(observation)`` returning two numbers, a velocity (m/s), or a force
    (N) if the class sets ``command = "force"``, or a car's speed (m/s) and
    steering angle (rad) if it sets ``command = "ackermann"`` (any other
    robot brakes on it; a car's velocity or force goes through the tracking
    controller). A robot uses one with
    ``planner = "NAME"`` in the scenario or ``set=["robot.r0.planner=NAME"]``.
    ``set`` takes ``KEY=VALUE`` overrides as ``mrsim run --set``; ``out`` the
    run folder (default: a new one under ``runs/``); ``plan_timeout`` the
    longest one ``plan`` call may take, s.

    A planner that raises, returns something else than two finite numbers,
    or takes longer than ``plan_timeout`` (watched while it runs: one that
    never returns too) stops the run at that tick, with
    the outputs so far written: :class:`PlannerError` names the robot and
    the tick (attributes ``robot``, ``tick``, ``dir``).
    """
    folder = run_inproc(
        None if scenario is None else str(scenario),
        dict(planners or {}),
        None if out is None else str(out),
        list(set),
        render,
        plan_timeout,
    )
    folder = Path(folder)
    metrics = json.loads((folder / FILES["metrics"]).read_text())
    return Run(metrics, folder)


class Rerun(NamedTuple):
    """What :func:`rerun` gives back."""

    metrics: dict
    """metrics.json of the rerun, as a dict."""
    dir: Path
    """The rerun's folder."""
    not_deterministic: list
    """``(robot, planner)`` pairs whose planner is not built in (a Python
    planner, say): not known to be deterministic, the reason the rerun may
    differ from the recorded run."""
    cut: Optional[str] = None
    """``None`` for a recorded run that ended; for one that was cut (its
    world killed), where the rerun stopped (the trajectory's last whole
    tick) and which files end at the cut."""


def rerun(run_dir, out=None, set=(), planners=None, render=False) -> Rerun:
    """Runs the recorded run in folder ``run_dir`` again, in this process
    and in lockstep, with the timing it recorded (``mrsim rerun``): every
    planner reads the snapshots it read and every command is sent when it
    was sent, so a realtime run's trajectory comes out byte for byte.

    ``set`` takes ``KEY=VALUE`` overrides on top of the recorded run's, a
    counterfactual under the same timing (another planner for one robot,
    say); ``planners`` names Python planners as :func:`run` does; ``out``
    the rerun's folder (default: a new one under ``runs/``). A folder that
    is not a recorded run, or whose scenario file no longer gives the
    scenario it recorded, raises ``ValueError``.
    """
    folder, unsure, cut = rerun_inproc(
        str(run_dir),
        None if out is None else str(out),
        list(set),
        dict(planners or {}),
        render,
    )
    folder = Path(folder)
    metrics = json.loads((folder / FILES["metrics"]).read_text())
    return Rerun(metrics, folder, [tuple(p) for p in unsure], cut)


from ._sweep import sweep  # noqa: E402

# Last: the Gymnasium module uses the names above; importing it registers
# the id mrsim/Nav-v0 (``gymnasium.make("mrsim/Nav-v0")``).
from . import gym as _gym  # noqa: E402, F401
