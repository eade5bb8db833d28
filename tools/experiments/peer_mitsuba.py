#!/usr/bin/env python3
"""envtrace against a peer renderer, Mitsuba 3 (scalar_rgb, its path tracer), on scenes both can
describe exactly: the same triangles (an OBJ sphere of flat facets and a ground quad, written here),
the same map in Mitsuba's lat-long convention ("convention": "mitsuba"), the same pinhole camera
and box-filtered pixels, and materials whose models are the same in both:

  diffuse      Lambertian                                     -> diffuse
  mirror       a perfect mirror of reflectance R              -> conductor (material none, R)
  microfacet   GGX alpha, separable Smith, F0 = 1             -> roughconductor, ggx, material none
               (Schlick's Fresnel of F0 = 1 is 1: the lobe's D, G and sampling compared alone)
  conductor    GGX alpha, complex index eta + i k per channel -> roughconductor, ggx, eta, k
  dielectric   smooth or GGX (Walter) glass of index ior      -> dielectric / roughdielectric

Mitsuba's max_depth counts the emitter's vertex too: envtrace's depth d is Mitsuba's d + 1. Each
case is rendered by both with several seeds; the report gives the ratio of the image means and a
z-score of the difference against the seed-to-seed noise of both (plus 0.2% of the value), per
16x16 block (rms and worst), so a disagreement beyond Monte Carlo noise shows as |z| >> 1.

  tools/setup-like prerequisite: a Python with mitsuba and numpy (pip install mitsuba numpy)
  tools/experiments/peer_mitsuba.py [--tiny] [--check] [--out DIR] [--cases NAME ...]

--check exits 1 when a case disagrees (the ctest peer_mitsuba: --tiny --check;
it exits 77, skipped, where the Python running it has no mitsuba module).

Writes OUT/peer_mitsuba.md (default docs/figures/peer_mitsuba/)."""
import json
import math
import os
import re
import struct
import sys
import time
import zlib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

