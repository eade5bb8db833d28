"""Rendering: envtrace.render (one call, one image) and the Renderer (a progressive film with
edits, AOVs, noise and stats)."""

import json

from . import _envtrace
from ._denoise import denoise
from ._images import group_layers
from ._scene import load_scene_and_doc


class Renderer:
    """A scene held in memory and rendered progressively on one film.

    scene: a scene file's path, a dict in its schema (arrays allowed, see envtrace._scene) or a
    loaded Scene. backend: "opencl" or "cpu" (the native one); device: the OpenCL device index;
    threads: native threads (0: all cores); aovs: keep albedo, normal and depth of the first hits;
    width, height: the film's, over the scene's (as --width, --height). Any other keyword is a key of the scene's "render" block (seed, strategy, max_depth, sampler,
    spp, ...), checked as the file's would be.

    render(spp) adds spp samples per pixel and returns the image so far: calls adding up to N
    give the bits of one render of N. Edits (set_environment, set_camera, set_material,
    set_render, edit) restart the film; the meshes, maps and textures stay in memory, nothing is
    read from disk again (the device scene and the strategy's tables are made again).
    """

    def __init__(self, scene, *, backend="opencl", device=0, threads=0, aovs=False,
                 width=None, height=None, base_dir=None, **render):
        if isinstance(scene, _envtrace.Scene):
            loaded, self._doc = scene, {}
        else:
            loaded, self._doc = load_scene_and_doc(scene, base_dir)
        self._r = _envtrace.Renderer(loaded, backend=backend, device=device, threads=threads,
                                     aovs=aovs)
        film = {"width": width, "height": height}  # as --width and --height
        blocks = {"film": {k: v for k, v in film.items() if v is not None},
                  "render": {k: _plain(v) for k, v in render.items()}}
        if film["width"] is not None or film["height"] is not None or render:
            self.edit({k: v for k, v in blocks.items() if v})

    # Rendering and its results.

    def render(self, spp=None, progress=None):
        """Adds spp samples per pixel (default: the scene's render.spp) and returns the image
        (H x W x 3 float32, linear). progress: called as progress(spp, seconds) after each pass
        (the film's samples, this call's seconds); an exception it raises stops the render.
        Ctrl-C stops the render and keeps its film (the samples of the passes finished):
        KeyboardInterrupt is raised, image() returns the film, and the next render continues
        it."""
        spp = self._r.scene.spp if spp is None else int(spp)
        if spp < 1:
            raise _envtrace.Error(f"spp {spp}: must be at least 1")
        self._r.render(self._r.spp + spp, progress)
        return self._r.image()

    @property
    def spp(self):
        """Samples per pixel in the film."""
        return self._r.spp

    def image(self):
        """The film's mean radiance, H x W x 3 float32."""
        return self._r.image()

    def variance(self):
        """The estimated variance of each pixel's mean (s^2 / n), H x W x 3 float32."""
        return self._r.variance()

    def aovs(self):
        """The first hits' layers of a Renderer made with aovs=True, as the EXR holds them:
        {"albedo": H x W x 3, "normal": H x W x 3, "depth": H x W, "variance": H x W x 3}."""
        names, pixels = self._r.layers()
        layers = group_layers(names, pixels)
        layers.pop("color", None)
        return layers

    def denoised(self):
        """The film so far through envtrace.denoise, guided by its albedo and normal (a Renderer
        made with aovs=True; render --denoise's image for the same film)."""
        layers = self.aovs()
        if "albedo" not in layers or "normal" not in layers:
            raise _envtrace.Error("Renderer.denoised: needs a Renderer made with aovs=True")
        return denoise(self.image(), layers["albedo"], layers["normal"])

    def noise(self):
        """The film's estimated relative error (the --noise-target measure); inf below 2 spp."""
        return self._r.noise()

    def stats(self):
        """The last render call's report, as `envtrace render --stats` writes it (a dict)."""
        return json.loads(self._r.stats())

    @property
    def scene(self):
        """The scene as edited (a loaded Scene: width, height, materials, environment, ...)."""
        return self._r.scene

    # Edits: each restarts the film.

    def edit(self, blocks):
        """Applies blocks of the scene file's schema: "camera", "render", "film" (over the
        current values), "environment" (intensity, rotation, convention) and "materials" (each
        named material's block, merged over the one the scene gave)."""
        blocks = dict(blocks)
        if "materials" in blocks:
            known = self._doc.get("materials", {})
            blocks["materials"] = {name: {**known.get(name, {}), **block}
                                   for name, block in blocks["materials"].items()}
        self._r.edit(json.dumps(blocks), "edit")
        if "materials" in blocks:  # a new dict: the caller's scene dict stays as it was
            self._doc = {**self._doc,
                         "materials": {**self._doc.get("materials", {}), **blocks["materials"]}}

    def set_environment(self, *, rotation=None, intensity=None, convention=None):
        """Turns the map about the up axis (degrees), scales it, or names its convention."""
        block = {"rotation": rotation, "intensity": intensity, "convention": convention}
        self.edit({"environment": {k: v for k, v in block.items() if v is not None}})

    def set_camera(self, *, eye=None, target=None, up=None, fov=None):
        block = {"eye": eye, "target": target, "up": up, "fov": fov}
        self.edit({"camera": {k: _plain(v) for k, v in block.items() if v is not None}})

    def set_material(self, name, **params):
        """Changes a material's parameters (albedo=..., roughness=..., type=...)."""
        self.edit({"materials": {name: {k: _plain(v) for k, v in params.items()}}})

    def set_strategy(self, strategy):
        self.edit({"render": {"strategy": strategy}})

    def set_render(self, **render):
        """Keys of the "render" block: seed, strategy, max_depth, sampler, spp, ..."""
        self.edit({"render": {k: _plain(v) for k, v in render.items()}})


def _plain(value):
    """numpy values as JSON's."""
    return value.tolist() if hasattr(value, "tolist") else value


def render(scene, spp=None, seed=None, backend="opencl", *, base_dir=None, **options):
    """Renders a scene (a path, a dict in the scene file's schema, or a loaded Scene) and returns
    its image, H x W x 3 float32: the bits `envtrace render SCENE --spp SPP --seed SEED
    --backend BACKEND` writes. Other keywords as Renderer's (device, threads, strategy, ...)."""
    if seed is not None:
        options["seed"] = seed
    return Renderer(scene, backend=backend, base_dir=base_dir, **options).render(spp)
