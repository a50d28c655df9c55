"""A planner of your own in Python, beside mrsim's built-in ones: robot g00 of
the jittered crossing heads straight for its goal and slows down near other
bodies, while the other seven run ORCA. Run from the repository's root:
`python examples/python_planner.py` (needs the package: `pip install ./python`).
"""

import numpy as np

import mrsim


class Cautious:
    """Straight at the goal; slower the nearer another body is."""

    def __init__(self, params):
        self.slow_within = params.get("slow_within", 1.0)

    def plan(self, obs):
        to_goal = obs.goal - obs.position
        d = max(np.hypot(*to_goal), 1e-9)
        gaps = (
            np.hypot(*(obs.others_position - obs.position).T)
            - obs.others_radius
            - obs.radius
        )
        gap = gaps.min() if len(gaps) else np.inf
        speed = obs.max_speed * np.clip(gap / self.slow_within, 0.2, 1.0)
        # No faster than it can still stop at the goal.
        speed = min(speed, np.sqrt(2 * obs.max_accel * d), d / obs.dt)
        return to_goal / d * speed  # a velocity, m/s


result = mrsim.run(
    "scenarios/crossing-jitter.toml",
    planners={"cautious": Cautious},
    set=["planner=orca", "robot.g00.planner=cautious"],
)
m = result.metrics
print(f"g00 (cautious) reached its goal: {m['robots']['g00']['reached_goal']}")
print(f"success {m['success_rate']:.0%}, collisions {m['collisions_total']}")
print(f"run folder: {result.dir}")
