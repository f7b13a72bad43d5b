"""Many renders on Ray: a batch of scenes, many seeds of a generated
plan, or one large render split into tiles.

Every render is keyed by (seed, pixel, sample), so where it runs changes
no bit: a batch gives the images that one ``flatray render`` per scene
gives, and a render split into tiles, put back together, is the single
render bit for bit.

On one machine, ``ray.init()`` starts a local Ray with a worker per core.
On a cluster, start Ray there (``ray start --head`` on one node, ``ray
start --address=HEAD:6379`` on the others) and call
``ray.init(address="auto")`` (or set ``RAY_ADDRESS``) before these
functions: they only submit tasks. Images come back to the caller, which
writes them, so the workers need no shared disk.

Each task renders with ``threads`` threads (one by default) and asks Ray
for as many CPUs, so a machine's cores are shared among tasks, not
oversubscribed.
"""

from __future__ import annotations

import json
import os
import time
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np

import flatray

#: The side of the square tiles the renderer works in: windows whose
#: edges fall on it split a render the way the renderer does.
TILE = 16


def _ray() -> Any:
    try:
        import ray
    except ImportError as e:  # pragma: no cover - said to the user
        raise ImportError(
            "flatray.batch needs Ray: pip install 'ray>=2.9' (or the package's [ray] extra)"
        ) from e
    if not ray.is_initialized():
        ray.init()
    return ray


def _render_task(scene: flatray.Scene, settings: Dict[str, Any]) -> Tuple[np.ndarray, Dict[str, Any], float]:
    result = flatray.render(scene, **settings)
    image = result.image
    if result.window is not None:
        x0, y0, x1, y1 = result.window
        image = image[y0:y1, x0:x1].copy()
    return image, result.stats, result.seconds


def _remote(threads: int) -> Any:
    ray = _ray()
    return ray.remote(num_cpus=threads)(_render_task)


def render_scenes(
    scenes: Sequence[flatray.Scene],
    out: Optional[os.PathLike] = None,
    *,
    names: Optional[Sequence[str]] = None,
    threads: int = 1,
    **settings: Any,
) -> List[Dict[str, Any]]:
    """Renders every scene as a Ray task, with ``settings`` as
    :func:`flatray.render` takes them. Returns one record per scene, in
    order: ``{"name", "image", "settings", "noise", "seconds", "stats"}``
    (``image`` the array). With ``out``, writes ``NAME.exr`` there for each
    and appends a JSON line per scene to ``out/renders.jsonl`` (the record
    without the image and statistics, and the file's name)."""
    names = list(names) if names is not None else [f"scene-{k:04d}" for k in range(len(scenes))]
    if len(names) != len(scenes):
        raise ValueError(f"names: expected {len(scenes)}, found {len(names)}")
    ray = _ray()
    task = _remote(threads)
    settings = dict(settings, threads=threads)
    started = time.perf_counter()
    refs = [task.remote(scene, settings) for scene in scenes]
    records = []
    for name, scene, ref in zip(names, scenes, refs):
        image, stats, seconds = ray.get(ref)
        chosen = dict(scene.settings)
        chosen.update({k: v for k, v in settings.items() if v is not None and k != "threads"})
        records.append(
            {
                "name": name,
                "image": image,
                "settings": chosen,
                "noise": stats["noise"]["relmse"],
                "seconds": seconds,
                "stats": stats,
            }
        )
    if out is not None:
        _write(records, out, time.perf_counter() - started)
    return records


def render_generated(
    seeds: Iterable[int],
    out: Optional[os.PathLike] = None,
    *,
    rooms: int = 16,
    lamps: int = 1,
    mirrors: float = 0.3,
    sun: bool = True,
    threads: int = 1,
    **settings: Any,
) -> List[Dict[str, Any]]:
    """Generates a plan per seed (as :func:`flatray.generate`) and renders
    them all as in :func:`render_scenes`; each record also has its
    ``seed``."""
    seeds = list(seeds)
    scenes = [flatray.generate(rooms=rooms, lamps=lamps, mirrors=mirrors, seed=s, sun=sun) for s in seeds]
    names = [f"plan-{s}" for s in seeds]
    records = render_scenes(scenes, None, names=names, threads=threads, **settings)
    for seed, record in zip(seeds, records):
        record["seed"] = seed
        record["settings"].update({"rooms": rooms, "lamps": lamps, "mirrors": mirrors, "sun": sun})
    if out is not None:
        _write(records, out, None)
    return records


