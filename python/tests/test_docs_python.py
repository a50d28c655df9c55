"""docs/python.md's examples, run as printed (the Dask one against a local
cluster in place of the remote scheduler it names)."""

import re

import pytest


def blocks(repo, lang):
    text = (repo / "docs" / "python.md").read_text()
    return re.findall(rf"```{lang}\n(.*?)```", text, re.S)


@pytest.fixture
def in_scratch(repo, tmp_path, monkeypatch):
    """A working directory like a clone's root (scenarios/)."""
    (tmp_path / "scenarios").symlink_to(repo / "scenarios")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_chapter_shows_four_python_examples(repo):
    assert len(blocks(repo, "python")) == 4


def test_the_make_vec_example_runs_and_builds_a_nav_vector_env(repo, capsys):
    exec(blocks(repo, "python")[0], {})
    assert capsys.readouterr().out.split() == ["NavVectorEnv", "(8,", "28)", "float64"]


def test_the_sweep_example_prints_one_line_per_run(repo, in_scratch, capsys):
    exec(blocks(repo, "python")[1], {})
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 8
    assert lines[0].split()[:3] == ["0.8", "orca", "1"]


def test_the_dask_example_runs_on_a_local_cluster(repo, in_scratch):
    pytest.importorskip("distributed")
    pytest.importorskip("pandas")
    code = blocks(repo, "python")[2]
    code = code.replace('Client("tcp://scheduler:8786")', "Client(LocalCluster(n_workers=2, dashboard_address=None))")
    code = code.replace("[30.0, 60.0]", "[3.0, 6.0]").replace("seeds=4", "seeds=1")
    code = "from distributed import LocalCluster\n" + code + "\nclient.close()\n"
    scope = {}
    exec(code, scope)
    frame = scope["rows"]
    assert list(frame["ticks"]) == [30.0, 60.0]


def test_the_load_rows_example_reads_a_cut_timing_file(repo, tmp_path, capsys):
    import mrsim

    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / mrsim.FILES["timing"]).write_text(
        "tick,robot,sent_ns,status,cpu_ns\n0,r0,5,accepted,3\n1,r0,6,acc"
    )
    scope = {"mrsim": mrsim, "run_dir": run_dir}
    exec(blocks(repo, "python")[3], scope)
    assert [r["sent_ns"] for r in scope["rows"]] == ["5"]
    assert "the run was cut" in capsys.readouterr().out
