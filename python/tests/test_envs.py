"""The Gymnasium and PettingZoo environments against their libraries'
checkers, and what the README promises of them."""

import numpy as np
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


def test_nav_env_passes_gymnasiums_checker():
    check_env(NavEnv(render_mode="rgb_array"), skip_render_check=False)


def test_nav_env_with_force_actions_passes_gymnasiums_checker():
    check_env(NavEnv(action="force"))


def test_parallel_nav_env_passes_pettingzoos_api_test():
    parallel_api_test(ParallelNavEnv(), num_cycles=200)


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
