"""The Python binding against the CLI and against bad input."""

import json
import os
import pathlib
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import flatray

# A rotated room (its walls at 30 degrees) with a mirror, a coloured wall,
# a pane, glass and two kinds of light: as RON text and as Python values.
ROOM_RON = """Scene(
    canvas: (60, 48),
    floor: Color((0.8, 0.8, 0.8)),
    walls: [
        Wall(a: (10, 8), b: (50, 4)),
        Wall(a: (50, 4), b: (54, 40), material: Mirror()),
        Wall(a: (54, 40), b: (14, 44), material: Diffuse(albedo: (0.9, 0.3, 0.2))),
        Wall(a: (14, 44), b: (10, 8), material: Transparent(tint: (0.5, 0.8, 1))),
    ],
    lights: [
        Point(at: (24, 20), intensity: 2.0),
        Line(a: (30, 36), b: (40, 35), intensity: 0.5),
    ],
    glass: [Glass(points: [(36, 14), (44, 16), (40, 24)], ior: 1.5)],
    render: (samples: 8, bounces: 2),
)
"""

ROOM_VALUES = dict(
    canvas=(60, 48),
    floor={"Color": (0.8, 0.8, 0.8)},
    walls=[
        {"a": (10, 8), "b": (50, 4)},
        {"a": (50, 4), "b": (54, 40), "material": "Mirror"},
        {"a": (54, 40), "b": (14, 44), "material": {"Diffuse": {"albedo": (0.9, 0.3, 0.2)}}},
        {"a": (14, 44), "b": (10, 8), "material": {"Transparent": {"tint": (0.5, 0.8, 1)}}},
    ],
    lights=[
        {"Point": {"at": (24, 20), "intensity": 2.0}},
        {"Line": {"a": (30, 36), "b": (40, 35), "intensity": 0.5}},
    ],
    glass=[{"points": [(36, 14), (44, 16), (40, 24)], "ior": 1.5}],
    render={"samples": 8, "bounces": 2},
)


def cli_render(cli, scene_path, out, *flags):
    subprocess.run([cli, "render", str(scene_path), "-o", str(out), "-q", *flags], check=True)
    return flatray.read_exr(out)


def test_a_scene_built_in_python_renders_the_clis_bits(cli, tmp_path):
    path = tmp_path / "room.ron"
    path.write_text(ROOM_RON)
    expected = cli_render(cli, path, tmp_path / "cli.exr", "--seed", "3")
    built = flatray.Scene(**ROOM_VALUES)
    got = flatray.render(built, seed=3)
    assert got.image.shape == expected.shape
    assert np.array_equal(got.image, expected)
    # The same through the loader, and with the samples given here.
    loaded = flatray.load(path)
    assert np.array_equal(flatray.render(loaded, seed=3).image, expected)
    more = cli_render(cli, path, tmp_path / "more.exr", "--spp", "20", "--integrator", "light")
    assert np.array_equal(flatray.render(built, spp=20, integrator="light").image, more)


# An optical bench: a beam of a sodium lamp, a laser of a blackbody and a
# mercury line lamp through a dispersive prism, and rough glass.
BENCH_RON = """Scene(
    canvas: (64, 40),
    floor: Color((0.8, 0.8, 0.8)),
    lights: [
        Beam(a: (2, 10), b: (2, 14), direction: (1, 0.1), intensity: 2, spectrum: Lamp(Sodium)),
        Laser(at: (2, 20), direction: (1, -0.05), intensity: 5, spectrum: Blackbody(6504)),
        Line(a: (4, 30), b: (8, 34), spectrum: Table([(400, 0.2), (550, 1), (700, 0.5)])),
    ],
    glass: [
        Glass(points: [(20, 30), (34, 30), (27, 8)], ior: 1.6, dispersion: 0.05),
        Glass(points: [(44, 10), (52, 10), (52, 34), (44, 34)], roughness: 0.2),
    ],
    render: (samples: 8),
)
"""

BENCH_VALUES = dict(
    canvas=(64, 40),
    floor={"Color": (0.8, 0.8, 0.8)},
    lights=[
        {"Beam": {"a": (2, 10), "b": (2, 14), "direction": (1, 0.1), "intensity": 2,
                  "spectrum": {"Lamp": "Sodium"}}},
        {"Laser": {"at": (2, 20), "direction": (1, -0.05), "intensity": 5,
                   "spectrum": {"Blackbody": 6504}}},
        {"Line": {"a": (4, 30), "b": (8, 34),
                  "spectrum": {"Table": [(400, 0.2), (550, 1), (700, 0.5)]}}},
    ],
    glass=[
        {"points": [(20, 30), (34, 30), (27, 8)], "ior": 1.6, "dispersion": 0.05},
        {"points": [(44, 10), (52, 10), (52, 34), (44, 34)], "roughness": 0.2},
    ],
    render={"samples": 8},
)


