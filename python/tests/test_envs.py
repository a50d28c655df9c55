"""The Gymnasium and PettingZoo environments against their libraries'
checkers, and what the guide (docs/learning.md) promises of them."""

import numpy as np
import gymnasium
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test, parallel_seed_test

from mrsim.gym import NavEnv
from mrsim.pettingzoo import ParallelNavEnv

SIXTY_FOUR = [
    "generate.count=64",
    "generate.radius=20.0",
    "world.arena={ min = [-25.0, -25.0], max = [25.0, 25.0] }",
]


# The checkers report most findings as warnings: here each one fails the test.
@pytest.mark.filterwarnings("error")
def test_nav_env_passes_gymnasiums_checker():
    env = gymnasium.make("mrsim/Nav-v0", render_mode="rgb_array")
    check_env(env.unwrapped, skip_render_check=False)


@pytest.mark.filterwarnings("error")
def test_nav_env_with_force_actions_passes_gymnasiums_checker():
    check_env(gymnasium.make("mrsim/Nav-v0", action="force").unwrapped)


def test_the_registered_id_passes_the_constructors_keyword_arguments():
    env = gymnasium.make("mrsim/Nav-v0", k=3, max_episode_steps=5)
    obs, _ = env.reset(seed=1)
    assert isinstance(env.unwrapped, NavEnv) and obs.shape == (4 + 6 * 3,)
    assert env.spec.id == "mrsim/Nav-v0"


@pytest.mark.filterwarnings("error")
def test_parallel_nav_env_passes_pettingzoos_api_test():
    parallel_api_test(ParallelNavEnv(), num_cycles=200)


@pytest.mark.filterwarnings("error")
def test_parallel_nav_env_passes_pettingzoos_seed_test():
    parallel_seed_test(ParallelNavEnv)


def rollout(env, seed, steps=80):
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(0)
    trace = [obs]
    for _ in range(steps):
        obs, reward, term, trunc, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        trace += [obs, np.array([reward, term, trunc, info["distance_to_goal"]])]
        if term or trunc:
            break
    return np.concatenate([np.ravel(t) for t in trace])


def test_one_seed_gives_identical_episodes_and_another_seed_another():
    env = NavEnv()
    a, b = rollout(env, 5), rollout(env, 5)
    assert np.array_equal(a, b)
    # The circle's starts are jittered by the seed.
    c = rollout(env, 6)
    assert len(a) != len(c) or not np.array_equal(a, c)


def test_the_observation_points_at_the_goal_in_the_robots_frame():
    env = NavEnv(k=4)
    obs, info = env.reset(seed=1)
    assert obs.shape == (4 + 6 * 4,)
    assert np.isclose(np.hypot(obs[0], obs[1]), info["distance_to_goal"], rtol=1e-5)
    # Fifteen other robots: all four neighbour slots are present.
    assert list(obs[9::6]) == [1.0, 1.0, 1.0, 1.0]


def test_driving_at_the_goal_earns_progress_and_standing_still_none():
    env = NavEnv(reward_collision=0.0)
    obs, _ = env.reset(seed=1)
    toward = obs[:2] / np.hypot(*obs[:2])
    _, r, *_ = env.step(toward.astype(np.float32))
    assert r > 0
    env.reset(seed=1)
    _, r, *_ = env.step(np.zeros(2, dtype=np.float32))
    assert r == 0.0


def test_an_episode_is_truncated_at_the_scenarios_duration():
    # Alone in the scene and standing still: neither goal nor collision.
    env = NavEnv(set=["generate.count=2", "world.duration=1.0"])
    env.reset(seed=0)
    # Keep the other robot away: it is driven by ORCA towards our start.
    flags = []
    for _ in range(10):
        _, _, term, trunc, info = env.step(np.zeros(2, dtype=np.float32))
        flags.append((term, trunc))
    assert flags[-1] == (False, True)
    assert all(f == (False, False) for f in flags[:-1])
    assert info["tick"] == 10


def test_a_collision_terminates_the_episode():
    # Driving away from the goal ends at the arena's wall (12 m out).
    env = NavEnv(set=["generate.count=2", "generate.radius=2.0"])
    obs, _ = env.reset(seed=0)
    away = -obs[:2] / np.hypot(*obs[:2])
    for _ in range(200):
        _, r, term, trunc, info = env.step(away.astype(np.float32))
        if term or trunc:
            break
    assert term and not trunc
    assert info["collisions"] > 0 and not info["reached"]
    assert r < 0


