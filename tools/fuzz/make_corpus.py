#!/usr/bin/env python3
"""Writes the fuzz harnesses' seed corpora (tools/fuzz/README.md) into OUT/<harness>/.

Seeds come from scenes/*.json (pointed at the harness's small stand-in map and mesh), from the
shared data's edge cases (read where they lie: OBJ/MTL pairs and images), from small images made
here (PFM, Radiance HDR, PNG by hand; EXR, TIFF, JPEG with oiiotool when it is installed) and
from a few hand-written light sets. Nothing is copied into the repository.
"""
import argparse
import base64
import json
import os
import re
import shutil
import struct
import subprocess
import tempfile
import zlib
from pathlib import Path

# Must match fuzz_envmap.cpp: the first byte of an input picks the file's extension.
ENVMAP_EXTENSIONS = [".exr", ".hdr", ".pfm", ".png", ".jpg", ".tif", ".img"]
MTL_SEPARATOR = b"#---mtl---\n"  # fuzz_obj_mtl.cpp


def write(out_dir, name, data):
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / name).write_bytes(data if isinstance(data, bytes) else data.encode())


# ---------------------------------------------------------------- scenes
def point_at_stand_ins(scene, k):
    env = scene.get("environment")
    if isinstance(env, dict):
        if "map" in env:
            env["map"] = "map.exr" if k % 2 else "map.hdr"
        sky = env.get("sky")
        if isinstance(sky, dict):
            sky["resolution"] = [32, 16]
    for s in scene.get("shapes", []):
        if isinstance(s, dict):
            if "file" in s:
                s["file"] = "mesh.obj"
            if "segments" in s:
                s["segments"] = min(s["segments"], 16)
            elif s.get("type") == "sphere":
                s["segments"] = 16
    return scene


