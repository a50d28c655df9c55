"""mrsim.gym.NavVectorEnv: a Gymnasium 1.x vector environment whose
environments step in one call into Rust, against Gymnasium's own
SyncVectorEnv of NavEnvs."""

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import data_equivalence
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import mrsim  # noqa: F401  (registers mrsim/Nav-v0)
from mrsim.gym import NavEnv, NavVectorEnv

# Four robots on a circle of radius 2 m, 6 s episodes: a learner that heads
# for its goal arrives, one that does not may collide or run out of time, so
# a few hundred steps see every way an episode ends.
SMALL = ["generate.count=4", "generate.radius=2.0", "world.duration=6.0"]


def policy(obs, rng, noise):
    """Heads for the goal (the first two observation values), with noise;
    the last environment's learner stands still (its episodes run out of
    time)."""
    goal = obs[:, :2]
    norm = np.maximum(np.linalg.norm(goal, axis=1, keepdims=True), 1e-9)
    a = goal / norm + noise * rng.normal(size=goal.shape)
    a[-1] = 0.0
    return a.astype(np.float32)


def run_both(n, steps, seed, noise, num_threads=None, **kwargs):
    """Steps a NavVectorEnv and a SyncVectorEnv of n NavEnvs side by side
    with the same actions; asserts every output equal; returns the ends."""
    vec = NavVectorEnv(num_envs=n, num_threads=num_threads, **kwargs)
    ref = SyncVectorEnv([lambda: NavEnv(**kwargs) for _ in range(n)])
    assert ref.metadata["autoreset_mode"] == vec.metadata["autoreset_mode"]
    o1, i1 = vec.reset(seed=seed)
    o2, i2 = ref.reset(seed=seed)
    assert data_equivalence(o1, o2, exact=True)
    for key in ("distance_to_goal", "at_goal", "reached", "tick", "time"):
        assert np.array_equal(i1[key], i2[key]), key
    rng = np.random.default_rng(seed)
    ends = {"terminated": 0, "truncated": 0, "reached": 0, "collided": 0}
    for t in range(steps):
        a = policy(o1, rng, noise)
        o1, r1, te1, tr1, i1 = vec.step(a)
        o2, r2, te2, tr2, i2 = ref.step(a)
        where = f"step {t}"
        assert data_equivalence(o1, o2, exact=True), where
        assert np.array_equal(r1, r2), (where, r1, r2)
        assert np.array_equal(te1, te2), where
        assert np.array_equal(tr1, tr2), where
        for key in ("collisions", "distance_to_goal", "at_goal", "reached", "tick", "time"):
            assert np.array_equal(i1[key], i2[key]), (where, key, i1[key], i2[key])
        ends["terminated"] += int(te1.sum())
        ends["truncated"] += int(tr1.sum())
        ends["reached"] += int((te1 & i1["reached"]).sum())
        ends["collided"] += int((te1 & (i1["collisions"] > 0)).sum())
    return ends


def test_each_environment_gives_the_episodes_of_a_nav_env_with_its_seed_through_autoresets():
    ends = run_both(3, 240, seed=5, noise=0.6, set=SMALL)
    # The comparison went through episodes ended every way.
    assert ends["reached"] > 0 and ends["collided"] > 0 and ends["truncated"] > 0, ends


def test_force_actions_and_uneven_threads_give_the_same_episodes_as_nav_envs():
    # Five environments on three threads: chunks of two, two and one.
    ends = run_both(5, 120, seed=11, noise=1.0, set=SMALL, action="force", num_threads=3)
    assert ends["terminated"] + ends["truncated"] > 0, ends


def test_make_vec_builds_a_nav_vector_env_with_batched_spaces():
    envs = gymnasium.make_vec("mrsim/Nav-v0", num_envs=4, set=SMALL, k=3)
    assert isinstance(envs, NavVectorEnv)
    assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    single = NavEnv(set=SMALL, k=3)
    assert envs.single_observation_space == single.observation_space
    assert envs.single_action_space == single.action_space
    assert envs.observation_space.shape == (4, 4 + 6 * 3)
    assert envs.action_space.shape == (4, 2)
    obs, info = envs.reset(seed=0)
    assert envs.observation_space.contains(obs)
    assert info["_tick"].all() and (info["tick"] == 0).all()
    envs.action_space.seed(0)
    for _ in range(20):
        obs, rew, term, trunc, info = envs.step(envs.action_space.sample())
        assert envs.observation_space.contains(obs)
        assert rew.dtype == np.float64 and rew.shape == (4,)
        assert term.dtype == np.bool_ and trunc.dtype == np.bool_


