"""Images through envtrace's own readers and writers (OpenEXR with its layers, PFM, HDR, PNG, ...),
as numpy arrays; no OpenImageIO Python module needed."""

import os

import numpy as np

from . import _envtrace

# A render's layers (render/film_layers.h) by the names its EXR gives them.
_LAYER_NAMES = {"albedo": "albedo", "N": "normal", "Z": "depth", "variance": "variance"}
_CHANNEL_ORDER = {"R": 0, "G": 1, "B": 2, "A": 3, "X": 0, "Y": 1, "Z": 2}


def _layer_of(channel):
    prefix, _, suffix = channel.rpartition(".")
    if prefix:
        return _LAYER_NAMES.get(prefix, prefix), suffix
    if channel in ("R", "G", "B", "A", "Y"):
        return "color", channel
    return _LAYER_NAMES.get(channel, channel), channel


def group_layers(names, pixels):
    """Channels grouped into layers: "color" (R, G, B), "albedo", "normal" (N.X, N.Y, N.Z),
    "depth" (Z), "variance", and any other prefix by its name; H x W x C, or H x W for one
    channel. OpenEXR sorts channels by name (B, G, R): they come back R, G, B."""
    layers = {}
    for index, channel in enumerate(names):
        layer, suffix = _layer_of(channel)
        layers.setdefault(layer, []).append((_CHANNEL_ORDER.get(suffix, 9), index))
    out = {}
    for layer, channels in layers.items():
        order = [index for _, index in sorted(channels)]
        a = np.ascontiguousarray(pixels[:, :, order])
        out[layer] = a[:, :, 0] if len(order) == 1 else a
    return out


def read_image(path):
    """Every layer of an image file: {"color": H x W x 3, ...} float32, linear (8- and 16-bit
    files decoded from sRGB). An envtrace render's EXR gives color, and with --aovs albedo,
    normal, depth and variance."""
    names, pixels = _envtrace.read_channels(os.fspath(path))
    return group_layers(names, pixels)


def write_image(path, image):
    """Writes an H x W x 3 (or H x W, H x W x 4) float array, all or nothing: .exr, .hdr and
    .pfm keep linear floats; .png and .jpg take display values in [0, 1]. A dict of layers (as
    read_image returns) makes a multi-layer OpenEXR file."""
    path = os.fspath(path)
    if not isinstance(image, dict):
        _envtrace.write_channels(path, np.asarray(image, dtype=np.float32))
        return
    names, planes = [], []
    inverse = {v: k for k, v in _LAYER_NAMES.items()}
    for layer, a in image.items():
        a = np.asarray(a, dtype=np.float32)
        a = a[:, :, None] if a.ndim == 2 else a
        prefix = inverse.get(layer, layer)
        if layer == "color":
            suffixes = "RGBA"[: a.shape[2]] if a.shape[2] > 1 else "Y"
            names += list(suffixes)
        elif a.shape[2] == 1:
            names.append(prefix)
        else:
            suffixes = "XYZ" if layer == "normal" else "RGBA"
            names += [f"{prefix}.{s}" for s in suffixes[: a.shape[2]]]
        planes.append(a)
    _envtrace.write_channels(path, np.concatenate(planes, axis=2), names)
