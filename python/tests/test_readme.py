"""The guide's Python examples (docs/own-planner.md, docs/learning.md), run
exactly as printed."""

import os
import re
import subprocess

import pytest

from test_live import finish, mrsim_binary


def python_blocks(repo, chapter, heading=None):
    """The ```python blocks of a guide chapter (after `heading`, up to the
    next heading of its level, when given)."""
    text = (repo / "docs" / chapter).read_text()
    if heading is not None:
        start = text.index(f"\n{heading}\n")
        level = heading.split()[0]
        end = text.find(f"\n{level} ", start + 1)
        text = text[start : end if end >= 0 else len(text)]
    return re.findall(r"```python\n(.*?)```", text, re.S)


@pytest.fixture
def in_scratch(repo, tmp_path, monkeypatch):
    """A working directory like a clone's root (scenarios/), with runs/ in it."""
    (tmp_path / "scenarios").symlink_to(repo / "scenarios")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_guide_shows_two_python_planner_examples_and_two_learning_examples(repo):
    assert len(python_blocks(repo, "own-planner.md", "## Python")) == 2
    assert len(python_blocks(repo, "learning.md")) == 2
    assert len(python_blocks(repo, "learning.md", "## CrowdNav")) == 1


def test_the_guides_python_planner_and_live_agent_examples_run(repo, in_scratch, capsys):
    run_block, agent_block = python_blocks(repo, "own-planner.md", "## Python")
    scope = {}
    exec(run_block, scope)
    printed = capsys.readouterr().out.split()
    assert printed[0] == "True"
    assert os.path.isfile(os.path.join(printed[1], "metrics.json"))
    # The live agent, against the run the guide starts in another terminal.
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


def test_the_guides_learning_example_runs(repo):
    env_block, _ = python_blocks(repo, "learning.md")
    exec(env_block, {})


def test_the_guides_crowdnav_example_prints_what_it_says(repo, capsys):
    (block,) = python_blocks(repo, "learning.md", "## CrowdNav")
    exec(block, {})
    said = re.search(r"# (.*)\n", block.splitlines()[-1] + "\n").group(1)
    assert capsys.readouterr().out.split() == said.split()