def test_beams_lasers_spectra_and_rough_glass_from_python_render_the_clis_bits(cli, tmp_path):
    path = tmp_path / "bench.ron"
    path.write_text(BENCH_RON)
    expected = cli_render(cli, path, tmp_path / "cli.exr", "--seed", "5")
    got = flatray.render(flatray.Scene(**BENCH_VALUES), seed=5)
    assert np.array_equal(got.image, expected)
    assert got.image.max() > 0
    with pytest.raises(flatray.SceneError) as caught:
        flatray.Scene(**{**BENCH_VALUES, "lights": [{"Point": {"at": (5, 5),
                                                              "spectrum": {"Blackbody": 10}}}]})
    assert "kelvin" in caught.value.message


# Curved walls: a round room of two arcs with a glowing half, a round
# mirror column, and a lens of two arcs.
ARCS_RON = """Scene(
    canvas: (64, 48),
    floor: Color((0.8, 0.8, 0.8)),
    walls: [
        Wall(a: (8, 24), through: (32, 2), b: (56, 24)),
        Wall(a: (56, 24), through: (32, 46), b: (8, 24), emit: (intensity: 0.2)),
        Wall(center: (22, 20), radius: 3, material: Mirror()),
    ],
    lights: [Point(at: (40, 20), intensity: 3)],
    glass: [Glass(points: [(30, 26), (30, 38)], through: [Some((33, 32)), Some((27, 32))])],
    render: (samples: 8, bounces: 2),
)
"""

ARCS_VALUES = dict(
    canvas=(64, 48),
    floor={"Color": (0.8, 0.8, 0.8)},
    walls=[
        {"a": (8, 24), "through": (32, 2), "b": (56, 24)},
        {"a": (56, 24), "through": (32, 46), "b": (8, 24), "emit": {"intensity": 0.2}},
        {"center": (22, 20), "radius": 3, "material": "Mirror"},
    ],
    lights=[{"Point": {"at": (40, 20), "intensity": 3}}],
    glass=[{"points": [(30, 26), (30, 38)], "through": [(33, 32), (27, 32)]}],
    render={"samples": 8, "bounces": 2},
)


def test_arcs_from_python_render_the_clis_bits(cli, tmp_path):
    path = tmp_path / "arcs.ron"
    path.write_text(ARCS_RON)
    expected = cli_render(cli, path, tmp_path / "cli.exr", "--seed", "7")
    built = flatray.Scene(**ARCS_VALUES)
    assert built.counts["walls"] == 3
    got = flatray.render(built, seed=7)
    assert np.array_equal(got.image, expected)
    assert got.image.max() > 0
    with pytest.raises(flatray.SceneError) as caught:
        flatray.Scene(**{**ARCS_VALUES, "walls": [{"a": (1, 1), "through": (2, 2), "b": (3, 3)}]})
    assert "one line" in caught.value.message


def test_the_image_is_height_by_width_by_three_float32(repo):
    scene = flatray.load(repo / "scenes" / "room.ron")
    result = flatray.render(scene, spp=2, scale=0.1)
    assert result.image.shape == (50, 50, 3)
    assert result.image.dtype == np.float32
    assert result.image.flags["C_CONTIGUOUS"]
    assert result.image.max() > 0
    assert 0 < result.noise < 1
    assert result.stats["physics"]["camera_samples"] == 50 * 50 * 2
    assert result.settings["spp"] == 2 and result.settings["scale"] == 0.1


def test_a_bad_scene_file_raises_with_its_file_line_and_column(tmp_path):
    path = tmp_path / "bad.ron"
    path.write_text(
        "Scene(\n    canvas: (10, 10),\n    floor: Color((1, 1, 1)),\n"
        "    lights: [Point(at: (5, 5), intensity: -2)],\n)\n"
    )
    with pytest.raises(flatray.SceneError) as caught:
        flatray.load(path)
    error = caught.value
    assert error.file == str(path)
    assert (error.line, error.column) == (4, 43)
    assert "expected an intensity from 0 to 1e9, found -2" in error.message
    assert str(error).startswith(f"{path}:4:43: ")
    assert isinstance(error, ValueError)


