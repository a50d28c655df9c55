"""run.mcap against readers nobody on this project wrote: the `mcap` package
reads every record with its CRCs checked and counts what the summary says,
every message is checked against Foxglove's own JSON schemas (the
`@foxglove/schemas` npm package), and the robots' positions are those of
trajectory.csv."""

import base64
import csv
import json
import math
import os
import pathlib
import shutil
import subprocess

import jsonschema
import pytest
from mcap.reader import make_reader
from mcap.records import Message
from mcap.stream_reader import StreamReader

from conftest import built_mrsim as mrsim_binary


@pytest.fixture(scope="session")
def foxglove_schemas(tmp_path_factory):
    """Foxglove's published JSON schemas by name (`foxglove.SceneUpdate`, ...),
    from the npm package, installed here unless FOXGLOVE_SCHEMAS names a JSON
    file of them."""
    given = os.environ.get("FOXGLOVE_SCHEMAS")
    if given:
        return json.loads(pathlib.Path(given).read_text())
    npm, node = shutil.which("npm"), shutil.which("node")
    if not npm or not node:
        pytest.fail("npm and node are needed to install @foxglove/schemas (Debian: nodejs npm)")
    where = tmp_path_factory.mktemp("foxglove")
    subprocess.run(
        [npm, "install", "--silent", "--prefix", str(where), "@foxglove/schemas"],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    dump = (
        "const s = require('@foxglove/schemas/jsonschema');"
        "const out = {};"
        "for (const [k, v] of Object.entries(s)) if (v && v.title) out[v.title] = v;"
        "process.stdout.write(JSON.stringify(out));"
    )
    text = subprocess.run(
        [node, "-e", dump], cwd=where, check=True, capture_output=True, text=True
    ).stdout
    schemas = json.loads(text)
    assert "foxglove.SceneUpdate" in schemas and "foxglove.Grid" in schemas
    return schemas


def run_scene(repo, out, scenario, *sets):
    cmd = [
        mrsim_binary(repo), "run", str(repo / "scenarios" / scenario), "--quiet", "--no-report",
        "--transport", "inproc", "--out", str(out), "--set", "output.mcap=true", *sets,
    ]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, cwd=repo)
    assert done.returncode == 0, done.stderr
    return out


def read_all(path):
    """Every record through the streaming reader (CRCs of chunks, the data
    section and the summary checked), and the messages decoded."""
    with open(path, "rb") as f:
        records = list(StreamReader(f, validate_crcs=True).records)
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        messages = [
            (schema, channel, message, json.loads(message.data))
            for schema, channel, message in reader.iter_messages(log_time_order=False)
        ]
    return records, summary, messages


def trajectory(out):
    with open(out / "trajectory.csv") as f:
        return list(csv.DictReader(f))


def check_file(out, schemas):
    records, summary, messages = read_all(out / "run.mcap")
    # The summary's counts are what the file holds.
    in_records = [r for r in records if isinstance(r, Message)]
    assert summary.statistics.message_count == len(messages) == len(in_records) > 0
    per_channel = {}
    for _, channel, _, _ in messages:
        per_channel[channel.id] = per_channel.get(channel.id, 0) + 1
    assert summary.statistics.channel_message_counts == per_channel
    assert summary.statistics.channel_count == len(summary.channels)
    assert summary.statistics.schema_count == len(summary.schemas)
    # Every message is valid under its schema: Foxglove's for its
    # well-known types, the file's own for mrsim's stats.
    for schema, channel, _, msg in messages:
        assert channel.message_encoding == "json"
        assert schema.encoding == "jsonschema"
        known = schemas.get(schema.name) or json.loads(schema.data)
        jsonschema.validate(msg, known)
    return summary, messages


