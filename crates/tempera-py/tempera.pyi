"""Tempera: physically based rendering with tempered Markov-chain light transport.

Images are float32 numpy arrays of shape (height, width, 3), linear RGB.
"""

import os
from typing import Any, Literal, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

ImageLike = npt.ArrayLike | RenderResult | str | os.PathLike[str]

class SceneError(Exception):
    """A scene file that could not be loaded; the message names file and line."""

class Scene:
    def info(self) -> dict[str, Any]:
        """Resolution, primitives, emitters, materials and lights by type, the file's
        defaults (spp, maxdepth, integrator; mpp, the mutations per pixel of pbrt-v4's `mlt`)
        and the loader's warnings with file:line."""

class RenderResult:
    @property
    def image(self) -> npt.NDArray[np.float32]:
        """The image, (height, width, 3) float32, linear RGB."""
    @property
    def stats(self) -> dict[str, Any]:
        """The statistics `tempera render --stats` writes (per-depth chain statistics for
        the Markov-chain integrators)."""
    @property
    def interrupted(self) -> bool:
        """True when Ctrl-C stopped the render before its budget was spent."""
    def save(self, path: str | os.PathLike[str], exposure: float = 0.0) -> None:
        """Writes .exr, .pfm (linear float) or .png (sRGB after `exposure` stops)."""

def load(path: str | os.PathLike[str], strict: bool = False) -> Scene:
    """Loads a pbrt-v4 (.pbrt) or Mitsuba 0.5/0.6 (.xml) scene. Raises SceneError."""

def default_scene() -> Scene:
    """The embedded default scene."""

def render(
    scene: Scene,
    integrator: Literal["path", "bdpt", "pssmlt", "mmlt", "tempered"] | None = None,
    *,
    spp: int | None = None,
    mpp: int | None = None,
    time: float | None = None,
    seed: int = 0,
    threads: int = 0,
    resolution: tuple[int, int] | None = None,
    maxdepth: int | None = None,
    max_memory: float | None = None,
    progress: bool = True,
    **settings: Any,
) -> RenderResult:
    """Renders `scene` under one budget (spp, mpp or time seconds; default the scene's spp, or
    for the Markov-chain integrators the mutations per pixel it gives, as pbrt-v4's `mlt` does).
    Further keyword arguments are the integrator's settings as in experiment files
    (bootstrap, chains, large_step, sigma, allocation, independent_below, normaliser_share, bridge_above, bdpt_above,
    replicas, swap, ladder, max_temperature, collapse_above, collapse_below, pilot, tuning, burn_in, swap_target, tempered_mis,
    reuse_replicas, replica_splats, flattening, swap_every, hot_every, hot_large_step, paper, mis, photons, radius,
    photon_sampler). Bad settings raise ValueError. Ctrl-C returns the image so far."""

def compare(
    image: ImageLike, reference: ImageLike, metrics: Sequence[str] | None = None
) -> dict[str, float]:
    """mse, rmse, relmse, smape, flip, mean_ratio (or the ones asked for)."""

def error_map(
    image: ImageLike,
    reference: ImageLike,
    metric: Literal["relmse", "flip"] = "relmse",
    colour: bool = False,
) -> npt.NDArray[np.float32]:
    """Per-pixel errors, (height, width): the relMSE terms (their mean is compare's relmse)
    or FLIP (its mean is compare's flip). colour=True: the false-colour picture with a
    colour bar beneath, (height + legend, width, 3)."""

def save(image: ImageLike, path: str | os.PathLike[str], exposure: float = 0.0) -> None:
    """Writes any (height, width, 3) array as .exr, .pfm or .png."""

def read(path: str | os.PathLike[str]) -> npt.NDArray[np.float32]:
    """Reads an image file as linear RGB."""

def experiment(config: str | os.PathLike[str], quiet: bool = True) -> Any:
    """Runs an experiment file as `tempera experiment` does (same folder and report);
    returns the results table (a pandas DataFrame when pandas is installed, else a list of
    dicts). Ctrl-C stops it; finished runs are kept."""
