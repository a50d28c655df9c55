"""Gymnasium environment: one learning robot among robots driven by mrsim's
built-in planners.

Observation (float32, ``4 + 6 k``): in the learner's frame (origin at its
centre, axes parallel to the world's), ``[goal_dx, goal_dy, vx, vy]``, then
for each of the ``k`` nearest other bodies (robots and obstacles within its
sensing range, nearest first) ``[dx, dy, dvx, dvy, radius, 1]`` (position and
velocity relative to the learner's), zeros for missing neighbours. Bounded
where the scene bounds it (offsets by the walls' box, radii, the flag).
Action: two numbers in [-1, 1] (clipped), scaled to a velocity (times the
robot's max_speed) or a force (times mass x max_accel + damping x
max_speed), as the constructor's ``action`` says; the world applies it
through the robot's actuator limits as it would an agent's command.
"""

import gymnasium
import numpy as np
from gymnasium import spaces

from . import _common
from ._render import Canvas


class NavEnv(gymnasium.Env):
    """One learner in a scenario (default: 16 robots on a circle, the other
    15 on ORCA). ``terminated`` at the goal (the world's goal test) or at a
    collision; ``truncated`` at the scenario's duration. Episodes are
    identical for one seed."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        scenario=None,
        learner=None,
        set=(),
        k=8,
        action="velocity",
        reward_progress=1.0,
        reward_collision=-10.0,
        reward_arrival=10.0,
        render_mode=None,
        render_size=256,
    ):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        if learner is None:
            learner = _common.robot_names(scenario, set)[0]
        self._sim = _common.make_sim(scenario, [learner], set, k)
        self.learner = learner
        self._scenario, self._set, self._k = scenario, tuple(set), k
        self._bound = float(_common.action_bounds(self._sim, action)[0])
        self._force = action == "force"
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.observation_space = _common.observation_space(self._sim, k)
        self.rewards = _common.Rewards(reward_progress, reward_collision, reward_arrival)
        self.render_mode = render_mode
        self._render_size = render_size
        self._obs = np.zeros((1, self._sim.obs_size), dtype=np.float32)
        self._horizon = _common.horizon(self._sim)
        self._distance = 0.0
        self._reached = False
        self._canvas = None

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        # Without a seed the next episode's comes from the env's generator,
        # so a seeded sequence of resets repeats too.
        episode_seed = seed if seed is not None else int(self.np_random.integers(0, 2**62))
        self._sim.reset(episode_seed)
        self._sim.observe(self._obs)
        self._distance = float(_common.distances(self._sim)[0])
        self._reached = False
        self._canvas = None
        return self._obs[0].copy(), self._info(0, self._distance, False, False)

    def step(self, action):
        a = _common.scaled(action, self._bound).reshape(1, 2)
        collisions, distance, at_goal, reached = self._sim.step(a, self._force)
        self._sim.observe(self._obs)
        d = float(distance[0])
        reached_now = bool(reached[0]) and not self._reached
        self._reached = bool(reached[0])
        reward = self.rewards(self._distance, d, int(collisions[0]), reached_now)
        self._distance = d
        terminated = self._reached or int(collisions[0]) > 0
        truncated = self._sim.tick >= self._horizon and not terminated
        info = self._info(int(collisions[0]), d, bool(at_goal[0]), self._reached)
        return self._obs[0].copy(), float(reward), terminated, truncated, info

    def _info(self, collisions, distance, at_goal, reached):
        return {
            "collisions": collisions,
            "distance_to_goal": distance,
            "at_goal": at_goal,
            "reached": reached,
            "tick": self._sim.tick,
            "time": self._sim.time,
        }

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._canvas is None:
            self._canvas = Canvas(self._sim, self._render_size)
        return self._canvas.draw(self._sim)

    @property
    def sim(self):
        """The underlying :class:`mrsim.Sim` (positions, velocities, walls)."""
        return self._sim


# Registered on import (``import mrsim`` imports this module):
# ``gymnasium.make("mrsim/Nav-v0", **kwargs)`` builds a NavEnv with the
# constructor's keyword arguments.
gymnasium.register(id="mrsim/Nav-v0", entry_point="mrsim.gym:NavEnv")