# Maps: "smooth.pfm" and "sun.pfm" are written here (write_maps); the others come from the data
# folder. Mitsuba's envmap reads an image as a bilinear field whose first and last rows lie on the
# poles (v (h - 1)), not at the rows' centres, so the same file lights a scene differently there:
# a diffuse ground under grace (256 x 128) 3.0% darker than the map's cos-weighted integral over
# its texels, under royal_esplanade_1k 1.3% (envtrace: within 0.04%). So Mitsuba reads each map
# sampled where it puts its rows (write_maps, mitsuba_grid_map): the same field in both.
# name: (map, envtrace material, envtrace depth)
DIFFUSE = {"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}
CASES = {
    "diffuse_smooth": ("smooth.pfm", DIFFUSE, 3),
    "diffuse_sun": ("sun.pfm", DIFFUSE, 3),
    "mirror_sun": ("sun.pfm", {"type": "mirror", "specular": [0.9, 0.9, 0.9]}, 3),
    "mirror_smooth": ("smooth.pfm", {"type": "mirror", "specular": [0.9, 0.7, 0.5]}, 3),
    "metal_a0.2_sun": ("sun.pfm", {"type": "microfacet", "specular": [1, 1, 1], "roughness": 0.2}, 3),
    "metal_a0.05_smooth": ("smooth.pfm", {"type": "microfacet", "specular": [1, 1, 1], "roughness": 0.05}, 3),
    # Metals of complex index (Mitsuba 3.9.1's RGB eta and k for Au and Cu): the conductor's
    # Fresnel reflectance, which Mitsuba's roughconductor states the same way.
    "gold_a0.2_sun": ("sun.pfm", {"type": "conductor", "eta": [0.143036, 0.375307, 1.44205],
                                  "k": [3.983, 2.38556, 1.60336], "roughness": 0.2}, 3),
    "copper_a0.05_smooth": ("smooth.pfm", {"type": "conductor", "eta": [0.201005, 0.92375, 1.10222],
                                           "k": [3.91326, 2.45305, 2.14209], "roughness": 0.05}, 3),
    "glass_sun": ("sun.pfm", {"type": "dielectric", "ior": 1.5}, 16),
    "glass_smooth": ("smooth.pfm", {"type": "dielectric", "ior": 1.5}, 16),
    "rough_glass_a0.3_sun": ("sun.pfm", {"type": "dielectric", "ior": 1.5, "roughness": 0.3}, 16),
    "rough_glass_a0.1_smooth": ("smooth.pfm", {"type": "dielectric", "ior": 1.33, "roughness": 0.1}, 16),
    "textured_ground_sun": ("sun.pfm", DIFFUSE, 3),
    "diffuse_grace": ("grace.hdr", DIFFUSE, 3),
    # Mitsuba's own material-preview scene from its XML (data/reference/matpreview), against
    # scenes/matpreview.json, envtrace's conversion of it (z-up to y-up, the map's to_world as
    # "convention": "mitsuba", "rotation": -77), the object diffuse in both: the conversion checked.
    "matpreview_diffuse": ("museum_wells6.exr", {"type": "diffuse", "albedo": [0.94, 0.271, 0.361]}, 5),
    "metal_a0.2_esplanade": ("royal_esplanade_1k.hdr", {"type": "microfacet", "specular": [1, 1, 1], "roughness": 0.2}, 3),
}
GROUND = {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}
# Cases whose ground is not GROUND: an 8-bit sRGB PNG albedo (write_texture), red growing with u
# and green with v, so that a flipped or transposed lookup or a missing sRGB decode shows.
TEXTURED = {"type": "diffuse", "albedo": {"texture": "ground.png", "uv_scale": 2}}
GROUND_OF = {"textured_ground_sun": TEXTURED}
# --tiny (the ctest run): the analytic maps without the sun's caustics, whose few-sample estimates
# are too heavy-tailed for four seeds to measure their noise.
TINY = ["diffuse_sun", "metal_a0.2_sun", "metal_a0.05_smooth", "gold_a0.2_sun", "mirror_smooth",
        "glass_smooth", "rough_glass_a0.1_smooth", "textured_ground_sun", "diffuse_grace",
        "matpreview_diffuse"]
# --check: a case agrees when its blocks' z-scores have an rms of at most Z_RMS (about 1 when the
# two renderers agree, more with few seeds, whose spread estimates are t-distributed) and its image
# mean is within MEAN_TOL plus four standard errors of Mitsuba's.
Z_RMS, MEAN_TOL = 2.0, 0.005


def sphere_obj(path, nu=96, nv=48):
    """A unit sphere of flat facets (no normals: both renderers then shade with the face normal)."""
    v = [(0.0, 1.0, 0.0)]
    for j in range(1, nv):
        th = math.pi * j / nv
        for i in range(nu):
            ph = 2 * math.pi * i / nu
            v.append((math.sin(th) * math.cos(ph), math.cos(th), -math.sin(th) * math.sin(ph)))
    v.append((0.0, -1.0, 0.0))
    idx = lambda j, i: 2 + (j - 1) * nu + i % nu  # noqa: E731  (1-based OBJ index of ring j)
    f = []
    for i in range(nu):
        f.append((1, idx(1, i), idx(1, i + 1)))
        f.append((len(v), idx(nv - 1, i + 1), idx(nv - 1, i)))
    for j in range(1, nv - 1):
        for i in range(nu):
            a, b, c, d = idx(j, i), idx(j, i + 1), idx(j + 1, i + 1), idx(j + 1, i)
            f += [(a, d, c), (a, c, b)]
    with open(path, "w") as o:
        o.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in v)
        o.writelines(f"f {a} {b} {c}\n" for a, b, c in f)


