"""The live page in a real browser (Debian's Chromium, driven by Playwright):
it shows a run while it ticks, over shared memory, in-process and over
Zenoh, and says when the run has finished; `mrsim view` shows a run started
elsewhere; bodies that are not discs are drawn as their polygons."""

import json
import math
import os
import re
import shutil
import subprocess
import time
import urllib.request

import pytest
from playwright.sync_api import sync_playwright

from conftest import built_mrsim as mrsim_binary

CHROMIUM = os.environ.get("MRSIM_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
BROWSER_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]  # fmt: skip


@pytest.fixture(scope="module")
def browser():
    if not os.path.exists(CHROMIUM):
        pytest.fail(f"{CHROMIUM} not found: install Debian's chromium (or set MRSIM_CHROMIUM)")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=BROWSER_ARGS)
        yield b
        b.close()


def start(cmd, cwd):
    """Starts `cmd` and returns it with the live page's URL it printed."""
    proc = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        m = re.search(r"live page: (http://\S+)", line)
        if m:
            return proc, m.group(1)
    proc.kill()
    pytest.fail(f"no live page URL from {cmd}: {proc.communicate()}")


def canvas(page):
    return page.evaluate("document.getElementById('map').toDataURL()")


def watch_to_the_end(browser, url, robots):
    page = browser.new_page(viewport={"width": 1100, "height": 800})
    page.goto(url)
    page.wait_for_function("Number(document.body.dataset.tick || 0) > 0", timeout=60_000)
    first_tick, first = int(page.evaluate("document.body.dataset.tick")), canvas(page)
    page.screenshot()
    time.sleep(1.0)
    second_tick, second = int(page.evaluate("document.body.dataset.tick")), canvas(page)
    page.screenshot()
    # A second later the run has ticked on and the robots have moved.
    assert second_tick > first_tick
    assert second != first
    title = page.text_content("#title")
    assert "run" in title
    # Every robot is there, and a click on one shows its details.
    setup = json.loads(urllib.request.urlopen(url + "setup").read())
    assert [r["name"] for r in setup["robots"]] == robots
    page.wait_for_function("document.body.dataset.ended !== undefined", timeout=90_000)
    status = page.text_content("#status")
    page.close()
    return status


def test_the_live_page_shows_a_realtime_run_over_shared_memory_until_it_finishes(
    repo, tmp_path, browser
):
    cmd = [
        mrsim_binary(repo), "run", "scenarios/crossing.toml", "--set", "planner=orca",
        "--set", "defaults.params.perturb=0.001", "--set", "world.mode=realtime",
        "--set", "world.duration=6", "--live", "--quiet", "--out", str(tmp_path / "run"),
    ]  # fmt: skip
    proc, url = start(cmd, repo)
    assert url.startswith("http://127.0.0.1:")
    try:
        status = watch_to_the_end(browser, url, [f"a{i}" for i in range(4)] + [f"b{i}" for i in range(4)])
        assert status == "the run has finished"
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()


@pytest.mark.parametrize("transport", ["inproc", "zenoh"])
def test_the_live_page_shows_an_in_process_and_a_zenoh_run(repo, tmp_path, browser, transport):
    cmd = [
        mrsim_binary(repo), "run", "scenarios/crossing.toml", "--set", "world.mode=realtime",
        "--set", "world.duration=5", "--transport", transport, "--live", "127.0.0.1:0",
        "--quiet", "--out", str(tmp_path / "run"),
    ]  # fmt: skip
    proc, url = start(cmd, repo)
    try:
        status = watch_to_the_end(browser, url, [f"a{i}" for i in range(4)] + [f"b{i}" for i in range(4)])
        assert status == "the run has finished"
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()


