"""What the Gymnasium and PettingZoo environments share."""

import numpy as np

from . import scenario_path
from ._mrsim import Sim

ACTIONS = ("velocity", "force")


def make_sim(scenario, learners, overrides, k):
    """A :class:`Sim` of ``scenario`` (None: the shipped circle-16)."""
    path = scenario_path() if scenario is None else str(scenario)
    return Sim(path, learners, list(overrides), k)


def robot_names(scenario, overrides):
    """Every robot's name in ``scenario``."""
    return make_sim(scenario, [], overrides, 0).robot_names


def action_bounds(sim, action):
    """Per learner, the largest component of an action that matters."""
    if action not in ACTIONS:
        raise ValueError(f"action must be one of {ACTIONS}, got {action!r}")
    return sim.max_speed if action == "velocity" else sim.max_force


def horizon(sim):
    """Ticks in the scenario's duration."""
    return int(round(sim.duration / sim.dt))


class Rewards:
    """Reward = progress x (metres gained towards the goal this tick)
    + collision x (collisions started this tick) + arrival (once, when the
    goal is reached: within tolerance for goal_hold_ticks ticks)."""

    def __init__(self, progress, collision, arrival):
        self.progress = float(progress)
        self.collision = float(collision)
        self.arrival = float(arrival)

    def __call__(self, before, after, collisions, reached_now):
        return (
            self.progress * (before - after)
            + self.collision * collisions
            + self.arrival * reached_now
        )


def scaled(action, bound):
    """A normalised action ([-1, 1] per axis, clipped) as a command of at
    most ``bound`` per axis; refuses NaN, infinities and other shapes."""
    a = np.asarray(action, dtype=np.float64)
    if a.shape != (2,):
        raise ValueError(f"an action is 2 numbers, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"non-finite action {a.tolist()}")
    return np.clip(a, -1.0, 1.0) * bound


def distances(sim):
    """Each learner's distance to its goal now."""
    p = sim.positions()[sim.learner_indices]
    return np.hypot(*(sim.goals() - p).T)
