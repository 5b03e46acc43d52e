"""mislab from Python: render, compare and benchmark Monte Carlo sampling strategies on the GPU.

A thin layer over mislab's Rust API (``mislab._native``): the keyword arguments are the command line's flags with
``-`` written as ``_`` (``light_sampling="area"`` is ``--light-sampling area``), with the same values, defaults
and error messages. One device is opened per process and keeps every compiled pipeline, so a second render of the
same scene and settings starts sampling at once.

    >>> import mislab
    >>> scene = mislab.load("veach-mis")
    >>> img = mislab.render(scene, spp=16, strategy="mis", width=128, height=128)
    >>> img.mean.shape
    (128, 128, 3)
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import REFERENCE_SEED, SceneError

__version__: str = _native.VERSION
__all__ = [
    "Image",
    "REFERENCE_SEED",
    "Scene",
    "SceneError",
    "adapter",
    "bench",
    "compare",
    "load",
    "merge",
    "pipelines_compiled",
    "reference",
    "render",
    "render_progressive",
    "settings",
]

#: A loaded scene (from :func:`load`).
Scene = _native.Scene

PathLike = Union[str, "os.PathLike[str]"]


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, os.PathLike):
        return os.fspath(v)
    if isinstance(v, tuple) and len(v) == 2:  # part=(k, n)
        return f"{v[0]}/{v[1]}"
    return str(v)


def _pairs(kwargs: Dict[str, Any]) -> List[Tuple[str, str]]:
    return [(k, _value(v)) for k, v in kwargs.items() if v is not None]


class Image:
    """A rendered image: per-pixel mean and variance (numpy float32, shape (H, W, 3), linear radiance) and what
    produced it. ``mean`` and ``variance`` wrap the rendered buffers without copying them again."""

    def __init__(self, native: "_native.NativeImage") -> None:
        self._native = native
        self._mean: Optional[np.ndarray] = None
        self._variance: Optional[np.ndarray] = None
        self._count: Optional[np.ndarray] = None

    @property
    def width(self) -> int:
        return self._native.width

    @property
    def height(self) -> int:
        return self._native.height

    @property
    def shape(self) -> Tuple[int, int, int]:
        return (self.height, self.width, 3)

    @property
    def mean(self) -> np.ndarray:
        """Mean radiance per pixel, float32 (H, W, 3), rows from the top."""
        if self._mean is None:
            self._mean = np.frombuffer(self._native.mean_bytes(), dtype=np.float32).reshape(self.shape)
        return self._mean

    @property
    def variance(self) -> np.ndarray:
        """Per-pixel sample variance of one sample, float32 (H, W, 3); the mean's variance is this / ``count``."""
        if self._variance is None:
            self._variance = np.frombuffer(self._native.variance_bytes(), dtype=np.float32).reshape(self.shape)
        return self._variance

    @property
    def count(self) -> np.ndarray:
        """Finite samples per pixel, uint32 (H, W)."""
        if self._count is None:
            self._count = np.frombuffer(self._native.count_bytes(), dtype=np.uint32).reshape(self.shape[:2])
        return self._count

    @property
    def spp(self) -> int:
        """Samples per pixel this render added to every pixel."""
        return self._native.spp

    @property
    def seconds(self) -> float:
        """Seconds spent sampling (start-up and shader compilation excluded)."""
        return self._native.seconds

    @property
    def rays(self) -> int:
        """Rays traced."""
        return self._native.rays

    @property
    def nonfinite(self) -> int:
        """NaN/Inf samples counted on the device (kept out of the image)."""
        return self._native.nonfinite

    @property
    def interrupted(self) -> bool:
        """Whether the render was stopped (KeyboardInterrupt) before its budget was met."""
        return self._native.interrupted

    @property
    def extra_rows(self) -> int:
        """Rows holding one sample more (a ``time`` budget's last, partial pass)."""
        return self._native.extra_rows

    @property
    def sample_range(self) -> Tuple[int, int]:
        """The sample indices this render added, [first, next)."""
        return self._native.sample_range

    @property
    def scene(self) -> str:
        """The scene as it was named."""
        return self._native.scene

    @property
    def settings(self) -> Dict[str, Any]:
        """Every setting the image was rendered with (the CLI's flag names, ``-`` as ``_``)."""
        return json.loads(self._native.settings_json())

    def tonemapped(self, exposure: float = 0.0, tonemap: str = "clamp") -> np.ndarray:
        """8-bit sRGB (H, W, 3) after ``exposure`` stops and the tonemapper (``"clamp"`` or ``"aces"``), for
        ``plt.imshow``."""
        raw = self._native.tonemapped_bytes(float(exposure), tonemap)
        return np.frombuffer(raw, dtype=np.uint8).reshape(self.shape)

    def save(self, path: PathLike, tonemap: str = "clamp", force: bool = False) -> None:
        """Writes ``.png`` (sRGB, tonemapped with the settings' exposure) or ``.exr`` (linear float32), with the
        header metadata ``mislab render`` writes (spp, seed, scene, settings)."""
        self._native.save(os.fspath(path), tonemap, force)

    def __repr__(self) -> str:
        flag = ", interrupted" if self.interrupted else ""
        return (
            f"<mislab.Image {self.width}x{self.height} of {self.scene!r}: {self.spp} spp in {self.seconds:.2f} s, "
            f"{self.nonfinite} NaN/Inf{flag}>"
        )


