"""The README's Python examples, run exactly as printed."""

import os
import re
import subprocess

import pytest

from test_live import finish, mrsim_binary


def python_blocks(repo):
    text = (repo / "README.md").read_text()
    start = text.index("\n### Python\n")
    end = text.find("\n## ", start)
    section = text[start:end]
    return re.findall(r"```python\n(.*?)```", section, re.S)


@pytest.fixture
def in_scratch(repo, tmp_path, monkeypatch):
    """A working directory like a clone's root (scenarios/), with runs/ in it."""
    (tmp_path / "scenarios").symlink_to(repo / "scenarios")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_readme_shows_three_python_examples(repo):
    assert len(python_blocks(repo)) == 3


def test_the_readmes_python_planner_and_live_agent_examples_run(repo, in_scratch, capsys):
    run_block, agent_block, _ = python_blocks(repo)
    scope = {}
    exec(run_block, scope)
    printed = capsys.readouterr().out.split()
    assert printed[0] == "True"
    assert os.path.isfile(os.path.join(printed[1], "metrics.json"))
    # The live agent, against the run the README starts in another terminal.
    cmd = [
        mrsim_binary(repo), "run", "scenarios/crossing.toml",
        "--set", "robot.a0.planner=external", "--run", "mine", "--quiet",
    ]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        exec(agent_block, scope)
        finish(proc)
        # The run out closed it; the scope lives on in a reference cycle
        # until some later collection, on whatever thread triggers it.
        scope["agent"].close()
    finally:
        proc.kill()


def test_the_readmes_learning_example_runs(repo):
    *_, env_block = python_blocks(repo)
    exec(env_block, {})
