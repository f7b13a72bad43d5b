"""The native module under `flatray`: use the package's functions, which
wrap these with NumPy arrays and `flatray.Scene`."""

from typing import Any, Callable, List, Optional, Tuple

__version__: str

class SceneError(ValueError):
    """A scene that cannot be loaded: where it points and what was
    expected."""

    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    at: Optional[str]
    message: str

class LoadedScene:
    @property
    def canvas(self) -> Tuple[int, int]: ...
    @property
    def counts(self) -> Tuple[int, int, int, int]: ...
    @property
    def warnings(self) -> List[Tuple[int, int, str]]: ...
    @property
    def text(self) -> Optional[str]: ...
    @property
    def settings(self) -> Tuple[int, int, int, int, float, str, str, bool]: ...
    @property
    def white(self) -> Optional[float]: ...
    def image_size(self, scale: float) -> Tuple[int, int]: ...
    def plan(self) -> str: ...

def load(path: str) -> LoadedScene: ...
def parse(text: str, name: str = "<string>", base: str = ".") -> LoadedScene: ...
def from_json(json: str, name: str = "<values>", base: str = ".") -> LoadedScene: ...
def values_text(json: str) -> str: ...
def generate(
    rooms: int = 16, lamps: int = 1, mirrors: float = 0.3, seed: int = 1, sun: bool = True
) -> str: ...
def import_plan(
    path: str,
    scale: Optional[float] = None,
    tolerance: Optional[float] = None,
    doors: Optional[str] = None,
    open_portals: Optional[str] = None,
    lights: Optional[str] = None,
    output: Optional[str] = None,
    force: bool = False,
) -> Tuple[str, List[str], List[str]]: ...
def render(
    scene: LoadedScene,
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
    window: Optional[Tuple[int, int, int, int]] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> Tuple[bytes, int, int, str, float]: ...
def measure(
    scene: LoadedScene,
    *,
    spp: Optional[int] = None,
    batches: int = 8,
    scale: float = 1.0,
    door_width: Optional[float] = None,
) -> Tuple[str, bytes, int]: ...
def read_exr(path: str) -> Tuple[bytes, int, int]: ...
def write_image(
    path: str, data: bytes, width: int, height: int, white: Optional[float] = 4.0
) -> None: ...
