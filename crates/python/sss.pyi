"""Subsurface scattering from Python: the toolkit's BSSRDF models, Monte Carlo reference,
separable kernels, screen-space filter, renders and image metrics on numpy arrays.

Profiles are float64, images float32 (H, W, 3) row-major from the top-left; lengths in mm.
Errors keep the one-line message of the `sss` tool in Python's terms (the keyword
`max_samples` where the tool names `--max-samples`): ValueError for bad input, OSError for
files, TypeError for an argument of the wrong type or dtype.
"""

import os
from typing import Callable, Literal, Sequence, TypedDict, overload

import numpy as np
import numpy.typing as npt

__version__: str
#: Model names accepted by `Model` ("standard-dipole", "better-dipole", ...).
MODELS: list[str]
#: Kernel names accepted by `kernel` and `filter` ("preintegrated", "svd3", ..., "exact2d").
KERNELS: list[str]
#: Rendering methods accepted by `render` ("exact", "pathtrace", "separable", ...).
METHODS: list[str]
#: Names of the built-in scenes accepted by `render` ("sphere", ...).
BUILTIN_SCENES: list[str]

F64 = npt.NDArray[np.float64]
F32 = npt.NDArray[np.float32]
#: Three numbers (R, G, B), or one for all three channels (as in a scene file).
RGB = float | Sequence[float] | npt.ArrayLike
#: A float64 array (N,), or a sequence of numbers (a list, a tuple, a range).
F64Like = F64 | Sequence[float]
#: progress(done, total), called on the calling thread about every 0.1 s and once at the end
#: (`progress=True` draws a text bar on sys.stderr instead, in a terminal or a notebook);
#: raising from it stops the call and the exception propagates.
ProgressCallback = Callable[[int, int], object]

class Model:
    """A BSSRDF model for a medium, as `sss profile` evaluates it.

    `kind` is one of `MODELS`. The medium is a preset (see `presets()`; g = 0) or
    `sigma_a` and `sigma_s` in 1/mm with anisotropy `g` (default 0); `eta` is the relative
    index of refraction (default 1.3). Raises ValueError for an unknown model or preset or an
    invalid medium.
    """

    def __init__(
        self,
        kind: str,
        preset: str | None = None,
        sigma_a: RGB | None = None,
        sigma_s: RGB | None = None,
        g: float | None = None,
        eta: float | None = None,
    ) -> None: ...
    @property
    def kind(self) -> str:
        """The model's name."""
    @property
    def preset(self) -> str | None:
        """The preset's name, or None for a medium given by coefficients."""
    @property
    def sigma_a(self) -> F64:
        """Absorption coefficients (1/mm), shape (3,)."""
    @property
    def sigma_s(self) -> F64:
        """Scattering coefficients (1/mm), shape (3,)."""
    @property
    def g(self) -> float:
        """Henyey-Greenstein anisotropy."""
    @property
    def eta(self) -> float:
        """Relative index of refraction."""
    @property
    def total_diffuse_reflectance(self) -> F64:
        """Total diffuse reflectance per channel, shape (3,)."""
    @overload
    def rd(self, r: float) -> F64: ...
    @overload
    def rd(self, r: F64Like) -> F64: ...
    def rd(self, r: float | F64Like) -> F64:
        """R_d(r) in 1/mm² at radii r (mm, float64 (N,) or a list, finite, >= 0): shape
        (N, 3); a float r gives shape (3,)."""
    @overload
    def sample_r(self, u: float, channel: int) -> float: ...
    @overload
    def sample_r(self, u: F64Like, channel: int) -> F64: ...
    def sample_r(self, u: float | F64Like, channel: int) -> float | F64:
        """Radii (mm) with density proportional to 2πr R_d(r) of `channel` (0, 1, 2), from
        uniform u in [0, 1)."""
    @overload
    def pdf_r(self, r: float, channel: int) -> float: ...
    @overload
    def pdf_r(self, r: F64Like, channel: int) -> F64: ...
    def pdf_r(self, r: float | F64Like, channel: int) -> float | F64:
        """The density per mm of radius with which `sample_r` returns r."""