def test_a_bad_scene_text_and_bad_values_raise_where_they_are_wrong():
    with pytest.raises(flatray.SceneError) as caught:
        flatray.parse("Scene(canvas: (10, 10), floor: Colour((1, 1, 1)))", name="mine.ron")
    assert caught.value.file == "mine.ron" and caught.value.line == 1
    assert "Colour" in caught.value.message
    values = dict(ROOM_VALUES)
    values["lights"] = [{"Spot": {"at": (1, 1), "direction": (1, 0), "cone": 200}}]
    with pytest.raises(flatray.SceneError) as caught:
        flatray.Scene(**values)
    assert caught.value.at == "lights[0].Spot.cone", caught.value.at
    assert caught.value.line is None and caught.value.file is None
    assert "cone" in caught.value.message
    values["lights"] = [{"Point": {"at": (1, 1), "intensty": 2}}]
    with pytest.raises(flatray.SceneError) as caught:
        flatray.Scene(**values)
    assert "did you mean `intensity`?" in caught.value.message, caught.value.message
    values["lights"] = [{"Point": {"at": (1, float("nan"))}}]
    with pytest.raises(flatray.SceneError) as caught:
        flatray.Scene(**values)
    assert caught.value.at == "lights[0].Point.at[1]", caught.value.at
    values["lights"] = [{"Point": {"at": (1, "x")}}]
    with pytest.raises(flatray.SceneError) as caught:
        flatray.Scene(**values)
    assert caught.value.at.startswith("lights[0].Point.at")
    values = dict(ROOM_VALUES, walls=[{"a": (1, 1), "b": (5, 5), "material": {"Rough": {"roughness": 2}}}])
    with pytest.raises(flatray.SceneError) as caught:
        flatray.Scene(**values)
    assert caught.value.at == "walls[0].material.roughness"
    assert "`roughness` is from 0" in caught.value.message


def test_warnings_name_what_would_render_wrong():
    dark = flatray.Scene(canvas=(20, 20), floor={"Color": (1, 1, 1)},
                         walls=[{"a": (30, 30), "b": (40, 40)}])
    said = [w["message"] for w in dark.warnings]
    assert any("no lights" in m for m in said), said
    assert any("wall 0 lies wholly outside the canvas" in m for m in said), said
    assert all(w["line"] is None for w in dark.warnings)
    text = flatray.parse("Scene(canvas: (20, 20), floor: Color((1, 1, 1)))")
    assert text.warnings[0]["line"] == 1
    assert not flatray.Scene(**ROOM_VALUES).warnings


def test_bad_render_settings_raise_value_errors():
    scene = flatray.Scene(**ROOM_VALUES)
    for bad in [dict(spp=0), dict(integrator="photon"), dict(cache="maybe"), dict(scale=0),
                dict(indirect="rays"),
                dict(window=(0, 0, 100, 10)), dict(exposure=-1), dict(threads=0)]:
        with pytest.raises(ValueError):
            flatray.render(scene, **bad)


def test_the_gil_is_released_while_rendering(repo):
    scene = flatray.load(repo / "scenes" / "room.ron")
    ticks = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    ticker = threading.Thread(target=tick)
    ticker.start()
    try:
        started = time.perf_counter()
        result = flatray.render(scene, spp=16, bounces=2, threads=1)
        ended = time.perf_counter()
    finally:
        stop.set()
        ticker.join()
    assert ended - started > 0.3, "the render is too short to tell"
    during = [t for t in ticks if started + 0.05 < t < ended - 0.05]
    # Held, the GIL would let the ticker run only before and after.
    assert len(during) > 0.5 * (ended - started - 0.1) / 0.02, (len(during), ended - started)
    assert result.image.max() > 0


def test_progress_is_reported_and_can_stop_a_render(repo):
    scene = flatray.load(repo / "scenes" / "room.ron")
    heard = []
    result = flatray.render(scene, spp=32, threads=1, progress=lambda done, total: heard.append((done, total)))
    assert len(heard) >= 2, heard
    total = heard[-1][1]
    assert total == 500 * 500 * 32 and heard[-1] == (total, total)
    assert all(a[0] <= b[0] for a, b in zip(heard, heard[1:]))
    assert any(0 < done < total for done, _ in heard[:-1]), heard
    assert result.image.max() > 0

    class Enough(Exception):
        pass

    def stop(done, total):
        if done > 0:
            raise Enough

    started = time.perf_counter()
    with pytest.raises(Enough):
        flatray.render(scene, spp=100000, progress=stop)
    assert time.perf_counter() - started < 20


