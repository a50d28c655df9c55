"""Gymnasium environment: one learning robot among robots driven by mrsim's
built-in planners.

Observation (float32, ``4 + 6 k``): in the learner's frame (origin at its
centre, axes parallel to the world's), ``[goal_dx, goal_dy, vx, vy]``, then
for each of the ``k`` nearest other bodies (robots and obstacles within its
sensing range, nearest first) ``[dx, dy, dvx, dvy, radius, 1]`` (position and
velocity relative to the learner's; a rectangle's or polygon's radius is its
circumscribed one), zeros for missing neighbours. Bounded
where the scene bounds it (offsets by the walls' box, radii, the flag).
Action: two numbers in [-1, 1] (clipped), scaled to a velocity (times the
robot's max_speed) or a force (times mass x max_accel + damping x
max_speed), as the constructor's ``action`` says; the world applies it
through the robot's actuator limits as it would an agent's command.
"""

import os
import tempfile

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from . import _common
from ._mrsim import Sim, VecSim, crowdnav_scene
from ._render import Canvas, Drawn


class NavEnv(Drawn, gymnasium.Env):
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

    @property
    def sim(self):
        """The underlying :class:`mrsim.Sim` (positions, velocities, walls)."""
        return self._sim


class _EnvView:
    """One environment of a :class:`NavVectorEnv`, as :class:`Canvas` reads
    a :class:`mrsim.Sim`."""

    def __init__(self, vec, i):
        self._vec, self._i = vec, i

    def positions(self):
        return self._vec.positions(self._i)

    def goals(self):
        return self._vec.goals(self._i)

    def walls(self):
        return self._vec.walls(self._i)

    def radii(self):
        return self._vec.radii(self._i)

    def kinds(self):
        return self._vec.kinds(self._i)

    @property
    def learner_indices(self):
        return self._vec.learner_indices


