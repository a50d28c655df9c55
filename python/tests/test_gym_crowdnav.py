"""mrsim/CrowdNav-v0: CrowdNav's episode and reward for a learning robot
(docs/learning.md, docs/crowdnav.md)."""

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import mrsim.gym
from mrsim._mrsim import crowdnav_scene
from mrsim.gym import CrowdNavEnv

DT = 0.25


def episode(env, seed, policy):
    """Runs one episode; returns every step's (reward, terminated,
    truncated, info)."""
    obs, info = env.reset(seed=seed)
    steps = []
    while True:
        obs, reward, terminated, truncated, info = env.step(policy(env, obs))
        steps.append((reward, terminated, truncated, info))
        if terminated or truncated:
            return steps


def straight(env, obs):
    """Straight at the goal, at 1 m/s."""
    return np.array([0.0, 1.0])


def still(env, obs):
    return np.array([0.0, 0.0])


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("visible", [False, True])
def test_crowdnav_env_passes_gymnasiums_checker(visible):
    env = gymnasium.make("mrsim/CrowdNav-v0", visible=visible, render_mode="rgb_array")
    assert isinstance(env.unwrapped, CrowdNavEnv) and env.unwrapped.visible == visible
    check_env(env.unwrapped, skip_render_check=False)


def test_case_0_is_the_shipped_scene_and_other_cases_other_people(repo):
    shipped = (repo / "scenarios" / "crowdnav" / "circle-crossing.toml").read_text()
    assert crowdnav_scene(0) == shipped
    assert crowdnav_scene(0, True) == shipped.replace("sees_robots = false", "sees_robots = true")
    assert "seed = 1007\n" in crowdnav_scene(7)
    assert crowdnav_scene(7) != crowdnav_scene(8)
    with pytest.raises(ValueError, match="cases run from 0"):
        crowdnav_scene(2**32)


def test_reset_with_a_seed_gives_that_case_s_people():
    env = CrowdNavEnv()
    for case in (0, 3):
        obs, info = env.reset(seed=case)
        assert info["case"] == case and info["tick"] == 0
        sim = env.sim
        people = sim.positions()[sim.kinds() == 2]
        text = crowdnav_scene(case)
        for x, y in people:
            assert f"start = [{float(x)!r}, {float(y)!r}]" in text
        # The robot at (0, -4), the goal 8 m ahead, five people observed.
        assert obs[:2].tolist() == [0.0, 8.0]
        assert obs[4 + 5 :: 6].tolist() == [1.0] * 5
        again, _ = env.reset(seed=case)
        assert np.array_equal(obs, again)
    first, _ = env.reset(seed=0)
    assert not np.array_equal(first, env.reset(seed=3)[0])


def test_walking_into_people_who_do_not_see_the_robot_ends_at_minus_a_quarter():
    env = gymnasium.make("mrsim/CrowdNav-v0")
    steps = episode(env, 0, straight)
    reward, terminated, truncated, info = steps[-1]
    assert info["outcome"] == "collision" and terminated and not truncated
    assert reward == -0.25
    assert all(not (t or u) and i["outcome"] is None for _, t, u, i in steps[:-1])


def test_people_who_see_the_robot_let_it_through_to_plus_one():
    env = gymnasium.make("mrsim/CrowdNav-v0", visible=True)
    steps = episode(env, 2, straight)
    reward, terminated, truncated, info = steps[-1]
    assert info["outcome"] == "success" and terminated and not truncated
    assert reward == 1.0
    # 7.7 m (to within the 0.3 m tolerance) at 1 m/s: 31 ticks of 0.25 s.
    assert info["tick"] == 31 and info["time"] == pytest.approx(7.75)
    # On the way it came within the discomfort distance: CrowdNav's
    # penalty, (dmin - 0.2) * 0.5 * dt, and 0 otherwise.
    close = 0
    for reward, _, _, info in steps[:-1]:
        if info["dmin"] < 0.2:
            close += 1
            assert reward == pytest.approx((info["dmin"] - 0.2) * 0.5 * DT, abs=1e-15)
            assert reward < 0
        else:
            assert reward == 0.0
    assert close > 0


def test_a_robot_that_waits_among_people_who_see_it_times_out_at_25_s_with_0():
    env = gymnasium.make("mrsim/CrowdNav-v0", visible=True)
    steps = episode(env, 0, still)
    reward, terminated, truncated, info = steps[-1]
    assert info["outcome"] == "timeout" and truncated and not terminated
    assert info["tick"] == 100 and info["time"] == pytest.approx(25.0)
    assert reward == 0.0 or info["dmin"] < 0.2


def test_an_action_is_a_velocity_of_at_most_1_m_s():
    env = CrowdNavEnv(visible=True)
    env.reset(seed=0)
    env.step(np.array([5.0, 5.0]))
    v = env.sim.velocities()[env.sim.learner_indices[0]]
    assert np.hypot(*v) == pytest.approx(1.0)
    assert v[0] == pytest.approx(v[1])
    with pytest.raises(ValueError, match="non-finite"):
        env.step(np.array([np.nan, 0.0]))
    with pytest.raises(ValueError, match="2 numbers"):
        env.step(np.array([1.0]))
    with pytest.raises(ValueError, match="visible"):
        CrowdNavEnv(visible="yes")


def test_the_module_registers_crowdnav():
    assert "mrsim/CrowdNav-v0" in gymnasium.registry
    assert gymnasium.registry["mrsim/CrowdNav-v0"].entry_point == "mrsim.gym:CrowdNavEnv"
    assert mrsim.gym.CrowdNavEnv is CrowdNavEnv
