"""flatray: a 2D Monte Carlo path tracer for floor plans.

Load a scene, render it, get a NumPy array back::

    import flatray

    scene = flatray.load("scenes/room.ron")
    result = flatray.render(scene, spp=64, bounces=1)
    result.image        # (height, width, 3) float32, linear
    result.noise        # the render's estimate of its own error (relMSE's root)
    result.write("room.png")

A scene can also be built from plain Python values, named as the RON
scene format names them (``docs/scene-format.md``)::

    scene = flatray.Scene(
        canvas=(200, 100),
        floor={"Color": (0.8, 0.8, 0.8)},
        walls=[{"a": (100, 10), "b": (100, 60), "material": "Mirror"}],
        lights=[{"Point": {"at": (50, 50), "intensity": 2.0}}],
    )

A render is the library's render, bit for bit the one ``flatray render``
writes for the same scene and settings. Batches of scenes, and one render
split into tiles, run on Ray with :mod:`flatray.batch`.
"""

from __future__ import annotations

import json
import math
import operator
import os
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _flatray
from ._flatray import SceneError

__version__: str = _flatray.__version__

__all__ = [
    "Rendered",
    "Scene",
    "SceneError",
    "generate",
    "import_plan",
    "load",
    "measure",
    "parse",
    "read_exr",
    "render",
]

PathLike = Union[str, "os.PathLike[str]"]

# Material variants that take fields; a bare name stands for all defaults.
_STRUCT_VARIANTS = {"Diffuse", "Mirror", "Rough", "Transparent"}


def _plain(value: Any) -> Any:
    """`value` as JSON's types: tuples and NumPy values become lists and
    numbers."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return _plain(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        # JSON has no NaN: said as a string, it fails where it stands
        # ("invalid type: string "nan", expected f64").
        return repr(value)
    return value


# The ranges of the whole-number settings, as the command line takes them.
_MAX_SAMPLES = 1 << 20
_MAX_BOUNCES = 1000
_MAX_U64 = (1 << 64) - 1
_MAX_U32 = (1 << 32) - 1


def _whole(name: str, value: Any, lo: int, hi: int) -> int:
    """``value`` as an int from ``lo`` to ``hi``: a TypeError naming
    ``name`` when it is not a whole number, a ValueError with the range
    when it is out of it."""
    if isinstance(value, bool):
        raise TypeError(f"{name}: expected a whole number from {lo} to {hi}, found {value!r}")
    try:
        n = operator.index(value)
    except TypeError:
        raise TypeError(
            f"{name}: expected a whole number from {lo} to {hi}, found {type(value).__name__} {value!r}"
        ) from None
    if not lo <= n <= hi:
        raise ValueError(f"{name}: expected {lo} to {hi}, found {n}")
    return n


def _maybe_whole(name: str, value: Any, lo: int, hi: int) -> Optional[int]:
    return None if value is None else _whole(name, value, lo, hi)


def _wall(wall: Any) -> Any:
    if isinstance(wall, dict) and isinstance(wall.get("material"), str):
        name = wall["material"]
        if name in _STRUCT_VARIANTS:
            wall = dict(wall, material={name: {}})
    return wall


class Scene:
    """A validated scene with the render settings it asks for.

    Build one from plain values (the keywords are the scene format's
    fields), or get one from :func:`load`, :func:`parse`,
    :func:`generate` or :func:`import_plan`. A scene that is not valid
    raises :class:`SceneError`; for values, its ``at`` names the value by
    its path, as ``lights[2].Spot.cone``.

    Scenes are immutable and can be pickled (to send them to Ray workers).
    """

    __slots__ = ("_loaded", "_source", "_notes")

    def __init__(
        self,
        *,
        floor: Any,
        canvas: Optional[Tuple[int, int]] = None,
        origin: Optional[Tuple[float, float]] = None,
        walls: Iterable[Any] = (),
        lights: Iterable[Any] = (),
        glass: Iterable[Any] = (),
        falloff: Any = None,
        small_radius: Optional[float] = None,
        render: Optional[Dict[str, Any]] = None,
        base: PathLike = ".",
    ) -> None:
        values: Dict[str, Any] = {"floor": floor}
        if canvas is not None:
            values["canvas"] = canvas
        if origin is not None:
            values["origin"] = origin
        values["walls"] = [_wall(w) for w in walls]
        values["lights"] = list(lights)
        values["glass"] = list(glass)
        if falloff is not None:
            values["falloff"] = falloff
        if small_radius is not None:
            values["small_radius"] = small_radius
        if render is not None:
            values["render"] = render
        text = json.dumps(_plain(values))
        # Absolute, so that a scene sent to another process finds its files.
        base = os.path.abspath(os.fspath(base))
        self._loaded = _flatray.from_json(text, "<values>", base)
        self._source = ("json", text, "<values>", base)
        self._notes: List[str] = []

    @classmethod
    def _of(
        cls, loaded: Any, source: Tuple[str, str, str, str], notes: Sequence[str] = ()
    ) -> "Scene":
        scene = cls.__new__(cls)
        scene._loaded = loaded
        scene._source = source
        scene._notes = list(notes)
        return scene

    def __reduce__(self) -> Any:
        return (_restore, self._source)

    @property
    def canvas(self) -> Tuple[int, int]:
        """The canvas's size in pixels at scale 1: (width, height)."""
        return self._loaded.canvas

    @property
    def counts(self) -> Dict[str, int]:
        """What the scene lists: walls, emitting walls, lights, glass."""
        walls, emitting, lights, glass = self._loaded.counts
        return {"walls": walls, "emitting_walls": emitting, "lights": lights, "glass": glass}

    @property
    def warnings(self) -> List[Dict[str, Any]]:
        """What would render otherwise than it reads, as ``flatray check``
        warns of it: ``{"line", "column", "message"}`` each (line and
        column None for a scene built from values; the message names the
        item by its index)."""
        return [
            {"line": l or None, "column": c or None, "message": m}
            for l, c, m in self._loaded.warnings
        ]

    @property
    def text(self) -> str:
        """The scene's text in the scene file's format (RON): the file's
        own text for a scene read from text, and for one built from values
        the text of those values, which loads back as the same scene (save
        it to a ``.ron`` file to edit or render it with the command
        line)."""
        kind, payload = self._source[0], self._source[1]
        if kind == "json":
            return _flatray.values_text(payload)
        text = self._loaded.text
        return payload if text is None else text

    @property
    def settings(self) -> Dict[str, Any]:
        """The render settings the scene asks for, by :func:`render`'s
        keywords."""
        spp, bounces, specular, seed, exposure, integrator, cache, caustics = self._loaded.settings
        return {
            "spp": spp,
            "bounces": bounces,
            "specular": specular,
            "seed": seed,
            "exposure": exposure,
            "integrator": integrator,
            "cache": cache,
            "caustics": caustics,
        }

    @property
    def import_notes(self) -> List[str]:
        """What :func:`import_plan` did not import, one line each."""
        return list(self._notes)

    def plan(self) -> str:
        """Which effects a render with the scene's settings simulates,
        which it skips, and why (as ``flatray plan`` prints it)."""
        return self._loaded.plan()

    def __repr__(self) -> str:
        c = self.counts
        w, h = self.canvas
        return (
            f"<flatray.Scene {w} x {h}, {c['walls']} walls, {c['lights']} lights, "
            f"{c['glass']} glass>"
        )


