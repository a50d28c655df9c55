"""The replay page in a real browser (Debian's Chromium, driven by
Playwright): it lists the run's encounters (encounters.csv) and highlights
the one picked, the two bodies ringed and joined where they met."""

import csv
import subprocess

import pytest

from conftest import built_mrsim
from test_live_page import browser  # noqa: F401  (the fixture)

SCENE = """name = "head-on"
[world]
dt = 0.1
duration = 8.0
mode = "lockstep"

[defaults]
radius = 0.3
max_speed = 1.0
max_accel = 2.0
planner = "orca"

[[robot]]
name = "left"
start = [-4.0, 0.0]
goal = [4.0, 0.0]

[[robot]]
name = "right"
start = [4.0, 0.05]
goal = [-4.0, 0.05]
"""

ORANGE = [255, 140, 0]


@pytest.fixture
def run_dir(repo, tmp_path):
    scene = tmp_path / "head-on.toml"
    scene.write_text(SCENE)
    out = tmp_path / "run"
    subprocess.run([built_mrsim(repo), "run", str(scene), "--out", str(out), "--quiet"], check=True)
    return out


def positions(run_dir, tick):
    with open(run_dir / "trajectory.csv") as f:
        return {r["body"]: (float(r["x"]), float(r["y"])) for r in csv.DictReader(f) if int(r["tick"]) == tick}


def pixel(page, x, y):
    return page.evaluate(
        "([x, y]) => { const c = document.getElementById('map'); const d = window.devicePixelRatio || 1;"
        " return Array.from(c.getContext('2d').getImageData(Math.round(x * d), Math.round(y * d), 1, 1).data.slice(0, 3)); }",
        [x, y],
    )


def test_the_replay_page_lists_the_encounters_and_highlights_the_one_picked(run_dir, browser):  # noqa: F811
    rows = list(csv.DictReader(open(run_dir / "encounters.csv")))
    head_on = [i for i, r in enumerate(rows) if {r["a"], r["b"]} == {"left", "right"}]
    assert head_on and rows[head_on[0]]["kind"] == "head-on", rows
    e = rows[head_on[0]]
    start = int(e["start_tick"])
    at = positions(run_dir, start)
    page = browser.new_page(viewport={"width": 1200, "height": 800})
    page.goto((run_dir / "replay.html").as_uri() + f"#tick={start}")
    page.wait_for_function("window.mrsimReplay && window.mrsimReplay.ready")
    listed = page.locator("#encounters .ev")
    assert listed.count() == len(rows)
    assert "head-on left - right" in listed.nth(head_on[0]).text_content()
    # Between the two robots where they met: nothing drawn before a pick...
    a = page.evaluate("([x, y]) => window.mrsimReplay.worldToCanvas(x, y)", list(at["left"]))
    b = page.evaluate("([x, y]) => window.mrsimReplay.worldToCanvas(x, y)", list(at["right"]))
    mid = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
    assert pixel(page, *mid) != ORANGE
    # ... the line joining them once it is picked; the view is where it began.
    listed.nth(head_on[0]).click()
    assert page.evaluate("window.mrsimReplay.picked()") == head_on[0]
    assert "on" in listed.nth(head_on[0]).get_attribute("class")
    assert pixel(page, *mid) == ORANGE
    # A second click lets it go.
    listed.nth(head_on[0]).click()
    assert page.evaluate("window.mrsimReplay.picked()") is None
    assert pixel(page, *mid) != ORANGE
    page.close()