def write_maps(tmp, w=2048, h=1024):
    """Two analytic maps, smooth at the scale of a texel: "smooth", a sky gradient with a broad warm
    lobe; "sun", the same under a Gaussian sun of 1.5 degrees holding most of the power. Each is
    written twice, sampled where each renderer puts its texels: envtrace's row i at v = (i + 0.5) / h
    (the lat-long convention of the data README), Mitsuba's at v = i / (h - 1) (its envmap's bilinear
    grid reaches both poles); columns at u = (j + 0.5) / w in both, in Mitsuba's convention
    (u = atan2(x, -z) / 2 pi)."""
    def field(v, u):
        th, ph = np.pi * v[:, None], 2 * np.pi * u[None, :]
        d = np.stack([np.sin(th) * np.sin(ph), np.cos(th) * np.ones_like(ph), -np.sin(th) * np.cos(ph)], -1)

        def lobe(direction, sigma_deg):
            c = d @ (np.array(direction) / np.linalg.norm(direction))
            return np.exp(-(np.arccos(np.clip(c, -1, 1)) / np.radians(sigma_deg)) ** 2 / 2)

        sky = 0.4 + 0.6 * np.clip(d[..., 1], 0, 1)
        base = np.stack([sky * 0.6, sky * 0.8, sky], -1) + lobe([1, 0.3, 0.5], 25)[..., None] * [3.0, 2.0, 1.0]
        return {"smooth": base, "sun": base + lobe([-0.4, 0.8, 0.45], 1.5)[..., None] * [2000.0, 1800.0, 1500.0]}

    u = (np.arange(w) + 0.5) / w
    for suffix, v in (("", (np.arange(h) + 0.5) / h), ("_mitsuba", np.arange(h) / (h - 1))):
        for name, img in field(v, u).items():
            write_pfm(os.path.join(tmp, name + suffix + ".pfm"), img)


def map_path(tmp, name, renderer="envtrace"):
    """The map file a renderer reads: for Mitsuba a copy resampled onto its grid (write_maps,
    mitsuba_grid_map), so that both renderers light the scene with the same field."""
    analytic = name in ("smooth.pfm", "sun.pfm")
    if renderer == "envtrace":
        return os.path.join(tmp, name) if analytic else os.path.join(common.data_dir(), "envmaps", name)
    return os.path.join(tmp, name.replace(".pfm", "_mitsuba.pfm")) if analytic else mitsuba_grid_map(tmp, name)


def mitsuba_grid_map(tmp, name):
    """A real map resampled for Mitsuba: its rows at v = i / (h - 1) read from envtrace's bilinear
    field (rows at (i + 0.5) / h, clamped at the poles: kernels/envmap.h, etk_env_quad); the
    columns lie at the texel centres in both, so they are kept. Mitsuba's bilinear field of these
    rows then equals envtrace's up to the second order in the texel size."""
    out = os.path.join(tmp, os.path.splitext(name)[0] + "_mitsuba.pfm")
    if not os.path.exists(out):
        pfm = os.path.join(tmp, "converted.pfm")
        common.run([common.envtrace(), "convert", os.path.join(common.data_dir(), "envmaps", name), pfm])
        img = common.read_pfm(pfm)
        h = img.shape[0]
        y = np.arange(h) / (h - 1) * h - 0.5
        r0 = np.floor(y).astype(int)
        t = (y - r0)[:, None, None]
        rows = img[np.clip(r0, 0, h - 1)] * (1 - t) + img[np.clip(r0 + 1, 0, h - 1)] * t
        write_pfm(out, rows)
    return out


def write_pfm(path, img):
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1\n" % (img.shape[1], img.shape[0]))
        f.write(np.ascontiguousarray(img[::-1], dtype="<f4").tobytes())


def ground_obj(path, s=4.0):
    """The ground quad, texture coordinates (0, 0) .. (1, 1) from its -x +z corner (OBJ's v up)."""
    with open(path, "w") as o:
        o.write(f"v {-s} 0 {s}\nv {s} 0 {s}\nv {s} 0 {-s}\nv {-s} 0 {-s}\n")
        o.write("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")


def write_texture(path, n=32):
    """A smooth 8-bit sRGB texture as PNG: red grows with u (to the right), green with v (up: the
    top row is v = 1), blue constant."""
    u = (np.arange(n) + 0.5) / n
    img = np.zeros((n, n, 3), np.uint8)
    img[..., 0] = np.round(40 + 200 * u)[None, :]
    img[..., 1] = np.round(40 + 200 * u[::-1])[:, None]
    img[..., 2] = 120
    raw = b"".join(b"\x00" + row.tobytes() for row in img)

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", n, n, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


CAMERA = {"eye": [0.0, 1.6, 4.2], "target": [0.0, 0.8, 0.0], "up": [0, 1, 0], "fov": 32}