def _restore(kind: str, payload: str, name: str, base: str) -> Scene:
    if kind == "json":
        loaded = _flatray.from_json(payload, name, base)
    else:
        loaded = _flatray.parse(payload, name, base)
    return Scene._of(loaded, (kind, payload, name, base))


def load(path: PathLike) -> Scene:
    """Reads and validates the scene file at ``path``; relative paths in
    it resolve against its folder. Raises :class:`SceneError` with the
    file, line and column of what is wrong."""
    path = os.fspath(path)
    loaded = _flatray.load(path)
    base = os.path.dirname(os.path.abspath(path))
    text = loaded.text if loaded.text is not None else ""
    return Scene._of(loaded, ("ron", text, path, base))


def parse(text: str, name: str = "<string>", base: PathLike = ".") -> Scene:
    """Parses and validates scene ``text`` (RON, as a scene file holds
    it); ``name`` names it in messages, and relative paths resolve
    against ``base``."""
    base = os.path.abspath(os.fspath(base))
    return Scene._of(_flatray.parse(text, name, base), ("ron", text, name, base))


def generate(
    rooms: int = 16, lamps: int = 1, mirrors: float = 0.3, seed: int = 1, sun: bool = True
) -> Scene:
    """A generated apartment, as ``flatray generate`` writes it: ``rooms``
    rooms with ``lamps`` lamps each, a share ``mirrors`` of them with a
    mirror, the sun through the windows unless ``sun`` is False. The same
    seed gives the same plan on every machine."""
    rooms = _whole("rooms", rooms, 1, 10_000)
    lamps = _whole("lamps", lamps, 0, 64)
    seed = _whole("seed", seed, 0, _MAX_U64)
    text = _flatray.generate(rooms, lamps, float(mirrors), seed, bool(sun))
    return parse(text, name=f"<generated rooms={rooms} lamps={lamps} seed={seed}>")


