"""Steps per second of mrsim's learning environments, on one core.

    taskset -c 0 python python/bench/envs.py [--seconds 5]

NavEnv: 1 learner among 15 ORCA robots (the shipped circle-16), random
actions, reset when an episode ends (resets included in the time).
ParallelNavEnv: 64 learning robots (circle of radius 20 m), random actions
for every agent present, reset when all have left.
Both rates are printed: per wall-clock second, and per second of this
process's CPU time (what it would be alone on the core).
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
    steps, t0, c0 = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < seconds:
        _, _, term, trunc, _ = env.step(env.action_space.sample())
        steps += 1
        if term or trunc:
            env.reset()
    return steps / (time.perf_counter() - t0), steps / (time.process_time() - c0)


def parallel(seconds):
    env = ParallelNavEnv(set=SIXTY_FOUR)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    steps, t0, c0 = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < seconds:
        env.step({a: rng.uniform(-1, 1, 2) for a in env.agents})
        steps += 1
        if not env.agents:
            env.reset()
    return steps / (time.perf_counter() - t0), steps / (time.process_time() - c0)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=5.0)
    a = p.parse_args()
    for name, f in [("NavEnv (1 learner + 15 ORCA)", nav), ("ParallelNavEnv (64 robots)", parallel)]:
        wall, cpu = f(a.seconds)
        print(f"{name:30s} {wall:8,.0f} steps/s wall clock, {cpu:8,.0f} per CPU second")


if __name__ == "__main__":
    main()
