"""mrsim.sweep on a real Dask cluster (distributed.LocalCluster: a scheduler
and worker processes) against `mrsim sweep`'s sweep.csv."""

import csv
import shutil
import subprocess

import pytest

import mrsim
from conftest import built_mrsim

distributed = pytest.importorskip("distributed")

GRID = {"robot.*.max_speed": [0.8, 1.2], "robot.*.planner": ["orca", "social-force"]}


@pytest.fixture(scope="module")
def executor():
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        yield client.get_executor()


def cli_rows(repo, tmp_path, scenario, sets, seeds):
    out = tmp_path / "cli"
    cmd = [built_mrsim(repo), "sweep", str(scenario), "--seeds", str(seeds), "--out", str(out), "--jobs", "2"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    with open(out / "sweep.csv", newline="") as f:
        return list(csv.DictReader(f))


def same_rows(cli, ours, keys):
    """Compares sweep.csv's rows with mrsim.sweep's, value for value."""
    assert len(cli) == len(ours)
    assert list(cli[0]) == list(ours[0]), "the same columns in the same order"
    for c, o in zip(cli, ours):
        for col, text in c.items():
            v = o[col]
            if col in keys:
                assert str(v) == text, (col, v, text)
            elif col in ("mode", "run"):
                assert v == text, (col, v, text)
            elif col == "seed":
                assert v == int(text)
            elif text == "":
                assert v is None, (col, v)
            else:
                # Rust prints the shortest text that reads back as the same
                # float: equal floats, bit for bit.
                assert v == float(text), (c["run"], col, v, text)


def test_a_dask_sweep_gives_the_rows_of_mrsim_sweep(repo, tmp_path, executor):
    scenario = repo / "scenarios" / "crossing-jitter.toml"
    rows = mrsim.sweep(scenario, grid=GRID, seeds=2, executor=executor)
    sets = [f"{k}={','.join(str(v) for v in vs)}" for k, vs in GRID.items()]
    cli = cli_rows(repo, tmp_path, scenario, sets, 2)
    assert len(rows) == 2 * 2 * 2
    same_rows(cli, rows, GRID)
    # The seeds do change the runs (the scene is jittered): the comparison
    # is of different runs, not of one run eight times.
    assert len({r["makespan"] for r in rows} | {r["min_clearance"] for r in rows}) > 2


def test_a_scene_with_a_map_runs_on_a_worker_from_the_files_its_task_carries(repo, tmp_path, executor):
    # A copy of the map scene in a folder of its own, removed before the
    # sweep runs: the workers can only have the bytes the tasks carry.
    src = repo / "scenarios" / "maps"
    here = tmp_path / "scene"
    shutil.copytree(src, here)
    scenario = here / "office.toml"
    grid = {"world.duration": [8.0]}
    cli = cli_rows(repo, tmp_path, scenario, ["world.duration=8.0"], 1)
    plan = mrsim._sweep.sweep_jobs(str(scenario), ["world.duration=8.0"], 1)
    assert sorted(p.rsplit("/", 1)[-1] for p in plan["files"]) == ["office.pgm", "office.yaml"]
    bundle = mrsim._sweep._Bundle(str(scenario), plan["files"])
    shutil.rmtree(here)
    rows = []
    for job in plan["jobs"]:
        metrics = executor.submit(mrsim._sweep._run_task, bundle, job[3]).result()
        rows.append({"world.duration": 8.0, "mode": "lockstep", "seed": job[1], **dict(metrics), "run": job[2]})
    same_rows(cli, rows, grid)
    assert rows[0]["ticks"] == 80


def test_sweep_returns_a_data_frame_when_asked(repo):
    pandas = pytest.importorskip("pandas")
    frame = mrsim.sweep(repo / "scenarios" / "crossing.toml", grid={"world.duration": [2.0]}, as_frame=True)
    assert isinstance(frame, pandas.DataFrame)
    assert list(frame["seed"]) == [1] and list(frame["ticks"]) == [20.0]


def test_bad_sweeps_are_refused_before_anything_runs(repo, tmp_path):
    crossing = repo / "scenarios" / "crossing.toml"
    with pytest.raises(ValueError, match="seeds"):
        mrsim.sweep(crossing, grid={}, seeds=0)
    with pytest.raises(ValueError, match="the seed is varied by"):
        mrsim.sweep(crossing, grid={"world.seed": [1, 2]})
    with pytest.raises(ValueError, match="no values"):
        mrsim.sweep(crossing, grid={"world.duration": []})
    with pytest.raises(ValueError, match="combination"):
        mrsim.sweep(crossing, grid={"world.duration": [-1.0]})
    # A map named by an absolute path would not travel with the task.
    maps = repo / "scenarios" / "maps"
    text = (maps / "office.toml").read_text().replace('file = "office.yaml"', f'file = "{maps / "office.yaml"}"')
    (tmp_path / "abs.toml").write_text(text)
    with pytest.raises(ValueError, match="absolute path"):
        mrsim.sweep(tmp_path / "abs.toml", grid={"world.duration": [1.0]})