def envtrace_scene(tmp, case, size):
    envmap, mat, depth = CASES[case]
    if case.startswith("matpreview"):
        return envtrace_matpreview(tmp, case, size)
    s = {"camera": CAMERA, "film": {"width": size, "height": size},
         "environment": {"map": map_path(tmp, envmap), "convention": "mitsuba"},
         "materials": {"ground": GROUND_OF.get(case, GROUND), "object": mat},
         "shapes": [{"type": "mesh", "file": "ground.obj", "material": "ground"},
                    {"type": "mesh", "file": "sphere.obj", "material": "object",
                     "transform": {"translate": [0, 0.8, 0], "scale": 0.8}}],
         "render": {"max_depth": depth, "strategy": "mis", "sampler": "sobol"}}
    path = os.path.join(tmp, case + ".json")
    with open(path, "w") as f:
        json.dump(s, f)
    return path


def matpreview_width(size):
    return round(size * 683 / 512)


def envtrace_matpreview(tmp, case, size):
    envmap, mat, depth = CASES[case]
    with open(os.path.join(common.REPO, "scenes", "matpreview.json")) as f:
        s = json.load(f)
    s["film"] = {"width": matpreview_width(size), "height": size}
    s["materials"]["matpreview"] = mat
    s["environment"]["map"] = map_path(tmp, envmap)
    for sh in s["shapes"]:
        sh["file"] = os.path.join(common.data_dir(), sh["file"])
    s["render"] = {"max_depth": depth, "strategy": "mis", "sampler": "sobol"}
    s.pop("output", None)
    path = os.path.join(tmp, case + ".json")
    with open(path, "w") as f:
        json.dump(s, f)
    return path


def mitsuba_matpreview(mi, tmp, case, size, spp):
    """The XML as shipped, with its shapes read from the OBJ conversions (texture coordinates as
    stored), a box filter (envtrace's
    pixels), the map resampled onto Mitsuba's grid and the object's plastic made diffuse."""
    envmap, mat, depth = CASES[case]
    ref = os.path.join(common.data_dir(), "reference", "matpreview")
    with open(os.path.join(ref, "matpreview_scene.xml")) as f:
        xml = f.read()
    xml = re.sub(r'type="serialized"( id="[^"]*">)\s*<string name="filename" value="matpreview.serialized" />'
                 r'\s*<integer name="shape_index" value="(\d)" />',
                 lambda m: f'type="obj"{m.group(1)}<string name="filename" value="'
                 f'{os.path.join(ref, "matpreview_shape" + m.group(2) + ".obj")}"/>'
                 # the OBJ holds the serialized mesh's texture coordinates as stored, which Mitsuba
                 # reads unflipped from a .serialized and flips from an OBJ unless told not to
                 '<boolean name="flip_tex_coords" value="false"/>', xml)
    xml = xml.replace('<rfilter type="gaussian" />', '<rfilter type="box" />')
    xml = xml.replace('value="envmap.exr"', f'value="{map_path(tmp, envmap, "mitsuba")}"')
    albedo = ", ".join(str(c) for c in mat["albedo"])
    xml = re.sub(r'<bsdf type="plastic" id="bsdf-matpreview">.*?</bsdf>',
                 f'<bsdf type="diffuse" id="bsdf-matpreview"><rgb name="reflectance" value="{albedo}"/></bsdf>',
                 xml, flags=re.S)
    assert xml.count('type="obj"') == 3 and "plastic" not in xml
    return mi.load_string(xml, spp=spp, width=matpreview_width(size), height=size, max_depth=depth + 1)