class NavVectorEnv(VectorEnv):
    """``num_envs`` :class:`NavEnv` environments stepped together: one call
    into mrsim's Rust engine steps all of them with Python's GIL released,
    spread over ``num_threads`` threads (default: the cores this process
    may use), writing straight into numpy arrays. The other keyword
    arguments are :class:`NavEnv`'s, and environment ``i`` gives the very
    episodes a NavEnv gives for the same seed.

    Autoreset is Gymnasium 1.x's default, next-step
    (``metadata["autoreset_mode"]``): the step after an environment's
    episode ended resets it (its action ignored) and returns its first
    observation with reward 0. ``reset(seed=s)`` seeds environment ``i``
    with ``s + i`` (or ``seed[i]`` for a list), as Gymnasium's
    SyncVectorEnv does; later episodes draw their seeds from each
    environment's generator, as NavEnv does. ``reset(options={"reset_mask":
    mask})`` resets only the environments marked.

    Info: arrays ``collisions``, ``distance_to_goal``, ``at_goal``,
    ``reached``, ``tick``, ``time`` (NavEnv's keys), each with its
    ``_key`` mask (always all true: every environment reports every key).
    ``gymnasium.make_vec("mrsim/Nav-v0", num_envs=N, ...)`` builds one.
    """

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": 10,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    _INFO = ("collisions", "distance_to_goal", "at_goal", "reached", "tick", "time")
    _INFO_TYPES = (np.int64, np.float64, np.bool_, np.bool_, np.uint64, np.float64)

    def __init__(
        self,
        num_envs=1,
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
        num_threads=None,
    ):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs must be a whole number of at least 1, got {num_envs!r}")
        if num_threads is None:
            try:
                num_threads = len(os.sched_getaffinity(0))
            except AttributeError:
                num_threads = os.cpu_count() or 1
        if learner is None:
            learner = _common.robot_names(scenario, set)[0]
        probe = _common.make_sim(scenario, [learner], set, k)
        bound = float(_common.action_bounds(probe, action)[0])
        rewards = _common.Rewards(reward_progress, reward_collision, reward_arrival)
        self.num_envs = int(num_envs)
        self.learner = learner
        self._vec = VecSim(
            _common.scenario_path() if scenario is None else str(scenario),
            learner,
            list(set),
            k,
            self.num_envs,
            action == "force",
            bound,
            _common.horizon(probe),
            rewards.progress,
            rewards.collision,
            rewards.arrival,
            int(num_threads),
        )
        self.rewards = rewards
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.single_observation_space = _common.observation_space(probe, k)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.render_mode = render_mode
        self._render_size = render_size
        self._canvases = [None] * self.num_envs
        self._obs_size = probe.obs_size
        self._rngs = [None] * self.num_envs
        self._seeds = np.zeros(self.num_envs, dtype=np.uint64)
        self._ended = np.zeros(self.num_envs, dtype=bool)
        self._started = False

    def _outputs(self):
        n = self.num_envs
        obs = np.empty((n, self._obs_size), dtype=np.float32)
        rewards = np.zeros(n, dtype=np.float64)
        terminated = np.zeros(n, dtype=bool)
        truncated = np.zeros(n, dtype=bool)
        info = [np.zeros(n, dtype=t) for t in self._INFO_TYPES]
        return obs, rewards, terminated, truncated, info

    def _infos(self, arrays):
        infos = {}
        everyone = np.ones(self.num_envs, dtype=bool)
        for key, a in zip(self._INFO, arrays):
            infos[key] = a
            infos[f"_{key}"] = everyone.copy()
        return infos

    def _draw_seed(self, i):
        """Environment ``i``'s next episode seed, from its generator, as
        NavEnv.reset draws one without a seed."""
        if self._rngs[i] is None:
            self._rngs[i], _ = seeding.np_random(None)
        return int(self._rngs[i].integers(0, 2**62))

    def reset(self, *, seed=None, options=None):
        n = self.num_envs
        if seed is None:
            seeds = [None] * n
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ValueError(f"{len(seeds)} seeds for {n} environments: give one per environment, an int or None")
        mask = np.ones(n, dtype=bool)
        if options is not None and "reset_mask" in options:
            mask = np.asarray(options["reset_mask"])
            if mask.shape != (n,) or mask.dtype != np.bool_:
                raise ValueError(f"options['reset_mask'] must be a bool array of shape ({n},), got {mask.dtype} {mask.shape}")
            if not mask.any():
                raise ValueError("options['reset_mask'] marks no environment")
            if not self._started and not mask.all():
                raise ValueError("the first reset must reset every environment")
        for i in np.flatnonzero(mask):
            if seeds[i] is not None:
                if isinstance(seeds[i], bool) or not isinstance(seeds[i], (int, np.integer)) or seeds[i] < 0:
                    raise ValueError(f"seed {seeds[i]!r} of environment {i}: seeds are whole numbers >= 0")
                self._rngs[i], _ = seeding.np_random(int(seeds[i]))
                self._seeds[i] = int(seeds[i])
            else:
                self._seeds[i] = self._draw_seed(i)
            self._canvases[i] = None
        obs, rewards, terminated, truncated, info = self._outputs()
        if self._started:
            obs[:] = self._last_obs
        self._vec.reset(self._seeds, mask, obs, rewards, terminated, truncated, *info)
        self._ended[mask] = False
        self._started = True
        self._last_obs = obs
        return obs.copy(), self._infos(info)

    def step(self, actions):
        if not self._started:
            raise RuntimeError("call reset() before step()")
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != (self.num_envs, 2):
            raise ValueError(
                f"actions of shape {a.shape}, expected ({self.num_envs}, 2): one row of two numbers per environment"
            )
        a = np.ascontiguousarray(a)
        if self._ended.any():
            for i in np.flatnonzero(self._ended):
                self._seeds[i] = self._draw_seed(i)
                self._canvases[i] = None
        obs, rewards, terminated, truncated, info = self._outputs()
        self._vec.step(a, self._seeds, obs, rewards, terminated, truncated, *info)
        np.logical_or(terminated, truncated, out=self._ended)
        self._last_obs = obs
        return obs.copy(), rewards, terminated, truncated, self._infos(info)

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        frames = []
        for i in range(self.num_envs):
            view = _EnvView(self._vec, i)
            if self._canvases[i] is None:
                self._canvases[i] = Canvas(view, self._render_size)
            frames.append(self._canvases[i].draw(view))
        return tuple(frames)