def test_ctrl_c_stops_a_render(repo):
    script = (
        "import flatray, sys, time\n"
        f"scene = flatray.load({str(repo / 'scenes' / 'room.ron')!r})\n"
        "print('rendering', flush=True)\n"
        "started = time.perf_counter()\n"
        "try:\n"
        "    flatray.render(scene, spp=100000)\n"
        "except KeyboardInterrupt:\n"
        "    print(f'interrupted after {time.perf_counter() - started:.1f}', flush=True)\n"
        "    sys.exit(3)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "rendering"
    time.sleep(1.0)
    child.send_signal(__import__("signal").SIGINT)
    try:
        code = child.wait(timeout=30)
    finally:
        child.kill()
    assert code == 3, child.stdout.read()


def test_generate_gives_the_clis_plan(cli, tmp_path):
    out = tmp_path / "plan.ron"
    subprocess.run([cli, "generate", "--rooms", "3", "--lamps", "2", "--seed", "7", "-o", str(out)],
                   check=True, capture_output=True)
    scene = flatray.generate(rooms=3, lamps=2, seed=7)
    assert scene.text == out.read_text()
    assert scene.counts["lights"] >= 6


def test_import_plan_gives_the_clis_scene(cli, tmp_path):
    svg = tmp_path / "plan.svg"
    svg.write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" width="100" height="80">'
        '<rect x="10" y="10" width="80" height="60" fill="none" stroke="black"/>'
        '<circle cx="50" cy="40" r="2" fill="yellow"/></svg>'
    )
    scene = flatray.import_plan(svg)
    out = tmp_path / "plan.ron"
    subprocess.run([cli, "import", str(svg), "-o", str(out)], check=True, capture_output=True)
    assert scene.text == out.read_text()
    assert scene.canvas == (100, 80)
    assert scene.counts["walls"] > 0


