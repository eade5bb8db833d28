"""envtrace: a path tracer for scenes lit by HDR environment maps, from Python.

The module is a thin layer over envtrace's C++ library, the one the command line drives: the same
scene files and loaders, the same renderer, the same bits for the same seed.

    import envtrace
    image = envtrace.render("scenes/default.json", spp=16, seed=1)   # H x W x 3 float32

    r = envtrace.Renderer("scenes/default.json", backend="cpu")
    r.render(spp=8)                      # the film so far
    r.render(spp=8)                      # 16 samples, the bits of one render of 16
    r.set_environment(rotation=90)       # restarts the film; nothing is read again
    layers = envtrace.read_image("out.exr")

docs/python.md is the reference.
"""

from ._envtrace import Error, EnvironmentMap, LightSet, __version__
from ._images import read_image, write_image
from ._render import Renderer, render
from ._denoise import denoise
from ._scene import load_scene
from ._tools import compare, load_map

__all__ = [
    "Error",
    "EnvironmentMap",
    "LightSet",
    "Renderer",
    "__version__",
    "compare",
    "denoise",
    "load_map",
    "load_scene",
    "read_image",
    "render",
    "write_image",
]