def mitsuba_bsdf(mi, mat, tmp=None):
    t = mat["type"]
    if t == "diffuse" and isinstance(mat["albedo"], dict):  # Mitsuba decodes an 8-bit PNG from sRGB
        s = mat["albedo"]["uv_scale"]
        return {"type": "diffuse", "reflectance": {
            "type": "bitmap", "filename": os.path.join(tmp, mat["albedo"]["texture"]),
            "to_uv": mi.ScalarTransform4f().scale([s, s, 1])}}
    if t == "diffuse":
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": mat["albedo"]}}
    if t == "mirror":
        return {"type": "conductor", "material": "none",
                "specular_reflectance": {"type": "rgb", "value": mat["specular"]}}
    if t == "microfacet":  # F0 = 1: Schlick's Fresnel is 1, as a conductor's of material "none"
        assert mat["specular"] == [1, 1, 1]
        return {"type": "roughconductor", "material": "none", "distribution": "ggx", "alpha": mat["roughness"]}
    if t == "conductor":
        return {"type": "roughconductor", "distribution": "ggx", "alpha": mat["roughness"],
                "eta": {"type": "rgb", "value": mat["eta"]}, "k": {"type": "rgb", "value": mat["k"]}}
    if t == "dielectric":
        if mat.get("roughness", 0.0) < 1e-3:
            return {"type": "dielectric", "int_ior": mat["ior"], "ext_ior": 1.0}
        return {"type": "roughdielectric", "distribution": "ggx", "alpha": mat["roughness"],
                "int_ior": mat["ior"], "ext_ior": 1.0}
    raise ValueError(t)


def mitsuba_scene(mi, tmp, case, size, spp):
    """The case's scene, loaded once and rendered with each seed."""
    envmap, mat, depth = CASES[case]
    if case.startswith("matpreview"):
        return mitsuba_matpreview(mi, tmp, case, size, spp)
    T = mi.ScalarTransform4f
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": depth + 1},
        "sensor": {"type": "perspective", "fov": CAMERA["fov"], "fov_axis": "y",
                   "to_world": T().look_at(origin=CAMERA["eye"], target=CAMERA["target"], up=CAMERA["up"]),
                   "sampler": {"type": "independent", "sample_count": spp},
                   "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"},
                            "pixel_format": "rgb"}},
        "env": {"type": "envmap", "filename": map_path(tmp, envmap, "mitsuba")},
        "ground": {"type": "obj", "filename": os.path.join(tmp, "ground.obj"), "face_normals": True,
                   "bsdf": mitsuba_bsdf(mi, GROUND_OF.get(case, GROUND), tmp)},
        "object": {"type": "obj", "filename": os.path.join(tmp, "sphere.obj"), "face_normals": True,
                   "to_world": T().translate([0, 0.8, 0]) @ T().scale(0.8), "bsdf": mitsuba_bsdf(mi, mat)},
    })


