"""A task too big for the limit of the worker that runs it is refused by
that worker, the reason in the task's error."""

import pytest

import mrsim


CROWD = """name = "crowd"
[world]
dt = 0.1
duration = 1.0
mode = "lockstep"
[defaults]
sensing_range = 1.0
[generate]
kind = "random"
count = 100000
radius = 2000.0
planner = "homing"
"""


def _address_space_limit(limit):
    """A worker process's initializer: `ulimit -v` of `limit` bytes."""
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def test_a_worker_refuses_a_task_too_big_for_its_own_limit_and_says_why(tmp_path):
    # A worker under a 1 GiB address-space limit (`ulimit -v`, as a cluster
    # may set) is given a run of about 2 GiB: the task fails with the
    # worker's refusal, not with the worker killed part-way.
    from concurrent.futures import ProcessPoolExecutor
    import multiprocessing

    scenario = tmp_path / "crowd.toml"
    scenario.write_text(CROWD)
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(
        1, mp_context=ctx, initializer=_address_space_limit, initargs=(1 << 30,)
    ) as pool:
        with pytest.raises(RuntimeError) as e:
            mrsim.sweep(scenario, grid={"robot.*.max_speed": [1.0]}, executor=pool)
    said = str(e.value)
    assert "this run needs about 2.0 GiB of memory (100000 robots x 20 KB" in said, said
    assert "RLIMIT_AS, `ulimit -v`: 1.0 GiB" in said, said
    assert "To make it fit: run fewer robots" in said, said
