"""Environment steps per second of mrsim.gym.NavVectorEnv, and of NavEnv in
Gymnasium's SyncVectorEnv beside it (the ratio).

    python python/bench/vector_env.py [--num-envs 64] [--seconds 10] [--threads T]

Both batch the shipped circle-16 scene (1 learner + 15 ORCA robots; dt 0.1,
10 substeps) num-envs times and step it with random actions, autoresets
included. A rate counts environment steps: num-envs per batch step. Also
printed: the rate per second of this process's CPU time.
"""

import argparse
import time

import numpy as np
from gymnasium.vector import SyncVectorEnv

from mrsim.gym import NavEnv, NavVectorEnv


def rate(env, seconds):
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    n = env.num_envs
    steps, t0, c0 = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < seconds:
        env.step(rng.uniform(-1.0, 1.0, (n, 2)).astype(np.float32))
        steps += n
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return steps / wall, steps / cpu


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--num-envs", type=int, default=64)
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--threads", type=int, default=None, help="NavVectorEnv's num_threads (default: the cores)")
    a = p.parse_args()
    n = a.num_envs
    vec = NavVectorEnv(num_envs=n, num_threads=a.threads)
    sync = SyncVectorEnv([NavEnv for _ in range(n)])
    results = {}
    for name, env in [("NavVectorEnv", vec), ("SyncVectorEnv(NavEnv)", sync)]:
        wall, cpu = rate(env, a.seconds)
        results[name] = wall
        print(f"{name:24s} N={n}: {wall:10,.0f} env steps/s wall clock, {cpu:10,.0f} per CPU second")
    print(f"ratio: {results['NavVectorEnv'] / results['SyncVectorEnv(NavEnv)']:.1f}x")


if __name__ == "__main__":
    main()