def test_a_nan_action_is_refused():
    env = NavEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="non-finite"):
        env.step(np.array([np.nan, 0.0], dtype=np.float32))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(3, dtype=np.float32))


def test_render_draws_the_learner_in_red():
    env = NavEnv(render_mode="rgb_array")
    env.reset(seed=0)
    img = env.render()
    assert img.shape == (256, 256, 3) and img.dtype == np.uint8
    assert ((img == [220, 60, 50]).all(axis=2)).sum() > 10


def test_sixty_four_agents_all_leave_by_the_duration():
    env = ParallelNavEnv(set=SIXTY_FOUR + ["world.duration=2.0"])
    obs, _ = env.reset(seed=0)
    assert len(obs) == 64
    steps = 0
    while env.agents:
        env.step({a: env.action_space(a).sample() for a in env.agents})
        steps += 1
    assert steps <= 20


def test_the_observation_space_is_bounded_by_the_arena_and_holds_every_observation():
    env = NavEnv(k=4)
    space = env.observation_space
    # circle-16's arena is 24 m square: offsets within its diagonal.
    assert np.isfinite(space.high[0]) and space.high[0] < 40
    assert list(space.low[9::6]) == [0.0] * 4 and list(space.high[9::6]) == [1.0] * 4
    obs, _ = env.reset(seed=3)
    for _ in range(30):
        assert space.contains(obs), obs
        obs, *_ = env.step(env.action_space.sample())
    # An observation with an offset past the arena is outside it.
    bad = obs.copy()
    bad[0] = 1e6
    assert not space.contains(bad)


ALONE = """name = "alone"
[world]
dt = 0.1
duration = 20.0
arena = { min = [-5.0, -5.0], max = [10.0, 5.0] }
[[robot]]
name = "me"
start = [0.0, 0.0]
goal = [3.0, 0.0]
planner = "homing"
max_speed = 1.0
[[robot]]
name = "far"
start = [0.0, 4.0]
goal = [0.5, 4.0]
planner = "homing"
"""


def alone(tmp_path, **kw):
    path = tmp_path / "alone.toml"
    path.write_text(ALONE)
    return NavEnv(scenario=path, learner="me", **kw)


def test_reaching_the_goal_terminates_the_episode_and_pays_reward_arrival_once(tmp_path):
    env = alone(tmp_path, reward_progress=0.0, reward_collision=0.0, reward_arrival=7.0)
    obs, _ = env.reset(seed=0)
    rewards = []
    for _ in range(100):
        # Full speed while far, slowing within 1 m (a controller that never
        # slows overshoots and cannot hold within the goal tolerance).
        toward = obs[:2] / max(np.hypot(*obs[:2]), 1.0)
        obs, r, term, trunc, info = env.step(toward.astype(np.float32))
        rewards.append(r)
        if term or trunc:
            break
    assert term and not trunc
    assert info["reached"] and info["collisions"] == 0
    assert rewards[-1] == 7.0 and all(r == 0.0 for r in rewards[:-1]), rewards
    assert info["distance_to_goal"] < 0.5


def test_actions_are_clipped_to_the_unit_box(tmp_path):
    env = alone(tmp_path)

    def after(action, steps=10):
        # Several ticks: one tick's change of velocity is bounded by
        # max_accel whatever the action, so only a few show the speed asked.
        env.reset(seed=0)
        for _ in range(steps):
            obs, *_ = env.step(np.array(action, dtype=np.float32))
        return obs

    unit = after([1.0, -1.0])
    assert np.array_equal(after([50.0, -3.0]), unit)
    assert not np.array_equal(after([0.5, -0.5]), unit)


def test_fewer_neighbours_than_k_leave_zeros_in_the_missing_slots(tmp_path):
    env = alone(tmp_path, k=3)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (4 + 6 * 3,)
    first = obs[4:10]
    # The one other robot: 4 m away, present.
    assert np.isclose(np.hypot(first[0], first[1]), 4.0, atol=1e-4) and first[5] == 1.0
    assert first[4] > 0.0
    assert np.all(obs[10:] == 0.0), obs


def test_the_parallel_env_pads_missing_neighbours_with_zeros():
    env = ParallelNavEnv(set=["generate.count=2"], k=3)
    obs, _ = env.reset(seed=0)
    for a, o in obs.items():
        assert o[9] == 1.0, (a, o)
        assert np.all(o[10:] == 0.0), (a, o)
        assert env.observation_space(a).contains(o)