def blocks(img, n=16):
    h, w = img.shape[0] // n * n, img.shape[1] // n * n
    return img[:h, :w].mean(axis=2).reshape(h // n, n, w // n, n).mean(axis=(1, 3))


def compare_case(mi, tmp, case, args):
    """Both renderers, args.seeds seeds each; the statistics of one row of the report."""
    scene = envtrace_scene(tmp, case, args.size)
    t0 = time.time()
    scene_ms = mitsuba_scene(mi, tmp, case, args.size, args.spp)
    et, ms, et_t, ms_t = [], [], 0.0, time.time() - t0
    for seed in range(1, args.seeds + 1):
        img = os.path.join(tmp, f"{case}_{seed}.pfm")
        t0 = time.time()
        common.run([common.envtrace(), "render", scene, "--spp", str(args.spp), "--seed", str(seed),
                    "--backend", args.backend, "--strategy", args.strategy, "-o", img])
        et_t += time.time() - t0
        et.append(common.read_pfm(img))
        t0 = time.time()
        ms.append(np.array(mi.render(scene_ms, seed=seed), dtype=np.float64)[:, :, :3])
        ms_t += time.time() - t0
    et, ms = np.array(et), np.array(ms)
    finite = bool(np.isfinite(et).all() and np.isfinite(ms).all())
    ratio = et.mean(axis=(0, 1, 2)) / ms.mean(axis=(0, 1, 2))
    # Per block: the difference of the seed means against the standard error of both, plus 0.2%
    # of the block's value: where the noise is nil (the sky seen directly) the two renderers' map
    # lookups differ by that much (bilinear fields on grids half a texel apart), which is not a
    # difference of the transport compared here.
    ba, bb = np.array([blocks(x) for x in et]), np.array([blocks(x) for x in ms])
    se = np.sqrt(ba.var(axis=0, ddof=1) / len(ba) + bb.var(axis=0, ddof=1) / len(bb)
                 + (2e-3 * np.abs(bb.mean(axis=0))) ** 2)
    z = (ba.mean(axis=0) - bb.mean(axis=0)) / np.maximum(se, 1e-12)
    z_rms = float(np.sqrt((z ** 2).mean()))
    # The image mean against its standard error from both renderers' seed means.
    se_mean = np.sqrt(et.mean(axis=(1, 2, 3)).var(ddof=1) / len(et) + ms.mean(axis=(1, 2, 3)).var(ddof=1) / len(ms))
    agrees = finite and z_rms <= Z_RMS and abs(et.mean() - ms.mean()) <= MEAN_TOL * ms.mean() + 4 * se_mean
    r = {"case": case, "ratio": ratio, "z_rms": z_rms, "z_max": float(np.abs(z).max()),
         "verdict": "agrees" if agrees else "DISAGREES",
         "envtrace_s": et_t, "mitsuba_s": ms_t}
    print(f"{case}: mean envtrace / mitsuba R G B {' '.join(f'{x:.4f}' for x in ratio)}; block z rms "
          f"{z_rms:.2f} max {r['z_max']:.2f}; finite {finite}; {r['verdict']}; {et_t:.1f} s / {ms_t:.1f} s",
          flush=True)
    return r


def main():
    p = common.parser(__doc__.split("\n\n")[0])
    p.add_argument("--cases", nargs="*", default=list(CASES))
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--spp", type=int, default=256, help="samples per pixel of each seed, both renderers")
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--check", action="store_true", help="exit 1 when a case disagrees")
    p.add_argument("--strategy", default="mis", help="envtrace's estimator (envtrace render --strategy)")
    p.add_argument("--backend", default="cpu", choices=["cpu", "opencl"], help="envtrace's back end")
    args = p.parse_args()
    unknown = [c for c in args.cases if c not in CASES]
    if unknown:
        p.error(f"unknown case(s) {', '.join(unknown)}; known: {', '.join(CASES)}")
    try:
        import mitsuba as mi
    except ImportError:
        print("peer_mitsuba: no mitsuba module in this Python (pip install mitsuba): skipping", file=sys.stderr)
        sys.exit(77)
    mi.set_variant("scalar_rgb")
    if args.tiny:
        args.size, args.spp, args.seeds = 48, 32, 4
        if args.cases == list(CASES):
            args.cases = TINY
    out = common.out_dir(args, "peer_mitsuba")
    tmp = common.tmpdir("peer_mitsuba")
    sphere_obj(os.path.join(tmp, "sphere.obj"))
    ground_obj(os.path.join(tmp, "ground.obj"))
    write_maps(tmp)
    write_texture(os.path.join(tmp, "ground.png"))
    rows = [compare_case(mi, tmp, case, args) for case in args.cases]
    with open(os.path.join(out, "peer_mitsuba.md"), "w") as f:
        f.write(f"Mitsuba {mi.__version__} (scalar_rgb, path) against envtrace ({args.backend}, {args.strategy}, "
                f"sobol); {args.size}x{args.size}, {args.spp} spp x {args.seeds} seeds each "
                f"(`tools/experiments/peer_mitsuba.py --spp {args.spp} --seeds {args.seeds} --strategy "
                f"{args.strategy} --backend {args.backend}`)\n\n")
        f.write("| case | mean ratio R / G / B | block z rms | block z max | verdict | envtrace s | mitsuba s |\n")
        f.write("|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['case']} | {' / '.join(f'{x:.4f}' for x in r['ratio'])} | {r['z_rms']:.2f} | "
                    f"{r['z_max']:.2f} | {r['verdict']} | {r['envtrace_s']:.1f} | {r['mitsuba_s']:.1f} |\n")
    print(f"wrote {os.path.join(out, 'peer_mitsuba.md')}")
    failed = [r["case"] for r in rows if r["verdict"] == "DISAGREES"]
    if args.check and failed:
        sys.exit(f"peer_mitsuba: envtrace and Mitsuba disagree beyond the noise on: {', '.join(failed)}")


if __name__ == "__main__":
    main()
