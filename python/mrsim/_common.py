"""What the Gymnasium and PettingZoo environments share."""

import numpy as np
from gymnasium import spaces

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


def observation_space(sim, k):
    """The observation vector's space: bounded where the scene bounds it.
    With walls, every body and goal stays within their box (and the goals'
    and starts'), so an offset is at most its diagonal; a neighbour's radius
    is at most the largest body's; its presence flag is 0 or 1. Velocities
    have no bound of their own (a contact may push a body past its top
    speed): theirs is float32's largest value, what the vector can hold."""
    n = 4 + 6 * k
    largest_f32 = float(np.finfo(np.float32).max)
    low = np.full(n, -largest_f32, dtype=np.float32)
    high = np.full(n, largest_f32, dtype=np.float32)
    walls = np.asarray(sim.walls())
    offset = largest_f32
    if len(walls):
        points = np.concatenate([walls[:, :2], walls[:, 2:], sim.goals(), sim.positions()])
        offset = float(np.hypot(*(points.max(axis=0) - points.min(axis=0)))) * (1 + 1e-6)
    radii = np.asarray(sim.radii())
    largest = float(radii.max()) * (1 + 1e-6) if len(radii) else 0.0
    low[0:2], high[0:2] = -offset, offset
    for j in range(k):
        at = 4 + 6 * j
        low[at : at + 2], high[at : at + 2] = -offset, offset
        low[at + 4], high[at + 4] = 0.0, largest
        low[at + 5], high[at + 5] = 0.0, 1.0
    return spaces.Box(low, high, dtype=np.float32)


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