def test_mrsim_view_shows_a_run_started_elsewhere_and_two_pages_at_once(repo, tmp_path, browser):
    run_id = f"view{os.getpid()}"
    run = subprocess.Popen(
        [
            mrsim_binary(repo), "run", "scenarios/crossing.toml", "--set", "world.mode=realtime",
            "--set", "world.duration=6", "--run", run_id, "--quiet", "--out", str(tmp_path / "run"),
        ],  # fmt: skip
        cwd=repo, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        view, url = start([mrsim_binary(repo), "view", "--run", run_id, "--timeout", "30"], repo)
        other = browser.new_page()
        other.goto(url)
        status = watch_to_the_end(browser, url, [f"a{i}" for i in range(4)] + [f"b{i}" for i in range(4)])
        assert status == "the run has finished"
        other.wait_for_function("document.body.dataset.ended !== undefined", timeout=30_000)
        assert other.text_content("#status") == "the run has finished"
        assert view.wait(timeout=60) == 0
        assert run.wait(timeout=60) == 0
    finally:
        run.kill()
        if "view" in locals():
            view.kill()


def test_live_refuses_an_address_it_cannot_parse(repo):
    done = subprocess.run(
        [mrsim_binary(repo), "run", "scenarios/crossing.toml", "--live", "nowhere", "--quiet"],
        cwd=repo, capture_output=True, text=True,
    )  # fmt: skip
    assert done.returncode == 2
    assert "--live nowhere" in done.stderr


def test_the_live_page_draws_each_body_as_its_shape_turned_by_its_heading(repo, tmp_path, browser):
    cmd = [
        mrsim_binary(repo), "run", "scenarios/shapes/boxes.toml", "--set", "world.mode=realtime",
        "--set", "world.duration=3", "--transport", "inproc", "--live", "127.0.0.1:0",
        "--quiet", "--out", str(tmp_path / "run"),
    ]  # fmt: skip
    proc, url = start(cmd, repo)
    try:
        page = browser.new_page(viewport={"width": 1100, "height": 800})
        page.goto(url)
        # The setup sends each polygon once, in its body frame.
        setup = json.loads(urllib.request.urlopen(url + "setup").read())
        rect = [[-0.45, -0.3], [0.45, -0.3], [0.45, 0.3], [-0.45, 0.3]]
        assert [r["shape"] for r in setup["robots"]] == [rect, rect]
        crate, wedge = setup["obstacles"]
        assert crate["shape"] == [[-0.6, -0.25], [0.6, -0.25], [0.6, 0.25], [-0.6, 0.25]]
        assert wedge["shape"] == [[-0.5, -0.4], [0.5, -0.4], [0.0, 0.5]]
        # Once the run has ended the page draws no more: check its last frame.
        page.wait_for_function("document.body.dataset.ended !== undefined", timeout=90_000)
        assert page.text_content("#status") == "the run has finished"
        frame = page.evaluate("window.mrsimLive.frame()")
        bodies = {b[0]: b for b in frame["bodies"]}
        # The crate's heading comes with every frame: its fixed 30 degrees.
        assert bodies[2][5] == pytest.approx(math.radians(30), abs=1e-3)
        to_canvas = lambda x, y: page.evaluate("([x, y]) => window.mrsimLive.toCanvas(x, y)", [x, y])  # noqa: E731
        everyone = setup["robots"] + setup["obstacles"]
        for i, body in enumerate(everyone):
            _, x, y, _, _, th = bodies[i]
            c, s = math.cos(th), math.sin(th)
            want = [to_canvas(x + c * px - s * py, y + s * px + c * py) for px, py in body["shape"]]
            drawn = page.evaluate("(i) => window.mrsimLive.outline(i)", i)
            assert drawn is not None and len(drawn) == len(want), (body["name"], drawn)
            for d, w in zip(drawn, want):
                assert d == pytest.approx(w, abs=0.01), body["name"]
        # On the canvas (transparent, over the page's white): a cart's
        # colour at 0.85 opacity near its corner, and not just beyond its
        # long side, inside the disc that holds it.
        def painted(rgba, rgb):
            return all(abs(a - b) <= 3 for a, b in zip(rgba, rgb)) and abs(rgba[3] - 217) <= 3

        for i, r in enumerate(setup["robots"]):
            _, x, y, _, _, th = bodies[i]
            rgb = [int(r["color"][k : k + 2], 16) for k in (1, 3, 5)]
            c, s = math.cos(th), math.sin(th)
            near_corner = to_canvas(x + 0.8 * (c * 0.45 + s * 0.3), y + 0.8 * (s * 0.45 - c * 0.3))
            beyond = to_canvas(x + s * 0.38, y - c * 0.38)
            inside = page.evaluate(PIXEL, near_corner)
            assert painted(inside, rgb), (inside, rgb)
            outside = page.evaluate(PIXEL, beyond)
            assert not painted(outside, rgb), (outside, rgb)
        page.close()
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()


PIXEL = (
    "([x, y]) => Array.from(document.getElementById('map').getContext('2d')"
    ".getImageData(Math.round(x), Math.round(y), 1, 1).data)"
)


def test_the_live_page_draws_the_people_in_their_own_colour(repo, tmp_path, browser):
    cmd = [
        mrsim_binary(repo), "run", "scenarios/people/crossing.toml", "--set", "world.mode=realtime",
        "--set", "world.duration=3", "--transport", "inproc", "--live", "127.0.0.1:0",
        "--quiet", "--out", str(tmp_path / "run"),
    ]  # fmt: skip
    proc, url = start(cmd, repo)
    try:
        page = browser.new_page(viewport={"width": 1100, "height": 800})
        page.goto(url)
        setup = json.loads(urllib.request.urlopen(url + "setup").read())
        assert [p["name"] for p in setup["people"]] == [f"p{k}" for k in range(8)]
        assert setup["personColor"] == "#f4a460"
        page.wait_for_function("document.body.dataset.ended !== undefined", timeout=90_000)
        frame = page.evaluate("window.mrsimLive.frame()")
        bodies = {b[0]: b for b in frame["bodies"]}
        to_canvas = lambda x, y: page.evaluate("([x, y]) => window.mrsimLive.toCanvas(x, y)", [x, y])  # noqa: E731
        first = len(setup["robots"]) + len(setup["obstacles"])
        sandy = [0xF4, 0xA4, 0x60]
        for k, person in enumerate(setup["people"]):
            # Each person's body, after the robots and obstacles, in the
            # people's colour at 0.85 opacity half-way out from its centre.
            _, x, y, *_ = bodies[first + k]
            rgba = page.evaluate(PIXEL, to_canvas(x - 0.5 * person["radius"], y))
            assert all(abs(a - b) <= 3 for a, b in zip(rgba, sandy)) and abs(rgba[3] - 217) <= 3, (person, rgba)
        page.close()
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()