def test_one_seed_gives_the_same_batch_of_episodes_and_returned_arrays_are_not_reused():
    def trace(env):
        obs, _ = env.reset(seed=3)
        out = [obs]
        rng = np.random.default_rng(0)
        for _ in range(80):
            obs, rew, term, trunc, _ = env.step(rng.uniform(-1, 1, (2, 2)))
            out += [obs, rew, term, trunc]
        return out

    env = NavVectorEnv(num_envs=2, set=SMALL)
    a, b = trace(env), trace(env)
    assert all(data_equivalence(x, y, exact=True) for x, y in zip(a, b))
    # Each step's arrays are its own: a later step does not change them.
    assert not np.shares_memory(a[1], a[5])
    assert not data_equivalence(a[1], a[5])


def test_a_partial_reset_resets_only_the_marked_environments():
    env = NavVectorEnv(num_envs=3, set=SMALL, k=2)
    env.reset(seed=1)
    for _ in range(5):
        obs, *_ = env.step(np.zeros((3, 2)))
    mask = np.array([False, True, False])
    again, info = env.reset(seed=[None, 2, None], options={"reset_mask": mask})
    assert np.array_equal(again[[0, 2]], obs[[0, 2]])
    fresh, _ = NavEnv(set=SMALL, k=2).reset(seed=2)
    assert np.array_equal(again[1], fresh)
    assert info["tick"][1] == 0


def test_rgb_array_renders_one_frame_per_environment():
    env = NavVectorEnv(num_envs=2, set=SMALL, render_mode="rgb_array", render_size=64)
    env.reset(seed=0)
    frames = env.render()
    assert len(frames) == 2
    assert all(f.shape == (64, 64, 3) and f.dtype == np.uint8 for f in frames)
    # The learner (red) is drawn.
    assert any((f[..., 0] > 200).sum() and (f[..., 1] < 100).sum() for f in frames)


def test_wrong_action_shapes_and_non_finite_actions_are_refused_clearly():
    env = NavVectorEnv(num_envs=3, set=SMALL)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros((3, 2)))
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2, 2\), expected \(3, 2\)"):
        env.step(np.zeros((2, 2)))
    with pytest.raises(ValueError, match=r"shape \(6,\), expected \(3, 2\)"):
        env.step(np.zeros(6))
    bad = np.zeros((3, 2))
    bad[1, 0] = np.nan
    with pytest.raises(ValueError, match=r"environment 1: non-finite action"):
        env.step(bad)
    bad[1, 0] = np.inf
    with pytest.raises(ValueError, match=r"environment 1"):
        env.step(bad)
    # A refused step changed nothing: the batch still steps.
    obs, *_ = env.step(np.zeros((3, 2)))
    assert np.isfinite(obs).all()


def test_bad_constructor_arguments_are_refused_clearly():
    with pytest.raises(ValueError, match="num_envs"):
        NavVectorEnv(num_envs=0)
    with pytest.raises(ValueError, match="action must be one of"):
        NavVectorEnv(num_envs=2, action="torque")
    with pytest.raises(ValueError, match="no robot `zz`"):
        NavVectorEnv(num_envs=2, learner="zz")
    with pytest.raises(ValueError, match="seeds"):
        NavVectorEnv(num_envs=2, set=SMALL).reset(seed=[1, 2, 3])


def test_gymnasiums_vector_wrappers_record_the_episodes():
    env = gymnasium.wrappers.vector.RecordEpisodeStatistics(NavVectorEnv(num_envs=2, set=SMALL))
    env.reset(seed=0)
    episodes = 0
    for _ in range(100):
        _, _, term, trunc, info = env.step(np.ones((2, 2)))
        if "episode" in info:
            episodes += int(info["_episode"].sum())
    assert episodes > 0
