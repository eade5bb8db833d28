"""Scenes from a file or from a dict in the scene file's schema (docs/scene-format.md).

A dict goes through the same loader as a file: it is written as JSON, with its arrays taken out
and handed over in memory. A "mesh" shape may give "vertices" (N x 3), "indices" (M x 3) and
optionally "normals" (N x 3) and "uvs" (N x 2) instead of "file"; the environment's "map" may be
an H x W x 3 linear RGB array (or an envtrace.load_map result) instead of a file name. Relative paths in a dict resolve against
base_dir (default: the current folder).
"""

import copy
import json
import os

import numpy as np

from . import _envtrace

# How a dict scene is named in messages, where a file's path would be.
DICT_NAME = "<scene dict>"

_MESH_ARRAYS = ("vertices", "indices", "normals", "uvs")


def _json_value(value):
    """numpy scalars and small arrays (a camera's eye) as JSON numbers and lists."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not a value of the scene schema")


def split_arrays(doc):
    """(the dict without its arrays, meshes by name, maps by name): what the loader takes."""
    doc = copy.copy(doc)
    meshes, maps = {}, {}
    shapes = doc.get("shapes")
    if isinstance(shapes, list):
        doc["shapes"] = shapes = [copy.copy(s) for s in shapes]
        for i, shape in enumerate(shapes):
            if isinstance(shape, dict) and shape.get("type") == "mesh" and "vertices" in shape:
                name = f"shapes[{i}]"
                meshes[name] = {k: shape.pop(k) for k in _MESH_ARRAYS if k in shape}
                if "indices" not in meshes[name]:
                    raise _envtrace.Error(f"{DICT_NAME}: {name}: a mesh of arrays needs "
                                          '"indices" (M x 3 vertex indices)')
                idx = np.asarray(meshes[name]["indices"])
                if idx.size and idx.dtype.kind not in "iu":
                    raise _envtrace.Error(f"{DICT_NAME}: {name}: indices: expected integers, "
                                          f"got {idx.dtype}")
                shape["arrays"] = name
    env = doc.get("environment")
    if isinstance(env, dict) and "map" in env and not isinstance(env["map"], str):
        doc["environment"] = env = dict(env)
        texels = env.pop("map")
        if isinstance(texels, _envtrace.EnvironmentMap):  # envtrace.load_map's: its texels
            texels = texels.pixels
        maps["environment"] = texels
        env["arrays"] = "environment"
    return doc, meshes, maps


def to_json(doc):
    return json.dumps(doc, default=_json_value)


def load_scene(scene, base_dir=None):
    """A loaded scene (envtrace._envtrace.Scene) and its JSON document (a dict, arrays out).

    scene: a path to a scene file, a dict in its schema, or an already loaded Scene.
    """
    if isinstance(scene, _envtrace.Scene):
        return scene
    return load_scene_and_doc(scene, base_dir)[0]


def load_scene_and_doc(scene, base_dir=None):
    if isinstance(scene, (str, os.PathLike)):
        path = os.fspath(scene)
        loaded = _envtrace.load_scene(path)  # its errors first, as the command line's
        with open(path, encoding="utf-8") as f:
            return loaded, json.load(f)
    if isinstance(scene, dict):
        doc, meshes, maps = split_arrays(scene)
        folder = os.fspath(base_dir) if base_dir is not None else os.getcwd()
        return _envtrace.scene_from_json(to_json(doc), DICT_NAME, folder, meshes, maps), doc
    raise TypeError(f"a scene is a path or a dict, not {type(scene).__name__}")
