"""The paper's tools on a map and on images: samples drawn through a map's distribution, a map
as N directional lights (EnvironmentMap.sample, .lights) and image errors (compare)."""

import os

import numpy as np

from . import _envtrace
from ._images import read_image


def load_map(map, blur=0.5, resolution=None, name="array"):
    """An EnvironmentMap with its sampling distribution, from a file or an H x W x 3 linear RGB
    array. blur: the luminance's Gaussian sigma in texels; resolution: (width, height) of the
    distribution (default: the map's).

    map.sample(n, sampler="sobol", seed=1, backend="opencl") -> {"directions": N x 3,
    "pdfs": N, "radiance": N x 3}, the samples `envtrace sample` plots;
    map.lights(n, method="ours", seed=1, power="share") -> LightSet (directions, powers, save),
    as `envtrace lights` makes it."""
    width, height = resolution if resolution is not None else (0, 0)
    if isinstance(map, (str, os.PathLike)):
        return _envtrace.load_map(os.fspath(map), blur, width, height)
    return _envtrace.map_from_array(np.asarray(map, dtype=np.float32), name, blur, width, height)


def _rgb(image):
    if isinstance(image, (str, os.PathLike)):
        return read_image(image)["color"]
    return np.asarray(image, dtype=np.float32)


def compare(image, reference, mask=None):
    """Errors of image against reference (arrays or image files), as `envtrace compare` prints
    them: {"rmse", "rel_mse", "l2", "mean", "mean_reference", "pixels"}. mask: H x W, pixels
    above 0.5 compared (default: all)."""
    return _envtrace.compare(_rgb(image), _rgb(reference), mask)