class CrowdNavEnv(Drawn, gymnasium.Env):
    """CrowdNav's episode (Chen et al., "Crowd-Robot Interaction", ICRA
    2019): scenarios/crowdnav/circle-crossing.toml, five people crossing a
    circle of radius 4 m on ORCA, the learner the robot going from (0, -4)
    to (0, 4) in ticks of 0.25 s, at most 25 s.

    ``reset(seed=k)`` gives CrowdNav's test case ``k`` (its people placed
    from seed 1000 + k as CrowdNav places them; its test set is cases 0 to
    499); without a seed the case is drawn from the env's generator.
    ``visible``: whether the people see the robot (CrowdNav's
    ``robot.visible``; False, its test setting, by default).

    Action: the robot's velocity ``(vx, vy)`` in m/s, CrowdNav's holonomic
    robot: each component clipped to [-1, 1] and the vector to 1 m/s
    (``v_pref``). Observation (float32, 34): ``[goal_dx, goal_dy, vx, vy]``
    of the robot, then for each of the five people, nearest first, ``[dx,
    dy, dvx, dvy, radius, 1]`` (position and velocity relative to the
    robot's), as :class:`NavEnv` observes with ``k = 5``.

    Reward, CrowdNav's (``CrowdSim.step``): +1 at the goal (within 0.3 m),
    -0.25 at a collision, ``(dmin - 0.2) * 0.5 * 0.25`` when the robot came
    within 0.2 m (``discomfort_dist``) of a person during the tick (``dmin``
    the least surface distance over the tick, the bodies moving in straight
    lines from their positions before to after it), else 0; a timeout 0.
    ``terminated`` at a collision or the goal, ``truncated`` at 25 s.
    Info: ``outcome`` (``"success"``, ``"collision"``, ``"timeout"`` or
    None), ``dmin``, ``case``, ``tick``, ``time``.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    SUCCESS_REWARD = 1.0
    COLLISION_PENALTY = -0.25
    DISCOMFORT_DIST = 0.2
    DISCOMFORT_PENALTY_FACTOR = 0.5
    K = 5

    def __init__(self, visible=False, render_mode=None, render_size=256):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        if not isinstance(visible, (bool, np.bool_)):
            raise ValueError(f"visible must be True or False, got {visible!r}")
        self.visible = bool(visible)
        self.render_mode = render_mode
        self._render_size = render_size
        self._load(0)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.observation_space = _common.observation_space(self._sim, self.K)
        self._obs = np.zeros((1, self._sim.obs_size), dtype=np.float32)

    def _load(self, case):
        # The engine reads the scene from a file once, when it is built.
        fd, path = tempfile.mkstemp(prefix="mrsim-crowdnav-", suffix=".toml")
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(crowdnav_scene(case, self.visible))
            self._sim = Sim(path, ["robot"], [], self.K)
        finally:
            os.unlink(path)
        self.case = case
        self._horizon = _common.horizon(self._sim)
        self._dt = self._sim.dt
        kinds = self._sim.kinds()
        self._people = np.flatnonzero(kinds == 2)
        self._robot = self._sim.learner_indices[0]
        self._radii = self._sim.radii()
        self._canvas = None

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        case = seed if seed is not None else int(self.np_random.integers(0, 2**31))
        self._load(int(case))
        self._sim.observe(self._obs)
        return self._obs[0].copy(), self._info(None, float("inf"))

    def _dmin(self, before, after):
        """The least surface distance between the robot and a person over
        the tick: the closest point to the robot of each person's relative
        path, a segment from before to after."""
        r = self._robot
        start = before[self._people] - before[r]
        end = after[self._people] - after[r]
        d = end - start
        length2 = (d * d).sum(axis=1)
        t = np.where(length2 > 0, -(start * d).sum(axis=1) / np.where(length2 > 0, length2, 1), 0.0)
        closest = start + np.clip(t, 0.0, 1.0)[:, None] * d
        gaps = np.hypot(*closest.T) - self._radii[self._people] - self._radii[r]
        return float(gaps.min()) if len(gaps) else float("inf")

    def step(self, action):
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (2,):
            raise ValueError(f"an action is 2 numbers (vx, vy), got shape {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"non-finite action {a.tolist()}")
        v = np.clip(a, -1.0, 1.0)
        speed = float(np.hypot(*v))
        if speed > 1.0:
            v = v / speed
        before = self._sim.positions()
        collisions, _, _, reached = self._sim.step(v.reshape(1, 2), False)
        after = self._sim.positions()
        self._sim.observe(self._obs)
        dmin = self._dmin(before, after)
        outcome = None
        reward = 0.0
        if int(collisions[0]) > 0:
            outcome, reward = "collision", self.COLLISION_PENALTY
        elif bool(reached[0]):
            outcome, reward = "success", self.SUCCESS_REWARD
        elif dmin < self.DISCOMFORT_DIST:
            reward = (dmin - self.DISCOMFORT_DIST) * self.DISCOMFORT_PENALTY_FACTOR * self._dt
        terminated = outcome is not None
        truncated = not terminated and self._sim.tick >= self._horizon
        if truncated:
            outcome = "timeout"
        return self._obs[0].copy(), float(reward), terminated, truncated, self._info(outcome, dmin)

    def _info(self, outcome, dmin):
        return {
            "outcome": outcome,
            "dmin": dmin,
            "case": self.case,
            "tick": self._sim.tick,
            "time": self._sim.time,
        }

    @property
    def sim(self):
        """The underlying :class:`mrsim.Sim` of the current case."""
        return self._sim


# Registered on import (``import mrsim`` imports this module):
# ``gymnasium.make("mrsim/Nav-v0", **kwargs)`` builds a NavEnv with the
# constructor's keyword arguments, ``gymnasium.make_vec("mrsim/Nav-v0",
# num_envs=N, **kwargs)`` a NavVectorEnv.
gymnasium.register(
    id="mrsim/Nav-v0",
    entry_point="mrsim.gym:NavEnv",
    vector_entry_point="mrsim.gym:NavVectorEnv",
)

# ``gymnasium.make("mrsim/CrowdNav-v0", visible=False)``: CrowdNav's
# episode with its reward, the learner its robot (CrowdNavEnv).
gymnasium.register(
    id="mrsim/CrowdNav-v0",
    entry_point="mrsim.gym:CrowdNavEnv",
)