def _write(records: List[Dict[str, Any]], out: os.PathLike, seconds: Optional[float]) -> None:
    folder = os.fspath(out)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "renders.jsonl"), "a", encoding="utf-8") as lines:
        for record in records:
            path = os.path.join(folder, f"{record['name']}.exr")
            _write_exr(record["image"], path)
            line = {k: v for k, v in record.items() if k not in ("image", "stats")}
            line["exr"] = os.path.basename(path)
            lines.write(json.dumps(line) + "\n")


def _write_exr(image: np.ndarray, path: str) -> None:
    image = np.ascontiguousarray(image, dtype="<f4")
    height, width, _ = image.shape
    flatray._flatray.write_image(path, image.tobytes(), width, height, None)


def bands(height: int, count: int) -> List[Tuple[int, int]]:
    """``count`` bands of rows (fewer for a short image) whose edges fall
    on the renderer's tiles: (first row, end row) each."""
    tiles = max(1, -(-height // TILE))
    count = max(1, min(count, tiles))
    edges = [round(k * tiles / count) * TILE for k in range(count + 1)]
    edges[-1] = height
    return [(a, min(b, height)) for a, b in zip(edges, edges[1:]) if a < min(b, height)]


def render_tiled(
    scene: flatray.Scene,
    *,
    tiles: Optional[int] = None,
    threads: int = 1,
    **settings: Any,
) -> flatray.Rendered:
    """One render split into bands of rows, each a Ray task, put back
    together: the single render's image, bit for bit. ``tiles`` is the
    number of bands (twice Ray's CPUs by default). The noise estimate is
    put together from the bands' sums: the single render's to rounding.

    Each task builds what the whole render shares (the wall memo, a
    caustic pass, a light table) for itself, so a band costs more than its
    share of the single render; the light tracer traces every path in
    each task."""
    ray = _ray()
    scale = settings.get("scale", 1.0)
    width, height = scene._loaded.image_size(scale)
    if tiles is None:
        tiles = max(1, 2 * int(ray.cluster_resources().get("CPU", 1)))
    task = _remote(threads)
    started = time.perf_counter()
    parts = bands(height, tiles)
    refs = [
        task.remote(scene, dict(settings, window=(0, y0, width, y1), threads=threads))
        for y0, y1 in parts
    ]
    image = np.zeros((height, width, 3), dtype=np.float32)
    stats: Optional[Dict[str, Any]] = None
    for (y0, y1), ref in zip(parts, refs):
        band, band_stats, _ = ray.get(ref)
        image[y0:y1] = band
        stats = band_stats if stats is None else _merge(stats, band_stats)
    assert stats is not None
    _finish_noise(stats)
    chosen = dict(scene.settings)
    chosen.update({k: v for k, v in settings.items() if v is not None})
    return flatray.Rendered(
        image, stats, time.perf_counter() - started, chosen, None, scene._loaded.white
    )


def _merge(a: Dict[str, Any], b: Dict[str, Any]) -> Dict[str, Any]:
    """The statistics of two renders of disjoint windows: counts add, and
    so do the noise's sums."""
    out: Dict[str, Any] = {}
    for key, value in a.items():
        other = b.get(key)
        if isinstance(value, dict):
            out[key] = _merge(value, other or {})
        elif isinstance(value, list) and isinstance(other, list):
            out[key] = [x + y for x, y in zip(value, other)]
        elif isinstance(value, (int, float)) and isinstance(other, (int, float)) and not isinstance(value, bool):
            out[key] = value + other
        else:
            out[key] = value
    return out


def _finish_noise(stats: Dict[str, Any]) -> None:
    noise = stats["noise"]
    error = sum(noise["error_squared"])
    value = sum(noise["value_squared"])
    noise["relative"] = (error / value) ** 0.5 if noise["pixels"] > 0 and value > 0 else None
    noise["relmse"] = (
        (noise["relative_squared"] / (3 * noise["pixels"])) ** 0.5
        if noise["pixels"] > 0 and value > 0
        else None
    )
    noise["relative_per_channel"] = (
        [(e / v) ** 0.5 if v > 0 else 0.0 for e, v in zip(noise["error_squared"], noise["value_squared"])]
        if noise["pixels"] > 0
        else None
    )
