"""Steps per second of mrsim's learning environments, on one core.

    taskset -c 0 python python/bench/envs.py [--seconds 5]

NavEnv: 1 learner among 15 ORCA robots (the shipped circle-16), random
actions, reset when an episode ends (resets included in the time).
ParallelNavEnv: 64 learning robots (circle of radius 20 m), random actions
for every agent present, reset when all have left.
"""

import argparse
import time

import numpy as np

from mrsim.gym import NavEnv
from mrsim.pettingzoo import ParallelNavEnv

SIXTY_FOUR = [
    "generate.count=64",
    "generate.radius=20.0",
    "world.arena={ min = [-25.0, -25.0], max = [25.0, 25.0] }",
]


def nav(seconds):
    env = NavEnv()
    env.reset(seed=0)
    env.action_space.seed(0)
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        _, _, term, trunc, _ = env.step(env.action_space.sample())
        steps += 1
        if term or trunc:
            env.reset()
    return steps / (time.perf_counter() - t0)


def parallel(seconds):
    env = ParallelNavEnv(set=SIXTY_FOUR)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        env.step({a: rng.uniform(-1, 1, 2) for a in env.agents})
        steps += 1
        if not env.agents:
            env.reset()
    return steps / (time.perf_counter() - t0)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=5.0)
    a = p.parse_args()
    print(f"NavEnv (1 learner + 15 ORCA): {nav(a.seconds):,.0f} steps/s")
    print(f"ParallelNavEnv (64 robots):   {parallel(a.seconds):,.0f} steps/s")


if __name__ == "__main__":
    main()