def _scene(scene: Union[Scene, PathLike]) -> Scene:
    return scene if isinstance(scene, Scene) else load(scene)


def load(
    scene: PathLike,
    *,
    env: Optional[PathLike] = None,
    env_scale: Optional[float] = None,
    env_rotation: Optional[float] = None,
    gltf_scene: Optional[int] = None,
    allow_outside_paths: bool = False,
) -> Scene:
    """Loads a scene: a built-in name (``veach-mis``, ``cornell-box``, ``furnace``, ``area-vs-cosine``, …) or a
    ``.gltf``/``.glb``/``.toml``/``.pbrt``/``.xml`` file; ``env`` lights it with an equirectangular map instead.

    Raises ``FileNotFoundError`` for a missing file and :class:`SceneError` (a ``ValueError``) for one that cannot
    be loaded, naming the file and line."""
    flags = dict(env=env, env_scale=env_scale, env_rotation=env_rotation, gltf_scene=gltf_scene)
    if allow_outside_paths:
        flags["allow_outside_paths"] = True
    return _native.load(os.fspath(scene), _pairs(flags))


def render(scene: Union[Scene, PathLike], **settings: Any) -> Image:
    """Renders ``scene`` and returns the :class:`Image`. Keyword arguments are ``mislab render``'s flags with
    ``-`` as ``_`` (listed below and by :func:`settings`); ``spp`` defaults to 64 unless ``time`` (seconds) is
    given. ``state``, ``checkpoint_every``, ``resume`` and ``part`` (``"K/N"`` or ``(k, n)``) write and continue
    state files as the CLI does. A KeyboardInterrupt stops the render within a second and returns what it has,
    with ``interrupted`` set. An unknown setting or value raises ``ValueError``."""
    return Image(_native.render(_scene(scene), _pairs(settings)))


def render_progressive(scene: Union[Scene, PathLike], **settings: Any) -> Iterator[Image]:
    """Like :func:`render`, but yields the image as it converges (after 1, 2, 4, … samples per pixel up to
    ``spp``), for a live display. State flags and ``time`` are not taken."""
    return (Image(native) for native in _native.Progressive(_scene(scene), _pairs(settings)))


_REFERENCE_FLAGS = {
    "spp", "time", "width", "height", "mode", "max_depth", "light_sampling", "env_sampling", "light_select",
    "seed", "part", "state", "checkpoint_every", "resume", "rr_depth", "exposure",
}


def reference(scene: Union[Scene, PathLike], **settings: Any) -> Image:
    """A reference image as ``mislab reference`` renders it: MIS (power heuristic, one light and one BSDF
    sample), Owen-scrambled Sobol, seed ``REFERENCE_SEED`` unless given, every pixel checked to hold every sample.
    Takes ``mislab reference``'s flags (``spp`` or ``time``, ``width``, ``height``, ``mode``, ``max_depth``,
    ``light_sampling``, ``env_sampling``, ``light_select``, ``seed``, state flags)."""
    unknown = sorted(set(settings) - _REFERENCE_FLAGS)
    if unknown:
        raise ValueError(
            f"reference() does not take {', '.join(unknown)}: a reference always uses MIS with the power heuristic "
            "and Sobol (allowed: " + ", ".join(sorted(_REFERENCE_FLAGS)) + ")"
        )
    settings.setdefault("seed", REFERENCE_SEED)
    return Image(_native.render(_scene(scene), _pairs(settings), True))