def import_plan(
    path: PathLike,
    scale: Optional[float] = None,
    tolerance: Optional[float] = None,
    *,
    doors: Optional[str] = None,
    open_portals: Optional[str] = None,
    lights: Optional[str] = None,
    output: Optional[PathLike] = None,
    force: bool = False,
) -> Scene:
    """A scene from a floor plan (an SVG drawing, a Tiled map, a Universal
    VTT map, a wall mask PNG), as ``flatray import`` makes it, with its
    options: ``doors`` ("as-drawn", "open", "closed"), ``open_portals``
    ("windows", "doors") and ``lights`` ("keep", "none") for a Universal
    VTT map. With ``output``, the scene file and its floor image are
    written there, as ``flatray import -o output`` writes them (replacing
    neither without ``force``), and the scene is loaded from it; without,
    nothing is written and a map's image is not the floor.
    ``scene.text`` is the scene text, to save and edit; what was not
    imported is in ``scene.import_notes``."""
    path = os.fspath(path)
    target = None if output is None else os.fspath(output)
    text, notes, warnings = _flatray.import_plan(
        path, scale, tolerance, doors, open_portals, lights, target, bool(force)
    )
    notes = list(notes) + [f"not imported: {w}" for w in warnings]
    if target is not None:
        scene = load(target)
    else:
        scene = parse(text, name=path, base=os.path.dirname(os.path.abspath(path)))
    return Scene._of(scene._loaded, scene._source, notes)


class Rendered:
    """A render: the image, the statistics and the noise estimate."""

    __slots__ = ("image", "stats", "seconds", "settings", "window", "_white")

    def __init__(
        self,
        image: np.ndarray,
        stats: Dict[str, Any],
        seconds: float,
        settings: Dict[str, Any],
        window: Optional[Tuple[int, int, int, int]],
        white: Optional[float],
    ) -> None:
        self.image = image
        """(height, width, 3) float32: the linear value of every pixel."""
        self.stats = stats
        """What was simulated, the work it took and the noise, by the names
        of ``flatray render --json`` (``docs/cli.md``)."""
        self.seconds = seconds
        """Wall-clock seconds the render took."""
        self.settings = settings
        """The settings it was rendered with."""
        self.window = window
        """The window of pixels rendered, or None for all of them."""
        self._white = white

    @property
    def noise(self) -> Optional[float]:
        """The render's estimate of its own error as the root of relMSE:
        each pixel's error relative to its own value, averaged over pixels
        and channels (None below two samples a pixel). The relative RMS
        error is ``stats["noise"]["relative"]``."""
        return self.stats["noise"]["relmse"]

    def write(self, path: PathLike) -> None:
        """Writes the image, whole or not at all: ``.exr`` linear, ``.png``
        tone-mapped as the scene asks."""
        image = np.ascontiguousarray(self.image, dtype="<f4")
        height, width, _ = image.shape
        _flatray.write_image(os.fspath(path), image.tobytes(), width, height, self._white)

    def __repr__(self) -> str:
        h, w, _ = self.image.shape
        noise = self.noise
        said = "n/a" if noise is None else f"{100 * noise:.2f} %"
        return f"<flatray.Rendered {w} x {h}, noise {said}, {self.seconds:.2f} s>"