HAND_SCENES = {
    "minimal_map": {"environment": {"map": "map.hdr"}},
    "sky_small": {"environment": {"sky": {"resolution": [32, 16], "sun_elevation": 10,
                                          "sun_azimuth": -30, "sun_radius": 2,
                                          "sun_radiance": 100, "sky_radiance": 0.5}},
                  "film": {"width": 8, "height": 4}},
    "everything": {
        "camera": {"eye": [0, 1, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
        "film": {"width": 16, "height": 16},
        "environment": {"map": "map.exr", "intensity": 2, "rotation": 90,
                        "distribution_resolution": [8, 4], "blur": 1.5},
        "materials": {"a": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
                      "b": {"type": "microfacet", "specular": 0.9, "roughness": 0.2},
                      "c": {"type": "plastic"}, "d": {"type": "mirror"},
                      "e": {"type": "cook-torrance", "albedo": [1, 0, 0]}},
        "shapes": [
            {"type": "mesh", "file": "mesh.obj", "material": "a",
             "transform": {"translate": [0, 1, 0], "rotate": [0, 1, 0, 30], "scale": 2}},
            {"type": "mesh", "file": "mesh.obj",
             "transform": {"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}},
            {"type": "sphere", "center": [0, 1, 0], "radius": 1, "material": "b",
             "segments": 8, "smooth": False},
            {"type": "quad", "center": [0, 0, 0], "size": [8, 4], "material": "c",
             "transform": {"rotate": [1, 0, 0, 10]}}],
        "render": {"spp": 4, "max_depth": 3, "strategy": "light", "heuristic": "balance",
                   "sampler": "random", "seed": 7, "time_limit": 1, "paths": 1024},
        "output": "out.exr"},
}


def scene_corpus(scenes_dir, out):
    k = 0
    for path in sorted(Path(scenes_dir).glob("*.json")):
        scene = point_at_stand_ins(json.loads(path.read_text()), k)
        write(out, "scene_" + path.stem + ".json", json.dumps(scene, indent=1))
        k += 1
    for name, scene in HAND_SCENES.items():
        write(out, "hand_" + name + ".json", json.dumps(scene, indent=1))


# ---------------------------------------------------------------- OBJ + MTL
def obj_corpus(data_dir, out):
    edge = Path(data_dir) / "edge-cases"
    n = 0
    for folder in ("obj-tinyobjloader", "obj-assimp"):
        for obj in sorted((edge / folder).glob("*.obj")):
            text = obj.read_bytes()
            mtl = b""
            m = re.search(rb"^[ \t]*mtllib[ \t]+([^\r\n]+)", text, re.M)
            if m:
                cand = obj.parent / m.group(1).strip().decode("utf-8", "replace").split(" ")[0]
                whole = obj.parent / m.group(1).strip().decode("utf-8", "replace")
                for c in (whole, cand):
                    if c.is_file():
                        mtl = c.read_bytes()
                        break
                text = text[: m.start(1)] + b"fuzz.mtl" + text[m.end(1):]
            write(out, folder + "_" + obj.stem.replace(" ", "_") + ".obj",
                  text + (MTL_SEPARATOR + mtl if mtl else b""))
            n += 1
    write(out, "hand_tetra.obj", b"mtllib fuzz.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
          b"vn 0 0 1\nvt 0 0\nusemtl m\nf 1/1/1 2/1/1 3/1/1\nf 1 2 4\nf -1 -2 -3\n"
          b"f 1 3 4 2\n" + MTL_SEPARATOR + b"newmtl m\nKd 0.5 0.2 0.1\nKs 0.1 0.1 0.1\nNs 50\n")
    return n


# ---------------------------------------------------------------- PLY, glTF, GLB
MESH_BIN_SEPARATOR = b"\n#---bin---\n"
TET_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def ply_binary(order):
    e = "<" if order == "binary_little_endian" else ">"
    head = ("ply\nformat %s 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
            "property float s\nproperty float t\nelement face 5\n"
            "property list uchar uint vertex_indices\nend_header\n" % order).encode()
    body = b"".join(struct.pack(e + "8f", *v, 0, 0, 1, v[0], v[1]) for v in TET_V)
    faces = [f for f in TET_F] + [(0, 1, 2, 3)]  # and a quad, fanned
    body += b"".join(struct.pack(e + "B%dI" % len(f), len(f), *f) for f in faces)
    return head + body


def gltf_tet(uri, material=True):
    buf = b"".join(struct.pack("<3f", *v) for v in TET_V)
    buf += b"".join(struct.pack("<3H", *f) for f in TET_F)
    g = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
         "nodes": [{"children": [1], "translation": [1, 0, 0]},
                   {"mesh": 0, "rotation": [0, 0.7071068, 0, 0.7071068], "scale": [2, 2, 2]}],
         "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
         "buffers": [{"byteLength": len(buf)}],
         "bufferViews": [{"buffer": 0, "byteLength": 48},
                         {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
         "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
                       {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}]}
    if material:
        g["meshes"][0]["primitives"][0]["material"] = 0
        g["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.3, 1],
                                                    "metallicFactor": 0.5,
                                                    "roughnessFactor": 0.4}}]
    if uri == "data":
        g["buffers"][0]["uri"] = ("data:application/octet-stream;base64," +
                                  base64.b64encode(buf).decode())
    elif uri:
        g["buffers"][0]["uri"] = uri
    return g, buf


def glb(g, buf):
    j = json.dumps(g).encode()
    j += b" " * (-len(j) % 4)
    buf += b"\0" * (-len(buf) % 4)
    return (b"glTF" + struct.pack("<II", 2, 28 + len(j) + len(buf)) +
            struct.pack("<I", len(j)) + b"JSON" + j + struct.pack("<I", len(buf)) + b"BIN\0" + buf)


def mesh_corpus(scenes_dir, out):
    # First byte: 0 .ply, 1 .gltf, 2 .glb (fuzz_mesh.cpp).
    for f in sorted((Path(scenes_dir) / "formats").glob("*")):
        kind = {".ply": 0, ".gltf": 1, ".glb": 2}.get(f.suffix.lower())
        if kind is not None:
            write(out, "scene_" + f.name, bytes([kind]) + f.read_bytes())
    write(out, "hand_ascii.ply", b"\0ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
          b"property float y\nproperty float z\nelement face 2\n"
          b"property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
          b"4 0 1 2 3\n3 0 2 3\n")
    for order in ("binary_little_endian", "binary_big_endian"):
        write(out, "hand_%s.ply" % order, b"\0" + ply_binary(order))
    g, buf = gltf_tet("data")
    write(out, "hand_embedded.gltf", b"\1" + json.dumps(g, indent=1).encode())
    g, buf = gltf_tet("fuzz.bin", material=False)
    write(out, "hand_external.gltf", b"\1" + json.dumps(g, indent=1).encode() +
          MESH_BIN_SEPARATOR + buf)
    g, buf = gltf_tet(None)
    write(out, "hand_tet.glb", b"\2" + glb(g, buf))


# ---------------------------------------------------------------- images
def envmap_seed(ext, data):
    return bytes([ENVMAP_EXTENSIONS.index(ext)]) + data


def pixels(w, h, c):
    return [[[0.1 + 0.8 * ((x + 2 * y + k) % 5) / 4 for k in range(c)] for x in range(w)]
            for y in range(h)]


def pfm(w, h, c, little=True):
    px = pixels(w, h, c)
    head = ("PF" if c == 3 else "Pf") + "\n%d %d\n%s\n" % (w, h, "-1.0" if little else "1.0")
    fmt = "<f" if little else ">f"
    body = b"".join(struct.pack(fmt, v) for row in reversed(px) for p in row for v in p)
    return head.encode() + body


def rgbe(r, g, b):
    import math
    v = max(r, g, b)
    if v < 1e-32:
        return bytes(4)
    m, e = math.frexp(v)
    s = m * 256.0 / v
    return bytes([int(r * s), int(g * s), int(b * s), e + 128])


def radiance_hdr(w, h, rle):
    px = pixels(w, h, 3)
    out = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w)
    for row in px:
        texels = [rgbe(*p) for p in row]
        if rle:  # new-style run-length scanline: 2 2 hi lo, then each channel as literal runs
            out += bytes([2, 2, w >> 8, w & 255])
            for ch in range(4):
                out += bytes([w]) + bytes(t[ch] for t in texels)
        else:
            out += b"".join(texels)
    return out


def png(w, h, channels, bits):
    px = pixels(w, h, channels)
    raw = b""
    for row in px:
        raw += b"\x00"
        for p in row:
            for v in p:
                raw += bytes([int(v * 255)]) if bits == 8 else struct.pack(">H", int(v * 65535))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    colour = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    ihdr = struct.pack(">IIBBBBB", w, h, bits, colour, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) +
            chunk(b"IEND", b""))