def test_the_lidar_demo_writes_an_mcap_that_foxglove_can_read(repo, tmp_path, foxglove_schemas):
    out = run_scene(repo, tmp_path / "lidar", "lidar-demo.toml", "--set", "world.duration=4")
    summary, messages = check_file(out, foxglove_schemas)
    topics = {c.topic for c in summary.channels.values()}
    assert {"/scene", "/tf", "/stats", "/scout/scan"} <= topics
    assert "/walker/scan" not in topics  # walker's scans are not recorded
    # Each scan in the file is a row of scan.csv, beam for beam.
    with open(out / "scan.csv") as f:
        rows = [line.rstrip("\n").split(",") for line in f.readlines()[1:]]
    scans = [m for _, c, _, m in messages if c.topic == "/scout/scan"]
    assert len(scans) == len(rows) > 0
    for scan, row in zip(scans, rows):
        beams = [c for c in row[5:] if c != ""]
        assert len(scan["ranges"]) == len(beams)
        for r, cell in zip(scan["ranges"], beams):
            value = float(cell)
            assert r == pytest.approx(value if value != float("inf") else 0.0, abs=1e-9)
        assert scan["start_angle"] == pytest.approx(float(row[2]))
    # The robots' frames are where trajectory.csv has them, tick by tick,
    # and log times are simulated time.
    rows = {(r["tick"], r["body"]): r for r in trajectory(out)}
    dt = 0.1
    tfs = [(m, msg) for _, c, m, msg in messages if c.topic == "/tf"]
    assert len(tfs) == len({r["tick"] for r in rows.values()})
    for message, msg in tfs:
        tick = round(message.log_time / 1e9 / dt)
        for t in msg["transforms"]:
            row = rows[(str(tick), t["child_frame_id"])]
            assert t["translation"]["x"] == pytest.approx(float(row["x"]), abs=1e-9)
            assert t["translation"]["y"] == pytest.approx(float(row["y"]), abs=1e-9)
    # The scene draws each robot with its name once a tick.
    scenes = [msg for _, c, _, msg in messages if c.topic == "/scene"]
    ids = {e["id"] for e in scenes[-1]["entities"]}
    assert {"scout", "walker"} <= ids
    assert any(e["id"] == "walls" and e["lines"][0]["points"] for e in scenes[0]["entities"])


def test_a_map_scene_exports_its_grid_and_export_rewrites_the_same_file(
    repo, tmp_path, foxglove_schemas
):
    out = run_scene(repo, tmp_path / "office", "maps/office.toml", "--set", "world.duration=2")
    summary, messages = check_file(out, foxglove_schemas)
    grids = [msg for _, c, _, msg in messages if c.topic == "/map"]
    assert len(grids) == 1
    scenario = json.loads((out / "scenario.json").read_text())
    width, height = scenario["map"]["size"]
    assert grids[0]["column_count"] == width
    assert grids[0]["cell_size"]["x"] == pytest.approx(scenario["map"]["resolution"])
    cells = base64.b64decode(grids[0]["data"])
    assert len(cells) == width * height
    assert set(cells) <= {0, 100, 255}  # free, occupied, unknown (-1 as INT8)
    assert 100 in set(cells)
    # `mrsim export` writes the same bytes from the folder.
    first = (out / "run.mcap").read_bytes()
    (out / "run.mcap").unlink()
    done = subprocess.run(
        [mrsim_binary(repo), "export", str(out), "--mcap"], capture_output=True, text=True, cwd=repo
    )
    assert done.returncode == 0, done.stderr
    assert (out / "run.mcap").read_bytes() == first


def test_export_refuses_a_folder_that_is_not_a_run(repo, tmp_path):
    done = subprocess.run(
        [mrsim_binary(repo), "export", str(tmp_path), "--mcap"], capture_output=True, text=True
    )
    assert done.returncode == 2
    assert "scenario.json" in done.stderr
    done = subprocess.run([mrsim_binary(repo), "export", str(tmp_path)], capture_output=True, text=True)
    assert done.returncode == 2
    assert "--mcap" in done.stderr


def yaw_of(q):
    return 2.0 * math.atan2(q["z"], q["w"])