def render(
    scene: Scene,
    *,
    spp: Optional[int] = None,
    bounces: Optional[int] = None,
    specular: Optional[int] = None,
    seed: Optional[int] = None,
    integrator: Optional[str] = None,
    cache: Optional[str] = None,
    caustics: Optional[bool] = None,
    indirect: Optional[str] = None,
    exposure: Optional[float] = None,
    scale: float = 1.0,
    window: Optional[Sequence[int]] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> Rendered:
    """Renders ``scene``. The keywords override the scene's own render
    settings, as ``flatray render``'s flags do: ``spp``, ``bounces``,
    ``specular``, ``seed``, ``integrator`` ("path", "original", "light"),
    ``cache`` ("on", "off", "direct"), ``caustics``, ``indirect``
    ("lines", the default: the floor's indirect light along lines across
    the image; "samples": by each pixel's own path samples), ``exposure``
    and ``scale``. ``window`` = (x0, y0, x1, y1) renders only those pixels
    (the others are 0), with the bits of the whole render. ``threads``
    sets the worker threads (all cores by default).

    ``progress``, where given, is called about ten times a second, on the
    calling thread, with (work done, total work), and once with both
    equal when the render ends; an exception it raises stops the render
    and is raised here.

    The GIL is released while rendering, and Ctrl-C stops the render
    (KeyboardInterrupt)."""
    if not isinstance(scene, Scene):
        raise TypeError(f"expected a flatray.Scene, found {type(scene).__name__}")
    spp = _maybe_whole("spp", spp, 1, _MAX_SAMPLES)
    bounces = _maybe_whole("bounces", bounces, 0, _MAX_BOUNCES)
    specular = _maybe_whole("specular", specular, 0, _MAX_BOUNCES)
    seed = _maybe_whole("seed", seed, 0, _MAX_U64)
    threads = _maybe_whole("threads", threads, 1, 1024)
    win = None
    if window is not None:
        try:
            given = list(window)
        except TypeError:
            raise TypeError(f"window: expected (x0, y0, x1, y1), found {window!r}") from None
        if len(given) != 4:
            raise ValueError(f"window: expected (x0, y0, x1, y1), found {window!r}")
        names = ("x0", "y0", "x1", "y1")
        win = tuple(_whole(f"window {n}", v, 0, _MAX_U32) for n, v in zip(names, given))
    for name, value in (("scale", scale), ("exposure", exposure)):
        if value is not None and (
            isinstance(value, bool) or not isinstance(value, (int, float, np.number))
        ):
            raise TypeError(f"{name}: expected a number, found {type(value).__name__} {value!r}")
    data, width, height, stats, seconds = _flatray.render(
        scene._loaded,
        spp=spp,
        bounces=bounces,
        specular=specular,
        seed=seed,
        integrator=integrator,
        cache=cache,
        caustics=caustics,
        indirect=indirect,
        exposure=exposure,
        scale=scale,
        window=win,
        threads=threads,
        progress=progress,
    )
    image = np.frombuffer(data, dtype="<f4").reshape(height, width, 3).astype(np.float32)
    settings = dict(scene.settings)
    given = {
        "spp": spp,
        "bounces": bounces,
        "specular": specular,
        "seed": seed,
        "integrator": integrator,
        "cache": cache,
        "caustics": caustics,
        "indirect": indirect,
        "exposure": exposure,
    }
    settings.update({k: v for k, v in given.items() if v is not None})
    settings["scale"] = scale
    return Rendered(image, json.loads(stats), seconds, settings, win, scene._loaded.white)


def measure(
    scene: Scene,
    *,
    spp: Optional[int] = None,
    batches: int = 8,
    scale: float = 1.0,
    door_width: Optional[float] = None,
    target_error: Optional[float] = None,
) -> Dict[str, Any]:
    """Measures each room of ``scene`` as ``flatray measure`` does: E_min,
    E_avg, E_max and U0 on the EN 12464-1 grid, and the daylight factor
    where the scene's only light is a sky, each as ``{"value", "se"}``
    (``se`` the standard error over ``batches`` independent renders of
    ``spp`` samples per pixel in all). With ``target_error`` (per cent),
    the samples double until every room's E_min, E_avg and U0 have a
    standard error of at most that share of their value (up to 16384 per
    batch); ``"target_error"`` then says whether they met it.

    Returns a dict: ``"rooms"`` (a list of each room's figures, with its
    ``"name"``, ``"area"``, ``"spacing"`` and ``"points"``), ``"batches"``,
    ``"metres_per_unit"``, and ``"grid"``: a NumPy array of one row per
    grid point, columns x, y, room (its index in ``"rooms"``), E and its
    standard error. Ctrl-C stops it between batches."""
    if not isinstance(scene, Scene):
        raise TypeError(f"expected a flatray.Scene, found {type(scene).__name__}")
    spp = _maybe_whole("spp", spp, 1, _MAX_SAMPLES)
    batches = _whole("batches", batches, 2, 64)
    for name, value in (("scale", scale), ("door_width", door_width), ("target_error", target_error)):
        if value is not None and (
            isinstance(value, bool) or not isinstance(value, (int, float, np.number))
        ):
            raise TypeError(f"{name}: expected a number, found {type(value).__name__} {value!r}")
    text, data, rows = _flatray.measure(
        scene._loaded,
        spp=spp,
        batches=batches,
        scale=float(scale),
        door_width=None if door_width is None else float(door_width),
        target_error=None if target_error is None else float(target_error),
    )
    result: Dict[str, Any] = json.loads(text)
    result["grid"] = np.frombuffer(data, dtype="<f8").reshape(rows, 5).copy()
    return result


def read_exr(path: PathLike) -> np.ndarray:
    """A linear EXR image (as ``flatray render -o out.exr`` writes) as a
    (height, width, 3) float32 array. Only a regular file is read (a pipe
    or a device is refused with OSError, never waited on), and the GIL is
    released while it is read and decoded."""
    data, width, height = _flatray.read_exr(os.fspath(path))
    return np.frombuffer(data, dtype="<f4").reshape(height, width, 3).astype(np.float32)