def oiiotool_images(out):
    tool = shutil.which("oiiotool")
    if not tool:
        print("make_corpus.py: oiiotool not found; no generated EXR/TIFF/JPEG seeds")
        return 0
    variants = [  # (name, extension, arguments before -o)
        ("exr_half_none", ".exr", ["-d", "half", "--compression", "none"]),
        ("exr_float_zip", ".exr", ["-d", "float", "--compression", "zip"]),
        ("exr_half_piz", ".exr", ["-d", "half", "--compression", "piz"]),
        ("exr_half_rle", ".exr", ["-d", "half", "--compression", "rle"]),
        ("exr_half_pxr24", ".exr", ["-d", "float", "--compression", "pxr24"]),
        ("exr_half_b44", ".exr", ["-d", "half", "--compression", "b44"]),
        ("exr_half_dwaa", ".exr", ["-d", "half", "--compression", "dwaa"]),
        ("exr_tiled", ".exr", ["-d", "half", "--tile", "8", "8"]),
        ("tif_float", ".tif", ["-d", "float"]),
        ("tif_uint16", ".tif", ["-d", "uint16"]),
        ("jpg", ".jpg", ["-d", "uint8"]),
    ]
    n = 0
    with tempfile.TemporaryDirectory() as tmp:
        for channels in (1, 3, 4):
            for name, ext, args in variants:
                if ext == ".jpg" and channels == 4:
                    continue
                f = os.path.join(tmp, name + ext)
                fill = ",".join(["0.2"] * channels), ",".join(["3.0"] * channels)
                cmd = [tool, "--pattern", "fill:top=%s:bottom=%s" % fill, "16x8", str(channels)]
                if subprocess.run(cmd + args + ["-o", f], capture_output=True).returncode == 0:
                    write(out, "gen_%s_%dch%s" % (name, channels, ext),
                          envmap_seed(ext, Path(f).read_bytes()))
                    n += 1
    return n


