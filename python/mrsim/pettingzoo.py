"""PettingZoo parallel environment: every robot of a scenario a learning
agent, each with :class:`mrsim.gym.NavEnv`'s observation and action spaces
(normalised actions) and rewards. An agent leaves at its goal or at a collision (its robot then
brakes and stays in the world as a body); all leave at the duration."""

import functools

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from . import _common
from ._render import Drawn


class ParallelNavEnv(Drawn, ParallelEnv):
    """Every robot of ``scenario`` (default: the shipped circle-16, or
    ``set=["generate.count=64"]`` for 64) is an agent named as its robot."""

    metadata = {"render_modes": ["rgb_array"], "name": "mrsim_nav_v0", "render_fps": 10}

    def __init__(
        self,
        scenario=None,
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
        self._sim = _common.make_sim(scenario, None, set, k)
        self.possible_agents = list(self._sim.learner_names)
        self.agents = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self._bounds = _common.action_bounds(self._sim, action)
        self._force = action == "force"
        self._action_spaces = {
            a: spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32) for a in self.possible_agents
        }
        self._observation_spaces = {
            a: _common.observation_space(self._sim, k)
            for a in self.possible_agents
        }
        self.rewards_of = _common.Rewards(reward_progress, reward_collision, reward_arrival)
        self.render_mode = render_mode
        self._render_size = render_size
        n = len(self.possible_agents)
        self._obs = np.zeros((n, self._sim.obs_size), dtype=np.float32)
        self._actions = np.zeros((n, 2), dtype=np.float64)
        self._distance = np.zeros(n)
        self._reached = np.zeros(n, dtype=bool)
        self._gone = np.zeros(n, dtype=bool)
        self._horizon = _common.horizon(self._sim)
        self._rng = np.random.default_rng()
        self._canvas = None

    @functools.lru_cache(maxsize=None)
    def observation_space(self, agent):
        return self._observation_spaces[agent]

    @functools.lru_cache(maxsize=None)
    def action_space(self, agent):
        return self._action_spaces[agent]

    def reset(self, seed=None, options=None):
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        episode_seed = seed if seed is not None else int(self._rng.integers(0, 2**62))
        self._sim.reset(episode_seed)
        self._sim.observe(self._obs)
        self._distance = _common.distances(self._sim)
        self._reached[:] = False
        self.agents = list(self.possible_agents)
        self._canvas = None
        obs = {a: self._obs[i].copy() for i, a in enumerate(self.agents)}
        infos = {a: {"distance_to_goal": float(self._distance[i])} for i, a in enumerate(self.agents)}
        return obs, infos

    def step(self, actions):
        # Agents that left (and any without an action) brake.
        self._actions[:] = 0.0
        for a, act in actions.items():
            i = self._index.get(a)
            if i is not None:
                self._actions[i] = _common.scaled(act, self._bounds[i])
        self._gone[:] = True
        for a in self.agents:
            self._gone[self._index[a]] = False
        collisions, distance, at_goal, reached = self._sim.step(
            self._actions, self._force, self._gone
        )
        self._sim.observe(self._obs)
        reached_now = reached & ~self._reached
        rewards_all = self.rewards_of(self._distance, distance, collisions, reached_now)
        self._distance = distance
        self._reached = reached.copy()
        truncated_all = self._sim.tick >= self._horizon
        obs, rewards, terms, truncs, infos = {}, {}, {}, {}, {}
        tick, time = self._sim.tick, self._sim.time
        for a in self.agents:
            i = self._index[a]
            term = bool(reached[i]) or int(collisions[i]) > 0
            obs[a] = self._obs[i].copy()
            rewards[a] = float(rewards_all[i])
            terms[a] = term
            truncs[a] = truncated_all and not term
            infos[a] = {
                "collisions": int(collisions[i]),
                "distance_to_goal": float(distance[i]),
                "at_goal": bool(at_goal[i]),
                "reached": bool(reached[i]),
                "tick": tick,
                "time": time,
            }
        self.agents = [a for a in self.agents if not (terms[a] or truncs[a])]
        return obs, rewards, terms, truncs, infos

    def close(self):
        pass

    @property
    def sim(self):
        """The underlying :class:`mrsim.Sim`."""
        return self._sim