class Preset(TypedDict):
    sigma_s_reduced: F64
    sigma_a: F64
    eta: float
    published_rd: F64

def presets() -> dict[str, Preset]:
    """The measured materials of Jensen et al. 2001 (Table 2), by name, as `sss presets`."""

def monte_carlo(
    *,
    preset: str | None = None,
    sigma_a: RGB | None = None,
    sigma_s: RGB | None = None,
    g: float | None = None,
    eta: float | None = None,
    r_max: float,
    bins: int = 100,
    photons: int = 1_000_000,
    seed: int = 1,
    progress: ProgressCallback | bool | None = None,
) -> tuple[F64, F64, F64]:
    """The Monte Carlo reference of `sss profile --model monte-carlo`: bin centres (N,),
    R_d (N, 3) and standard errors (N, 3) over `bins` linear bins of [0, r_max] mm.

    Releases the GIL; progress counts photons (total 3 × photons); Ctrl-C raises
    KeyboardInterrupt."""

class Kernel:
    """A separable screen-space kernel, exactly as `sss kernel` exports it."""

    @property
    def method(self) -> str: ...
    @property
    def model(self) -> str: ...
    @property
    def normalized(self) -> bool: ...
    @property
    def taps(self) -> F64 | None:
        """Rank-1 kernels: (N, 4) rows (offset_mm, w_r, w_g, w_b) in the order of the CSV
        export; None for multi-term kernels."""
    @property
    def terms(self) -> list[tuple[F64, F64]]:
        """Per term, the (horizontal, vertical) taps, each (N, 4) as `taps`."""
    def export(self, format: Literal["json", "csv", "glsl", "hlsl", "wgsl"] = "json") -> str:
        """The text `sss kernel --format FORMAT` prints."""

def kernel(
    model: Model,
    method: str | None = None,
    *,
    taps: int | None = None,
    uniform: bool = False,
    k: float | None = None,
    artist_preset: str | None = None,
    normalize: bool = False,
) -> Kernel:
    """The separable kernel of `model` (`method` one of `KERNELS` but "exact2d"); None takes
    `sss kernel`'s default (preintegrated, 7 taps, k = 2)."""

def filter(
    irradiance: F32,
    depth: F32,
    footprint: F32,
    object_id: npt.NDArray[np.int32],
    kernel: str | Kernel | None = None,
    model: Model | None = None,
    *,
    units_per_mm: float = 1.0,
    taps: int | None = None,
    uniform_taps: bool | None = None,
    k: float | None = None,
    jitter: float | None = None,
    seed: int = 1,
) -> F32:
    """The screen-space separable pass of `sss filter` on arrays.

    irradiance float32 (H, W, 3); depth and footprint (world size of a pixel) float32 (H, W)
    in scene units; object_id int32 (H, W), negative where no translucent object is seen.
    `kernel` is a name from `KERNELS` (None: "preintegrated"; with `model`) or a `Kernel`
    (its model, method and taps). Returns the diffuse
    exitance E ∗ R_d, float32 (H, W, 3). Releases the GIL."""

class RenderResult(TypedDict, total=False):
    total: F32
    subsurface: F32
    std_error: F32
    irradiance: F32
    surface: F32
    coverage: F32
    alpha: F32
    stats: dict[str, float]
    stages: dict[str, float]
    method: str
    settings: str
    irradiance_samples: int
    #: About how many more irradiance samples the parts of the objects out of the profile's
    #: reach of every visible point would have taken (they get none).
    irradiance_left_out: int
    warnings: list[str]

class Scene:
    """A loaded, checked scene (`load_dict`, `load_file`), to pass to `render`."""
    @property
    def resolution(self) -> tuple[int, int]:
        """The camera's (width, height)."""
    @property
    def objects(self) -> list[str]:
        """The objects' names, in order."""
    @property
    def materials(self) -> list[str]:
        """The materials' names, in order."""
    @property
    def warnings(self) -> list[str]:
        """The loader's warnings."""
    def to_dict(self) -> dict[str, object]:
        """The description as a new dict (the scene file's structure; a scene file's mesh
        paths made absolute): edit it and `load_dict` it again."""

