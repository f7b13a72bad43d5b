"""Batches and tiles on a local Ray of two workers, against the CLI and
against the single render."""

import json
import subprocess

import numpy as np
import pytest

import flatray

ray = pytest.importorskip("ray")
from flatray import batch  # noqa: E402


@pytest.fixture(scope="module")
def local_ray():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


def test_a_batch_of_generated_plans_gives_the_clis_images(local_ray, cli, tmp_path):
    seeds = list(range(11, 19))
    records = batch.render_generated(
        seeds, tmp_path / "out", rooms=3, lamps=2, spp=4, bounces=1, scale=0.25
    )
    assert [r["seed"] for r in records] == seeds
    lines = [json.loads(l) for l in (tmp_path / "out" / "renders.jsonl").read_text().splitlines()]
    assert [l["seed"] for l in lines] == seeds
    for seed, record, line in zip(seeds, records, lines):
        plan = tmp_path / f"plan-{seed}.ron"
        subprocess.run([cli, "generate", "--rooms", "3", "--lamps", "2", "--seed", str(seed),
                        "-o", str(plan)], check=True, capture_output=True)
        exr = tmp_path / f"cli-{seed}.exr"
        subprocess.run([cli, "render", str(plan), "-o", str(exr), "-q", "--spp", "4",
                        "--bounces", "1", "--scale", "0.25"], check=True)
        expected = flatray.read_exr(exr)
        assert np.array_equal(record["image"], expected), seed
        assert np.array_equal(flatray.read_exr(tmp_path / "out" / line["exr"]), expected)
        assert line["settings"]["spp"] == 4 and line["seconds"] > 0
        assert 0 < line["noise"] < 1


def test_one_render_split_into_tiles_is_the_single_render(local_ray, repo):
    scene = flatray.load(repo / "scenes" / "room.ron")
    settings = dict(spp=8, bounces=1, scale=0.3)
    single = flatray.render(scene, **settings)
    tiled = batch.render_tiled(scene, tiles=5, **settings)
    assert np.array_equal(tiled.image, single.image)
    assert tiled.stats["physics"]["camera_samples"] == single.stats["physics"]["camera_samples"]
    assert tiled.noise == pytest.approx(single.noise, rel=1e-9)
    # And with the light tracer, whose every task traces every path.
    light = dict(settings, integrator="light")
    assert np.array_equal(batch.render_tiled(scene, tiles=3, **light).image,
                          flatray.render(scene, **light).image)


def test_a_tiled_render_has_the_renders_size_where_the_scale_rounds(local_ray):
    # 45 x 33 at 0.5 is 22.5 x 16.5: the renderer rounds halves up.
    scene = flatray.Scene(canvas=(45, 33), floor={"Color": (1, 1, 1)},
                          lights=[{"Point": {"at": (20, 15)}}])
    single = flatray.render(scene, spp=2, scale=0.5)
    assert single.image.shape == (17, 23, 3)
    assert np.array_equal(batch.render_tiled(scene, tiles=2, spp=2, scale=0.5).image, single.image)


def test_bands_fall_on_tiles():
    assert batch.bands(150, 4) == [(0, 32), (32, 80), (80, 128), (128, 150)]
    assert batch.bands(10, 4) == [(0, 10)]
    for height in [1, 16, 17, 500]:
        for count in [1, 2, 3, 7]:
            parts = batch.bands(height, count)
            assert parts[0][0] == 0 and parts[-1][1] == height
            assert all(a % 16 == 0 and a < b for a, b in parts)
            assert all(p[1] == q[0] for p, q in zip(parts, parts[1:]))