def test_a_scene_of_shapes_draws_rectangles_as_cubes_and_a_polygon_as_a_line_loop(
    repo, tmp_path, foxglove_schemas
):
    out = run_scene(repo, tmp_path / "boxes", "shapes/boxes.toml", "--set", "world.duration=3")
    _, messages = check_file(out, foxglove_schemas)
    scenario = json.loads((out / "scenario.json").read_text())
    robots = {r["name"]: r for r in scenario["robots"]}
    obstacles = {o["name"]: o for o in scenario["obstacles"]}
    assert robots["west"]["shape"] == {"kind": "rectangle", "length": 0.9, "width": 0.6}
    wedge_points = obstacles["wedge"]["shape"]["points"]
    rows = {(r["tick"], r["body"]): r for r in trajectory(out)}
    dt = scenario["world"]["dt"]
    scenes = [(m, msg) for _, c, m, msg in messages if c.topic == "/scene"]
    # The first holds what lasts (walls, goals); then one a tick.
    assert len(scenes) == 1 + len({t for t, _ in rows})
    for message, msg in scenes[1:]:
        tick = str(round(message.log_time / 1e9 / dt))
        entities = {e["id"]: e for e in msg["entities"]}
        # Each cart: a cube 0.9 x 0.6 where trajectory.csv has it, turned
        # by its theta; no disc.
        for name in ["west", "east"]:
            e, row = entities[name], rows[(tick, name)]
            assert e["cylinders"] == [] and len(e["cubes"]) == 1, e
            cube = e["cubes"][0]
            assert (cube["size"]["x"], cube["size"]["y"]) == (pytest.approx(0.9), pytest.approx(0.6))
            assert cube["pose"]["position"]["x"] == pytest.approx(float(row["x"]), abs=1e-9)
            assert cube["pose"]["position"]["y"] == pytest.approx(float(row["y"]), abs=1e-9)
            turn = yaw_of(cube["pose"]["orientation"]) - float(row["theta"])
            assert math.cos(turn) == pytest.approx(1.0, abs=1e-9)
        # The crate: a cube 1.2 x 0.5 at its 30 degrees.
        crate = entities["crate"]["cubes"][0]
        assert (crate["size"]["x"], crate["size"]["y"]) == (pytest.approx(1.2), pytest.approx(0.5))
        assert yaw_of(crate["pose"]["orientation"]) == pytest.approx(math.radians(30), abs=1e-9)
        # The wedge: a line loop through its three points, in its frame,
        # posed where it is.
        wedge = entities["wedge"]
        assert wedge["cylinders"] == [] and wedge["cubes"] == []
        loop = wedge["lines"][0]
        assert loop["type"] == 1  # LINE_LOOP
        assert [[p["x"], p["y"]] for p in loop["points"]] == [pytest.approx(p) for p in wedge_points]
        assert loop["pose"]["position"]["y"] == pytest.approx(float(rows[(tick, "wedge")]["y"]))
        assert yaw_of(loop["pose"]["orientation"]) == pytest.approx(0.0, abs=1e-12)


def test_people_are_drawn_where_the_trajectory_has_them_in_their_own_colour(
    repo, tmp_path, foxglove_schemas
):
    out = run_scene(repo, tmp_path / "people", "people/crossing.toml", "--set", "world.duration=3")
    _, messages = check_file(out, foxglove_schemas)
    scenario = json.loads((out / "scenario.json").read_text())
    people = {p["name"]: p for p in scenario["people"]}
    assert len(people) == 8
    rows = {(r["tick"], r["body"]): r for r in trajectory(out)}
    dt = scenario["world"]["dt"]
    scenes = [(m, msg) for _, c, m, msg in messages if c.topic == "/scene"]
    assert len(scenes) == 1 + len({t for t, _ in rows})
    sandy = {"r": 0xF4 / 255, "g": 0xA4 / 255, "b": 0x60 / 255}
    for message, msg in scenes[1:]:
        tick = str(round(message.log_time / 1e9 / dt))
        entities = {e["id"]: e for e in msg["entities"]}
        for name, spec in people.items():
            row = rows[(tick, name)]
            assert row["kind"] == "person"
            # A cylinder of the person's diameter where trajectory.csv has it.
            (c,) = entities[name]["cylinders"]
            assert c["size"]["x"] == pytest.approx(2 * spec["radius"])
            assert c["pose"]["position"]["x"] == pytest.approx(float(row["x"]), abs=1e-9)
            assert c["pose"]["position"]["y"] == pytest.approx(float(row["y"]), abs=1e-9)
            for k, v in sandy.items():
                assert c["color"][k] == pytest.approx(v, abs=1e-6)
        # The robots are drawn apart, none in the people's colour.
        for robot in ["r0", "r1", "r2"]:
            (c,) = entities[robot]["cylinders"]
            assert any(abs(c["color"][k] - v) > 1e-3 for k, v in sandy.items())