def load_dict(
    description: dict[str, object], *, mesh_dirs: Sequence[str | os.PathLike[str]] | None = None
) -> Scene:
    """Load a scene described by a dict with the scene file's structure (`camera`, `lights`,
    `materials`, `objects`; numpy arrays taken as lists, None as a missing key), with the scene
    file's checks and messages naming the key (`objects[0].radius`). Relative mesh paths are
    looked up in the working directory, then `mesh_dirs`, then SSS_MESH_DIR."""

def load_file(
    path: str | os.PathLike[str], *, mesh_dirs: Sequence[str | os.PathLike[str]] | None = None
) -> Scene:
    """Load a scene file (TOML) or a built-in scene by name, as `sss render SCENE` does."""

def render(
    scene: Scene | dict[str, object] | str | os.PathLike[str],
    method: str = "exact",
    *,
    seed: int = 1,
    threads: int | None = None,
    max_memory: int | str | None = None,
    mesh_dirs: Sequence[str | os.PathLike[str]] | None = None,
    progress: ProgressCallback | bool | None = None,
    resolution: tuple[int, int] | None = None,
    pixel_samples: int | None = None,
    **options: str | int | float | bool,
) -> RenderResult:
    """Render `scene` (a `Scene`, a dict as `load_dict` takes, a path, a name from
    `BUILTIN_SCENES`, or TOML text holding a line break) with `method` (one of `METHODS`) as `sss render` does; `options` are the method's
    options (`spp=16`, `kernel="svd3"`, `uniform_taps=True`); an option of another method
    is ignored with a UserWarning (as the command line does), one of no method is a
    TypeError. `resolution=(width, height)` and `pixel_samples=n` override the scene's
    camera, as `--resolution` and `--pixel-samples` do.

    Returns the layers (`total`, `subsurface`, `std_error` for stochastic methods, the
    method's own) as float32 (H, W, 3), `coverage` (translucent objects) and `alpha` (any
    object: the silhouette) (H, W), `stats`, `stages` (seconds),
    `method`, `settings`, `irradiance_samples`, `warnings`. Releases the GIL; progress counts
    shaded samples; Ctrl-C raises KeyboardInterrupt; an exception from progress stops it."""

def write_exr(
    path: str | os.PathLike[str],
    layers: F32 | F64 | dict[str, F32 | F64],
    *,
    alpha: F32 | None = None,
    attributes: dict[str, str] | None = None,
) -> None:
    """Write a linear OpenEXR file as `sss render --out` does: an image (H, W, 3) as the
    plain R, G, B of a part named `beauty`, or a dict of images by name (the first the plain
    R, G, B, the others NAME.R, NAME.G, NAME.B); `alpha` (H, W) as channel A; `attributes`
    as text header attributes. Negative and non-finite values are written as 0; an error
    leaves no partial file."""

def write_png(
    path: str | os.PathLike[str], image: F32 | F64, *, exposure: float | None = None
) -> None:
    """Write a linear image (H, W, 3) as an 8-bit sRGB PNG, as `sss render --png` does:
    scaled by `exposure`, or by `sss render`'s automatic exposure when None."""

def read_exr(path: str | os.PathLike[str]) -> dict[str, F32]:
    """Every RGB layer of an OpenEXR file by name, float32 (H, W, 3), and `alpha` float32
    (H, W) when the file has the channel A (as `sss render --out` writes it)."""

class DiffResult(TypedDict):
    pixels: int
    rmse: float
    rel_rmse: float
    frac_within_eps: float
    mean_ratio: F64

def diff(
    a: F32 | F64 | str | os.PathLike[str],
    reference: F32 | F64 | str | os.PathLike[str],
    *,
    layer: str = "subsurface",
    reference_layer: str | None = None,
    eps: float = 0.05,
) -> DiffResult:
    """The figures of `sss diff`: images (H, W, 3) or EXR paths (their `layer`; the
    reference's `reference_layer` when given, `"beauty"` for another renderer's plain
    R,G,B)."""