def envmap_corpus(data_dir, out):
    n = 0
    for img in sorted((Path(data_dir) / "edge-cases" / "images").glob("*")):
        if img.suffix.lower() in ENVMAP_EXTENSIONS:
            write(out, "edge_" + img.name, envmap_seed(img.suffix.lower(), img.read_bytes()))
            n += 1
    for c in (1, 3):
        write(out, "gen_pfm_%dch_le.pfm" % c, envmap_seed(".pfm", pfm(16, 8, c)))
        write(out, "gen_pfm_%dch_be.pfm" % c, envmap_seed(".pfm", pfm(16, 8, c, False)))
    write(out, "gen_hdr_flat.hdr", envmap_seed(".hdr", radiance_hdr(16, 8, False)))
    write(out, "gen_hdr_rle.hdr", envmap_seed(".hdr", radiance_hdr(16, 8, True)))
    for c in (1, 2, 3, 4):
        for bits in (8, 16):
            write(out, "gen_png_%dch_%d.png" % (c, bits), envmap_seed(".png", png(16, 8, c, bits)))
    # The same bytes under the unknown extension: OpenImageIO picks the reader by content.
    write(out, "gen_hdr_unknown_ext.img", envmap_seed(".img", radiance_hdr(16, 8, True)))
    return n + oiiotool_images(out)


# ---------------------------------------------------------------- light sets
def light_corpus(out):
    full = {"method": "ours", "power_rule": "share", "map": "envmaps/grace.hdr", "count": 3,
            "map_power": [1.5, 1.2, 1.0], "precompute_seconds": 0.001,
            "selection_seconds": 0.0001, "total_seconds": 0.0011,
            "lights": [{"direction": [0, 1, 0], "power": [0.5, 0.4, 0.3]},
                       {"direction": [0.6, 0.0, -0.8], "power": [1, 0.8, 0.7],
                        "solid_angle": 0.2},
                       {"direction": [0, -1e-3, 1], "power": [0, 0, 0], "solid_angle": 12.5}]}
    write(out, "full.json", json.dumps(full, indent=1))
    write(out, "sis.json", json.dumps({"method": "sis", "power_rule": "voronoi",
                                       "lights": [{"direction": [1, 2, 3], "power": [1, 1, 1]}]}))
    write(out, "minimal.json", '{"lights":[{"direction":[0,0,1],"power":[1e30,0,1e-30]}]}')
    write(out, "bad_zero_direction.json",
          '{"lights": [{"direction": [0, 0, 0], "power": [1, 1, 1]}]}')
    write(out, "bad_empty.json", '{"lights": []}')


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenes", required=True)
    ap.add_argument("--data", required=True, help="the shared data folder (edge-cases/ inside)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    out = Path(a.out)
    if out.exists():
        shutil.rmtree(out)
    data = a.data
    if not (Path(data) / "edge-cases").is_dir():
        for d in os.environ.get("ENVTRACE_DATA", "").split(":"):
            if d and (Path(d) / "edge-cases").is_dir():
                data = d
                break
    scene_corpus(a.scenes, out / "fuzz_scene_json")
    n_obj = obj_corpus(data, out / "fuzz_obj_mtl")
    n_img = envmap_corpus(data, out / "fuzz_envmap")
    light_corpus(out / "fuzz_light_set")
    mesh_corpus(a.scenes, out / "fuzz_mesh")
    if n_obj == 0:
        print("make_corpus.py: no edge-cases under %s; OBJ seeds are the hand-written one" % data)
    (out / "stamp").write_text("")
    for h in sorted(p for p in out.iterdir() if p.is_dir()):
        print("make_corpus.py: %s: %d seeds" % (h.name, len(list(h.iterdir()))))


if __name__ == "__main__":
    main()