def _pixels(image: Union[Image, np.ndarray, PathLike]) -> Tuple[bytes, int, int]:
    if isinstance(image, Image):
        return bytes(image._native.mean_bytes()), image.width, image.height
    if isinstance(image, np.ndarray):
        if image.ndim != 3 or image.shape[2] != 3:
            raise ValueError(f"an image array must have shape (H, W, 3), not {image.shape}")
        a = np.ascontiguousarray(image, dtype=np.float32)
        return a.tobytes(), a.shape[1], a.shape[0]
    pixels, w, h = _native.read_image(os.fspath(image))
    return bytes(pixels), w, h


def compare(
    image: Union[Image, np.ndarray, PathLike], reference: Union[Image, np.ndarray, PathLike], block: int = 16
) -> Dict[str, Any]:
    """``mislab compare``: the mean ratio and the relMSE of ``block``×``block`` block means, per channel (R, G, B),
    of ``image`` against ``reference`` (each an :class:`Image`, an (H, W, 3) array or an EXR path). ``relmse`` is
    the mean of the three channels' block relMSE."""
    a, b = _pixels(image), _pixels(reference)
    c = json.loads(_native.compare(a[0], a[1], a[2], b[0], b[1], b[2], int(block)))
    c["relmse"] = c["block_relmse_all"]
    return c


def bench(
    scene: Union[Scene, PathLike],
    ref: Union[Image, np.ndarray, PathLike],
    *,
    spp: Sequence[int] = (1, 4, 16, 64),
    seeds: int = 3,
    **group: Any,
) -> Any:
    """``mislab bench`` from Python: every configuration (the cross product of the list arguments ``strategies``,
    ``samplers``, ``heuristics``, ``light_samplings``, ``env_samplings``, ``light_selects``, ``mis``, ``rr_depths``,
    ``ris_candidates``) over the ``spp`` ladder and ``seeds`` seeds, measured against ``ref``. Other keywords:
    ``mode``, ``max_depth``, ``width`` and ``height`` (default: the reference's size), ``time``, ``dispatch_spp``.
    Returns a pandas DataFrame when pandas is importable, else a list of dicts: one row per configuration × spp
    × seed, with the columns of ``mislab bench``'s results.csv."""
    pixels, w, h = _pixels(ref)
    fields = {"spp": [int(s) for s in spp], "seeds": int(seeds), "width": w, "height": h}
    for k, v in group.items():
        fields[k] = [_value(x) if not isinstance(x, (int, float)) else x for x in v] if isinstance(v, (list, tuple)) else v
    rows = json.loads(_native.bench_group(_scene(scene), json.dumps(fields), pixels, w, h))
    columns = _native.bench_columns()
    # results.json's field `nonfinite` is results.csv's column `nonfinite_samples`.
    rows = [{c: r["nonfinite" if c == "nonfinite_samples" else c] for c in columns} for r in rows]
    try:
        import pandas as pd
    except ImportError:
        return rows
    return pd.DataFrame(rows, columns=columns)


def merge(
    states: Sequence[PathLike], output: Optional[PathLike] = None, state: Optional[PathLike] = None, force: bool = False
) -> Image:
    """Combines the state files of ``part=`` renders into one image exactly as ``mislab merge`` does (missing,
    duplicate, overlapping or foreign parts are refused by name); writes ``output`` (.exr/.png) and the merged
    ``state`` when given."""
    image = Image(_native.merge([os.fspath(s) for s in states], None if state is None else os.fspath(state)))
    if output is not None:
        image.save(output, force=force)
    return image


def settings() -> Dict[str, Dict[str, Any]]:
    """Every render setting: its help, default and allowed values (``choices``, empty when free)."""
    return {
        name: {"help": help_, "default": default, "choices": list(choices)}
        for name, help_, default, choices in _native.settings()
    }


def adapter() -> str:
    """The device renders run on (opens it if no render has yet)."""
    return _native.adapter()


def pipelines_compiled() -> int:
    """Render pipelines this process has compiled so far. Every render reuses them: a render with the scene
    features and settings of an earlier one compiles nothing and starts at once."""
    return _native.pipelines_compiled()


def _settings_doc() -> str:
    lines = ["", "Settings (keyword = default: help):"]
    for name, s in settings().items():
        choices = f" [{', '.join(s['choices'])}]" if s["choices"] else ""
        lines.append(f"    {name} = {s['default']}{choices}: {s['help']}")
    return "\n".join(lines)


render.__doc__ = (render.__doc__ or "") + "\n" + _settings_doc()
render_progressive.__doc__ = (render_progressive.__doc__ or "") + "\n" + _settings_doc()