def test_import_plan_of_a_map_writes_what_the_cli_writes(cli, repo, tmp_path):
    tavern = repo / "scenes" / "maps" / "tavern.dd2vtt"
    (tmp_path / "cli").mkdir()
    (tmp_path / "py").mkdir()
    subprocess.run([cli, "import", str(tavern), "--doors", "open", "-o", str(tmp_path / "cli" / "tavern.ron")],
                   check=True, capture_output=True)
    scene = flatray.import_plan(tavern, doors="open", output=tmp_path / "py" / "tavern.ron")
    for name in ["tavern.ron", "tavern-floor.png"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert scene.text == (tmp_path / "cli" / "tavern.ron").read_text()
    assert scene.canvas == (896, 640)
    assert scene.counts["lights"] == 3
    assert any("2 doors open" in n for n in scene.import_notes)
    # The same image rendered from either file.
    ours = flatray.render(scene, spp=1, scale=0.125)
    theirs = flatray.render(flatray.load(tmp_path / "cli" / "tavern.ron"), spp=1, scale=0.125)
    assert np.array_equal(ours.image, theirs.image)
    assert ours.image.max() > 0
    # Neither file is replaced without force.
    with pytest.raises(ValueError, match="the file exists"):
        flatray.import_plan(tavern, output=tmp_path / "py" / "tavern.ron")
    # Without output nothing is written and the floor is plain.
    plain = flatray.import_plan(tavern, lights="none")
    assert plain.counts["lights"] == 0
    assert any("not written without output=" in n for n in plain.import_notes)
    with pytest.raises(ValueError, match="doors: expected"):
        flatray.import_plan(tavern, doors="ajar")


def test_a_window_has_the_whole_renders_bits():
    scene = flatray.Scene(**ROOM_VALUES)
    whole = flatray.render(scene, spp=4)
    part = flatray.render(scene, spp=4, window=(7, 19, 41, 33))
    assert np.array_equal(part.image[19:33, 7:41], whole.image[19:33, 7:41])
    outside = part.image.copy()
    outside[19:33, 7:41] = 0
    assert not outside.any()


def test_scenes_pickle_and_write(tmp_path):
    import pickle

    for scene in [flatray.Scene(**ROOM_VALUES), flatray.parse(ROOM_RON)]:
        again = pickle.loads(pickle.dumps(scene))
        assert np.array_equal(flatray.render(again, spp=2).image, flatray.render(scene, spp=2).image)
    result = flatray.render(flatray.parse(ROOM_RON), spp=2)
    result.write(tmp_path / "out.exr")
    assert np.array_equal(flatray.read_exr(tmp_path / "out.exr"), result.image)
    result.write(tmp_path / "out.png")
    assert (tmp_path / "out.png").read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(OSError):
        result.write(tmp_path / "out.tiff")


def test_the_floors_indirect_light_along_lines_or_by_samples(repo):
    scene = flatray.load(repo / "scenes" / "room.ron")
    lines = flatray.render(scene, spp=16, scale=0.25, seed=3)
    samples = flatray.render(scene, spp=16, scale=0.25, seed=3, indirect="samples")
    assert samples.settings["indirect"] == "samples"
    assert lines.stats["work"]["lines"] > 0 and samples.stats["work"]["lines"] == 0
    # The same image, in expectation; along lines, far less noise.
    assert abs(lines.image.mean() / samples.image.mean() - 1) < 0.03
    assert lines.noise < samples.noise / 2


@pytest.mark.parametrize(
    "keyword, value, error, says",
    [
        ("spp", -1, ValueError, "spp: expected 1 to 1048576, found -1"),
        ("spp", 2**64, ValueError, "spp: expected 1 to 1048576"),
        ("spp", 0, ValueError, "spp: expected 1 to"),
        ("spp", 1.5, TypeError, "spp: expected a whole number"),
        ("spp", "4", TypeError, "spp: expected a whole number"),
        ("bounces", -1, ValueError, "bounces: expected 0 to 1000, found -1"),
        ("bounces", 2**64, ValueError, "bounces: expected 0 to 1000"),
        ("specular", -1, ValueError, "specular: expected 0 to 1000"),
        ("seed", -1, ValueError, "seed: expected 0 to 18446744073709551615, found -1"),
        ("seed", 2**64, ValueError, "seed: expected 0 to 18446744073709551615"),
        ("threads", -1, ValueError, "threads: expected 1 to 1024, found -1"),
        ("threads", 2**64, ValueError, "threads: expected 1 to 1024"),
        ("window", (-1, 0, 4, 4), ValueError, "window x0: expected 0 to 4294967295, found -1"),
        ("window", (0, 0, 2**64, 4), ValueError, "window x1: expected 0 to 4294967295"),
        ("window", (0, 0, 4), ValueError, "window: expected (x0, y0, x1, y1)"),
        ("window", 5, TypeError, "window: expected (x0, y0, x1, y1)"),
        ("scale", "big", TypeError, "scale: expected a number"),
    ],
)
def test_every_bad_setting_names_itself_and_its_range(keyword, value, error, says):
    scene = flatray.Scene(**ROOM_VALUES)
    with pytest.raises(error) as caught:
        flatray.render(scene, **{keyword: value})
    assert says in str(caught.value), str(caught.value)
    assert not isinstance(caught.value, OverflowError)


def test_generate_names_a_bad_count():
    for keyword, value, says in [
        ("rooms", -1, "rooms: expected 1 to 10000, found -1"),
        ("lamps", 2**64, "lamps: expected 0 to 64"),
        ("seed", -1, "seed: expected 0 to"),
    ]:
        with pytest.raises(ValueError) as caught:
            flatray.generate(**{keyword: value})
        assert says in str(caught.value), str(caught.value)


def test_a_pipe_is_refused_not_waited_on(tmp_path):
    fifo = tmp_path / "image.exr"
    os.mkfifo(fifo)
    scene_fifo = tmp_path / "scene.ron"
    os.mkfifo(scene_fifo)
    ticks = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(1)
            stop.wait(0.01)

    # Another Python thread runs while the reads are refused: nothing
    # holds the GIL, and nothing waits for a writer.
    ticker = threading.Thread(target=tick)
    ticker.start()
    try:
        with pytest.raises(OSError) as caught:
            flatray.read_exr(fifo)
        assert "not a regular file" in str(caught.value)
        with pytest.raises(flatray.SceneError) as caught:
            flatray.load(scene_fifo)
        assert "not a regular file" in str(caught.value)
    finally:
        stop.set()
        ticker.join()
    assert ticks


def test_a_scene_of_values_has_its_text_and_it_loads_back_to_the_same_bits():
    scene = flatray.Scene(**ROOM_VALUES)
    text = scene.text
    assert text.startswith("Scene(\n"), text
    again = flatray.parse(text)
    assert again.text == text
    a = flatray.render(scene, spp=4, scale=0.5, seed=3)
    b = flatray.render(again, spp=4, scale=0.5, seed=3)
    assert np.array_equal(a.image, b.image)
    assert again.settings == scene.settings and again.counts == scene.counts
    # Every kind the format has, round the same way.
    every = flatray.Scene(
        canvas=(120, 80),
        floor={"Tiles": {"size": 20, "tile": (0.7, 0.7, 0.6)}},
        walls=[
            {"a": (10, 10), "b": (60, 10), "through": (35, 20), "material": {"Rough": {"roughness": 0.2}}},
            {"center": (90, 40), "radius": 10, "material": {"Transparent": {"tint": (0.5, 0.6, 1)}}},
            {"a": (0, 70), "b": (50, 70), "emit": {"intensity": 2}},
            {"a": (100, 5), "b": (110, 30), "material": "Mirror"},
        ],
        lights=[
            {"Spot": {"at": (20, 20), "direction": (1, 0.25), "cone": 30, "spectrum": {"Blackbody": 2700}}},
            {"Line": {"a": (10, 75), "b": (40, 75), "spectrum": {"Table": [(400, 0.1), (550, 1), (700, 0.4)]}}},
            {"Laser": {"at": (5, 40), "direction": (1, 0.1), "spectrum": {"Lamp": "Sodium"}}},
        ],
        glass=[{"points": [(60, 40), (75, 40), (68, 60)], "through": [None, (74, 52), None], "ior": 1.6}],
        falloff="Flatland",
        render={"samples": 4, "integrator": "Light", "cache": "Direct"},
    )
    back = flatray.parse(every.text)
    a = flatray.render(every, spp=2, scale=0.5)
    b = flatray.render(back, spp=2, scale=0.5)
    assert np.array_equal(a.image, b.image)
    # A scene read from a file keeps the file's own text.
    text = "Scene(canvas: (10, 10), floor: Color((1, 1, 1)))  // mine"
    assert flatray.parse(text).text == text


def test_measure_gives_the_clis_figures_and_the_grid_as_an_array(cli, repo, tmp_path):
    scene_path = repo / "scenes" / "daylight.ron"
    csv = tmp_path / "grid.csv"
    out = subprocess.run(
        [cli, "measure", str(scene_path), "--spp", "8", "--scale", "0.5",
         "--json", "--quiet", "--csv", str(csv)],
        check=True, capture_output=True, text=True,
    ).stdout
    expected = json.loads(out)
    got = flatray.measure(flatray.load(scene_path), spp=8, scale=0.5)
    grid = got.pop("grid")
    assert got == expected
    rows = np.loadtxt(csv, delimiter=",", skiprows=1, usecols=(0, 1, 3, 4))
    assert grid.shape == (len(rows), 5)
    assert np.array_equal(grid[:, [0, 1, 3, 4]], rows)
    names = [r["name"] for r in got["rooms"]]
    assert names == ["living", "bedroom"]
    # Each room's E_avg is its grid points' mean.
    for k, room in enumerate(got["rooms"]):
        assert np.isclose(grid[grid[:, 2] == k, 3].mean(), room["e_avg"]["value"], rtol=1e-12)
    with pytest.raises(ValueError, match="batches"):
        flatray.measure(flatray.load(scene_path), batches=1)


def test_measure_to_a_target_error_gives_the_clis_figures(cli, repo):
    scene_path = repo / "scenes" / "daylight.ron"
    out = subprocess.run(
        [cli, "measure", str(scene_path), "--spp", "8", "--scale", "0.5",
         "--target-error", "1", "--json", "--quiet"],
        check=True, capture_output=True, text=True,
    ).stdout
    expected = json.loads(out)
    got = flatray.measure(flatray.load(scene_path), spp=8, scale=0.5, target_error=1)
    got.pop("grid")
    assert got == expected
    assert got["target_error"] == {"percent": 1.0, "met": True}
    # 8 spp over 8 batches is 1 a batch: the rounds doubled it.
    assert got["batch_spp"] > 1
    for room in got["rooms"]:
        for name in ("e_min", "e_avg", "u0"):
            assert room[name]["se"] <= 0.01 * room[name]["value"]
    with pytest.raises(ValueError, match="target error"):
        flatray.measure(flatray.load(scene_path), target_error=0)
