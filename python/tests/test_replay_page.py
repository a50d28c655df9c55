"""The replay page in a real browser (Debian's Chromium, driven by
Playwright): it lists the run's encounters (encounters.csv) and highlights
the one picked, the two bodies ringed and joined where they met; it draws
bodies that are not discs as their polygons, turned by their headings, and
people in their own colour."""

import csv
import json
import math
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


def corners(shape, x, y, theta):
    """A body-frame polygon's corners in the world at (x, y), turned by theta."""
    c, s = math.cos(theta), math.sin(theta)
    return [(x + c * px - s * py, y + s * px + c * py) for px, py in shape]


def test_the_replay_page_draws_each_rectangle_turned_by_its_heading(repo, tmp_path, browser):  # noqa: F811
    out = tmp_path / "boxes"
    subprocess.run(
        [built_mrsim(repo), "run", str(repo / "scenarios/shapes/boxes.toml"), "--out", str(out), "--quiet"],
        check=True,
    )
    tick = 30
    with open(out / "trajectory.csv") as f:
        rows = {r["body"]: r for r in csv.DictReader(f) if int(r["tick"]) == tick}
    page = browser.new_page(viewport={"width": 1200, "height": 800})
    page.goto(out.joinpath("replay.html").as_uri() + f"#tick={tick}")
    page.wait_for_function("window.mrsimReplay && window.mrsimReplay.ready")
    to_canvas = lambda p: page.evaluate("([x, y]) => window.mrsimReplay.worldToCanvas(x, y)", list(p))  # noqa: E731
    half_l, half_w = 0.45, 0.3
    rect = [(-half_l, -half_w), (half_l, -half_w), (half_l, half_w), (-half_l, half_w)]
    for name in ["west", "east"]:
        row = rows[name]
        x, y, theta = float(row["x"]), float(row["y"]), float(row["theta"])
        # The polygon drawn is the cart's rectangle where trajectory.csv has
        # it, turned by its theta.
        drawn = page.evaluate("(n) => window.mrsimReplay.outline(n)", name)
        want = [to_canvas(p) for p in corners(rect, x, y, theta)]
        assert drawn is not None and len(drawn) == 4, drawn
        for d, w in zip(drawn, want):
            assert d == pytest.approx(w, abs=0.01)
        # On the canvas: its colour near a corner, and not its colour just
        # beyond its long side, which its circumscribed disc would cover.
        colour = page.evaluate("(n) => window.mrsimReplay.colorOf(n)", name)
        rgb = [int(colour[k : k + 2], 16) for k in (1, 3, 5)]
        centre = to_canvas((x, y))
        corner = want[0]
        inside = (centre[0] + 0.8 * (corner[0] - centre[0]), centre[1] + 0.8 * (corner[1] - centre[1]))
        assert pixel(page, *inside) == rgb
        beyond = to_canvas(corners([(0.0, -(half_w + 0.08))], x, y, theta)[0])
        assert math.hypot(beyond[0] - centre[0], beyond[1] - centre[1]) < 0.54 * page.evaluate(
            "window.mrsimReplay.worldToCanvas(1, 0)[0] - window.mrsimReplay.worldToCanvas(0, 0)[0]"
        )
        assert pixel(page, *beyond) != rgb
    # The crate at its 30 degrees, the wedge as its triangle.
    scenario = json.loads((out / "scenario.json").read_text())
    for o in scenario["obstacles"]:
        shape = o["shape"]
        points = (
            [(-shape["length"] / 2, -shape["width"] / 2), (shape["length"] / 2, -shape["width"] / 2),
             (shape["length"] / 2, shape["width"] / 2), (-shape["length"] / 2, shape["width"] / 2)]
            if shape["kind"] == "rectangle" else shape["points"]
        )  # fmt: skip
        row = rows[o["name"]]
        want = [to_canvas(p) for p in corners(points, float(row["x"]), float(row["y"]), o.get("heading", 0.0))]
        drawn = page.evaluate("(n) => window.mrsimReplay.outline(n)", o["name"])
        assert len(drawn) == len(want)
        for d, w in zip(drawn, want):
            assert d == pytest.approx(w, abs=0.01)
    page.close()


def test_the_replay_page_draws_every_person_in_the_people_s_colour_where_the_trajectory_has_them(
    repo, tmp_path, browser  # noqa: F811
):
    out = tmp_path / "people"
    subprocess.run(
        [built_mrsim(repo), "run", str(repo / "scenarios/people/crossing.toml"), "--out", str(out), "--quiet",
         "--set", "world.duration=4"],
        check=True,
    )  # fmt: skip
    scenario = json.loads((out / "scenario.json").read_text())
    people = {p["name"]: p for p in scenario["people"]}
    assert len(people) == 8
    sandy = [0xF4, 0xA4, 0x60]
    page = browser.new_page(viewport={"width": 1200, "height": 800})
    for tick in [0, 25]:
        with open(out / "trajectory.csv") as f:
            rows = {r["body"]: r for r in csv.DictReader(f) if int(r["tick"]) == tick}
        page.goto(out.joinpath("replay.html").as_uri() + f"#tick={tick}")
        page.wait_for_function("window.mrsimReplay && window.mrsimReplay.ready")
        to_canvas = lambda p: page.evaluate("([x, y]) => window.mrsimReplay.worldToCanvas(x, y)", list(p))  # noqa: E731
        scale = page.evaluate(
            "window.mrsimReplay.worldToCanvas(1, 0)[0] - window.mrsimReplay.worldToCanvas(0, 0)[0]"
        )
        for name, spec in people.items():
            row = rows[name]
            assert row["kind"] == "person"
            x, y = float(row["x"]), float(row["y"])
            # Half-way out from the centre, to the left (clear of the name
            # written above it): the people's colour.
            cx, cy = to_canvas((x, y))
            r = spec["radius"] * scale
            assert pixel(page, cx - 0.5 * r, cy) == sandy, (name, tick)
        # A robot is not drawn in it.
        for robot in ["r0", "r1", "r2"]:
            cx, cy = to_canvas((float(rows[robot]["x"]), float(rows[robot]["y"])))
            assert pixel(page, cx - 0.3 * 0.25 * scale, cy) != sandy
    page.close()
