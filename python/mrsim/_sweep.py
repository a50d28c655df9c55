"""``mrsim.sweep``: the runs of ``mrsim sweep`` from Python, on any
``concurrent.futures.Executor`` (a Dask cluster's included).

Each run is a task that carries everything it needs: the scenario's text
and the bytes of every file it reads (a map's YAML file and image), laid
out as they are beside the scenario. A worker writes them into a temporary
folder, runs the scenario there in-process, in lockstep, and sends back the
run's metrics; it needs only the installed ``mrsim`` package.
"""

import json
import os
import tempfile
from pathlib import Path

from ._mrsim import sweep_jobs, sweep_run


def _value_text(value, top=True):
    """A grid value as ``mrsim sweep --set`` text: strings as written at the
    top level (``orca``), quoted inside arrays and tables."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return value if top else json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value_text(v, False) for v in value) + "]"
    if isinstance(value, dict):
        items = ", ".join(f"{k} = {_value_text(v, False)}" for k, v in value.items())
        return "{ " + items + " }"
    if hasattr(value, "item"):  # numpy scalars
        return _value_text(value.item(), top)
    raise TypeError(f"grid value {value!r}: give numbers, strings, booleans, lists or dicts")


class _Bundle:
    """The scenario's text and the files it reads, by path relative to a
    common folder: what a worker writes down to run it."""

    def __init__(self, scenario, files):
        paths = [Path(scenario).resolve()] + [Path(f).resolve() for f in files]
        root = Path(os.path.commonpath([str(p.parent) for p in paths]))
        self.scenario = paths[0].relative_to(root).as_posix()
        self.files = {p.relative_to(root).as_posix(): p.read_bytes() for p in paths}

    def write(self, folder):
        """Writes the files under ``folder``; returns the scenario's path."""
        for rel, data in self.files.items():
            path = Path(folder, rel)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        return str(Path(folder, self.scenario))


def _run_task(bundle, overrides):
    """One run of a sweep, on whichever machine the executor picks: its
    metrics, as ``(name, value)`` pairs in sweep.csv's order."""
    with tempfile.TemporaryDirectory(prefix="mrsim-sweep-") as tmp:
        scenario = bundle.write(Path(tmp, "in"))
        return sweep_run(scenario, list(overrides), str(Path(tmp, "run")))


def sweep(scenario, grid=None, seeds=1, executor=None, as_frame=False):
    """Runs the sweep ``mrsim sweep SCENARIO --set KEY=V1,V2,... --seeds N``
    runs and returns one row per run, in sweep.csv's order and columns.

    ``grid`` maps each swept key (``robot.*.max_speed``, as ``--set``) to a
    list of values (numbers, strings, booleans, lists, dicts; a string is
    also taken as ``--set``'s comma-separated text); every combination runs
    with each seed 1..=``seeds`` (``world.seed``), first key slowest.
    ``executor``: any :class:`concurrent.futures.Executor` the runs are
    submitted to (a Dask cluster's ``Client.get_executor()``, a
    ``ProcessPoolExecutor``); None runs them here, one after the other.

    A row is a dict: each swept key with its value (as given in ``grid``),
    ``mode`` (``"lockstep"``), ``seed``, the metrics of sweep.csv (floats,
    None where sweep.csv's cell is empty) and ``run``, the run's folder as
    ``mrsim sweep`` names it under its output folder (the runs here keep no
    folder: each ran in a temporary one). ``as_frame=True`` returns a pandas
    DataFrame of the rows instead (pandas must be installed).

    Runs are in lockstep, so the rows equal those of ``mrsim sweep`` for the
    same scenario, grid and seeds. A run that fails raises RuntimeError
    naming its folder and why.
    """
    if as_frame:
        try:
            import pandas
        except ImportError as e:
            raise ImportError("as_frame=True needs pandas: pip install pandas") from e
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise ValueError(f"seeds must be a whole number of at least 1, got {seeds!r}")
    grid = dict(grid or {})
    given = {}
    overrides = []
    for key, values in grid.items():
        if isinstance(values, str):
            overrides.append(f"{key}={values}")
            given[key] = None
            continue
        values = list(values) if isinstance(values, (list, tuple)) else [values]
        if not values:
            raise ValueError(f"grid[{key!r}] has no values")
        overrides.append(f"{key}=" + ",".join(_value_text(v) for v in values))
        given[key] = values
    scenario = str(scenario)
    plan = sweep_jobs(scenario, overrides, seeds)
    for key, texts in zip(plan["axes"], plan["values"]):
        if given[key] is not None and len(texts) != len(given[key]):
            raise ValueError(
                f"grid[{key!r}]: {len(given[key])} values became {len(texts)} ({texts}): "
                "a string value must not hold a comma outside brackets or quotes"
            )
    bundle = _Bundle(scenario, plan["files"])
    _check_bundle(bundle, overrides, seeds)
    if executor is None:
        results = [_run_task(bundle, job[3]) for job in plan["jobs"]]
    else:
        futures = [executor.submit(_run_task, bundle, job[3]) for job in plan["jobs"]]
        results = []
        for job, f in zip(plan["jobs"], futures):
            try:
                results.append(f.result())
            except Exception as e:
                raise RuntimeError(f"{job[2]}: {e}") from e
    rows = []
    for (combo, seed, folder, _), metrics in zip(plan["jobs"], results):
        row = {}
        # The combination's index: the first key varies slowest.
        rest = combo
        picks = []
        for texts in reversed(plan["values"]):
            picks.append(rest % len(texts))
            rest //= len(texts)
        picks.reverse()
        for key, texts, j in zip(plan["axes"], plan["values"], picks):
            row[key] = texts[j] if given[key] is None else given[key][j]
        row["mode"] = "lockstep"
        row["seed"] = seed
        row.update(metrics)
        row["run"] = folder
        rows.append(row)
    if as_frame:
        return pandas.DataFrame(rows)
    return rows


def _check_bundle(bundle, overrides, seeds):
    """Refuses a scenario whose runs would read a file the bundle does not
    carry (a map named by an absolute path): written down elsewhere, the
    scenario must find every file inside its own folder."""
    with tempfile.TemporaryDirectory(prefix="mrsim-sweep-check-") as tmp:
        copy = bundle.write(tmp)
        inside = Path(tmp).resolve()
        for f in sweep_jobs(copy, overrides, seeds)["files"]:
            p = Path(f).resolve()
            if inside not in p.parents:
                raise ValueError(
                    f"{f}: the scenario reads this file by an absolute path, which a worker "
                    "elsewhere would not have; name it relative to the scenario's folder "
                    "(a map's image relative to its YAML file)"
                )
