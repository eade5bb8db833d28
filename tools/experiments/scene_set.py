#!/usr/bin/python3
"""A held-out scene set for measuring estimators: scenes nobody tuned on, generated from a seed,
split into a half to tune on and a half to report on.

    tools/experiments/scene_set.py --out DIR [--count 24] [--seed 1] [--size 160x120]

Each layout is written once (its geometry as OBJ + MTL where it has any) and rendered at depth 1
and depth 5 (two scene files). Layouts:
  room  a closed box of random size (3-8 x 2.4-4 x 3-8 m) lit only through openings: one to three
        windows in one or two walls, sometimes a skylight, sometimes a door to the floor; one to
        four pieces of furniture (boxes); a statue on the floor in half of them; the camera inside
        near a wall, looking across the room.
  open  a diffuse ground under the open sky with one to three statues (meshes of the shared data,
        spheres) of random materials, seen from a random side.
Lighting: every real map of the data folder (`--data`, default ../shared/data) turned at random,
and procedural skies whose sun ranges from tiny (0.1 degrees) to broad (10 degrees), at random
heights and azimuths. Materials: diffuse, plastic and metal at several roughnesses (GGX alpha 0.02
to 0.5), glass (smooth and rough).

The split is by layout (both depths of a layout on the same side), alternating over a shuffle
drawn from the seed: DIR/tune.txt and DIR/report.txt list the scene files, one a line, for
`tools/experiments/efficiency.py --scenes $(cat DIR/report.txt) ...`; DIR/manifest.json holds
both lists and every layout's parameters."""
import argparse
import json
import math
import os
import random
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from room_geometry import Obj, wall_with_holes  # noqa: E402

STATUES = ["meshes/stanford-bunny.obj", "meshes/spot.obj", "meshes/suzanne.obj",
           "meshes/teapot.obj", "meshes/ogre.obj"]
METALS = {"gold": ([0.143, 0.375, 1.442], [3.983, 2.386, 1.603]),
          "copper": ([0.201, 0.924, 1.102], [3.913, 2.453, 2.142]),
          "silver": ([0.155, 0.117, 0.138], [4.828, 3.122, 2.147]),
          "aluminium": ([1.658, 0.880, 0.521], [9.224, 6.270, 4.837])}
SUN_RADII = [0.1, 0.27, 0.8, 3.0, 10.0]  # degrees: tiny to broad


def colour(rng, lo=0.2, hi=0.85):
    return [round(rng.uniform(lo, hi), 3) for _ in range(3)]


def material(rng):
    """A random statue material: diffuse, plastic, metal or glass."""
    kind = rng.choice(["diffuse", "plastic", "metal", "metal", "glass"])
    if kind == "diffuse":
        return {"type": "diffuse", "albedo": colour(rng)}
    if kind == "plastic":
        return {"type": "plastic", "albedo": colour(rng),
                "roughness": rng.choice([0.05, 0.1, 0.3, 0.5])}
    if kind == "metal":
        eta, k = METALS[rng.choice(sorted(METALS))]
        return {"type": "conductor", "eta": eta, "k": k,
                "roughness": rng.choice([0.02, 0.05, 0.1, 0.3])}
    return {"type": "dielectric", "ior": 1.5, "roughness": rng.choice([0.0, 0.0, 0.1])}


def sky_with_radius(rng):
    radius = rng.choice(SUN_RADII)
    # The sun's power kept alike whatever its size: radiance x solid angle ~ radiance x radius^2.
    return {"sky": {"resolution": [1024, 512], "sun_elevation": round(rng.uniform(8.0, 70.0), 1),
                    "sun_azimuth": round(rng.uniform(0.0, 360.0), 1), "sun_radius": radius,
                    "sun_radiance": round(3000.0 * (0.8 / radius) ** 2, 1),
                    "sky_radiance": round(rng.uniform(0.3, 2.0), 2)}}


def environment(rng, maps):
    if maps and rng.random() < 2.0 / 3.0:
        return {"map": rng.choice(maps), "rotation": round(rng.uniform(0.0, 360.0), 1)}
    return sky_with_radius(rng)


def openings(rng, width, height, count):
    """count windows along a wall of this width and height: (x0, x1, y0, y1), apart."""
    holes, slot = [], width / count
    for k in range(count):
        w = rng.uniform(0.5, min(1.6, slot - 0.3))
        x0 = k * slot + rng.uniform(0.15, slot - w - 0.15)
        y0 = rng.uniform(0.6, 1.2)
        y1 = min(height - 0.3, y0 + rng.uniform(0.8, 1.6))
        holes.append((round(x0, 3), round(x0 + w, 3), round(y0, 3), round(y1, 3)))
    return holes


def room(rng, data, folder, name):
    """A closed room lit only through its openings; returns (shapes, camera, facts)."""
    W, H, D = rng.uniform(3.0, 8.0), rng.uniform(2.4, 4.0), rng.uniform(3.0, 8.0)
    o = Obj()
    o.quad((0, 0, 0), (0, 0, D), (W, 0, D), (W, 0, 0), "floor")
    facts = {"size": [round(W, 2), round(H, 2), round(D, 2)]}
    # The south wall (z = 0) always has windows; the east wall (x = W) sometimes.
    south = openings(rng, W, H, rng.randint(1, 3))
    if rng.random() < 0.3:  # a door: an opening down to the floor
        x0 = rng.uniform(0.2, W - 1.2)
        if all(x0 + 1.0 < h[0] or x0 > h[1] for h in south):
            south.append((round(x0, 3), round(x0 + 0.9, 3), 0.0, min(2.1, H - 0.2)))
            facts["door"] = True
    wall_with_holes(o, (0, W, 0, H, 0.0), south, "wall")
    facts["south_openings"] = len(south)
    east = openings(rng, D, H, 1) if rng.random() < 0.4 else []
    if east:  # the wall x = W, built as a z = 0 wall and turned: (x, y, z) -> (W, y, x)
        e = Obj()
        wall_with_holes(e, (0, D, 0, H, 0.0), east, "wall")
        for mtl, idx in e.f:
            quad = [e.v[i - 1] for i in idx]
            o.quad(*[(W, y, x) for (x, y, _) in quad], mtl)
        facts["east_openings"] = len(east)
    else:
        o.quad((W, 0, 0), (W, 0, D), (W, H, D), (W, H, 0), "wall")
    o.quad((0, 0, D), (0, H, D), (W, H, D), (W, 0, D), "wall")  # north, faces -z
    o.quad((0, 0, 0), (0, H, 0), (0, H, D), (0, 0, D), "wall")  # west, faces +x
    if rng.random() < 0.35:  # a skylight: the ceiling around a square opening
        s = rng.uniform(0.5, 1.2)
        a, b = rng.uniform(0.5, W - s - 0.5), rng.uniform(0.5, D - s - 0.5)
        for x0, x1, z0, z1 in ((0, W, 0, b), (0, W, b + s, D), (0, a, b, b + s), (a + s, W, b, b + s)):
            o.quad((x0, H, z0), (x1, H, z0), (x1, H, z1), (x0, H, z1), "ceiling")
        facts["skylight"] = round(s, 2)
    else:
        o.quad((0, H, 0), (W, H, 0), (W, H, D), (0, H, D), "ceiling")
    for k in range(rng.randint(1, 4)):  # furniture
        w, d, h = rng.uniform(0.4, 1.6), rng.uniform(0.4, 1.2), rng.uniform(0.4, 1.8)
        x, z = rng.uniform(0.1, W - w - 0.1), rng.uniform(0.8, D - d - 0.1)
        o.box((x, 0.0, z), (x + w, h, z + d), f"furniture{k}", skip=("-y",))
    mats = {"floor": colour(rng, 0.3, 0.7), "wall": colour(rng, 0.55, 0.85),
            "ceiling": colour(rng, 0.7, 0.85)}
    mats.update({f"furniture{k}": colour(rng) for k in range(4)})
    o.write(folder, name, mats, "scene_set.py")
    shapes = [{"type": "mesh", "file": f"{name}.obj"}]
    if rng.random() < 0.5:
        shapes.append(statue(rng, data, [W * rng.uniform(0.3, 0.7), 0.0, D * rng.uniform(0.3, 0.6)],
                             rng.uniform(0.5, 0.9), "statue0"))
    eye = [W * rng.uniform(0.2, 0.8), H * rng.uniform(0.45, 0.7), D - 0.3]
    target = [W * rng.uniform(0.3, 0.7), H * rng.uniform(0.2, 0.45), rng.uniform(0.0, D * 0.4)]
    return shapes, {"eye": eye, "target": target, "up": [0, 1, 0], "fov": 70}, facts


_BOUNDS = {}


def mesh_bounds(data, path):
    """(lo, hi) of an OBJ's vertices."""
    if path not in _BOUNDS:
        lo, hi = [math.inf] * 3, [-math.inf] * 3
        with open(os.path.join(data, path)) as f:
            for line in f:
                if line.startswith("v "):
                    p = [float(x) for x in line.split()[1:4]]
                    lo = [min(a, b) for a, b in zip(lo, p)]
                    hi = [max(a, b) for a, b in zip(hi, p)]
        _BOUNDS[path] = (lo, hi)
    return _BOUNDS[path]


def statue(rng, data, base, size, mtl):
    """A statue of the shared meshes (or a sphere) standing on `base`, `size` tall."""
    if rng.random() < 0.2:
        return {"type": "sphere", "center": [base[0], base[1] + size / 2, base[2]],
                "radius": size / 2, "material": mtl}
    path = rng.choice(STATUES)
    lo, hi = mesh_bounds(data, path)
    s = size / max(hi[1] - lo[1], 1e-6)
    angle = round(rng.uniform(0, 360), 1)
    # Scaled to the height, its foot's centre moved to the origin, turned about y, placed: as a
    # matrix (the loader's scale-rotate-translate order cannot centre first).
    cx, cz = (lo[0] + hi[0]) / 2, (lo[2] + hi[2]) / 2
    c, n = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    tx = -s * (c * cx + n * cz) + base[0]
    tz = -s * (-n * cx + c * cz) + base[2]
    ty = -s * lo[1] + base[1]
    return {"type": "mesh", "file": path, "material": mtl,
            "transform": {"matrix": [round(v, 6) for v in (s * c, 0, s * n, tx,
                                                            0, s, 0, ty,
                                                            -s * n, 0, s * c, tz,
                                                            0, 0, 0, 1)]}}


def open_scene(rng, data):
    """Statues on a ground under the open sky; returns (shapes, camera, facts)."""
    shapes = [{"type": "quad", "size": 40, "material": "ground"}]
    n = rng.randint(1, 3)
    for k in range(n):
        shapes.append(statue(rng, data, [(k - (n - 1) / 2) * 1.4, 0.0, rng.uniform(-0.5, 0.5)],
                             rng.uniform(0.8, 1.3), f"statue{k}"))
    angle = math.radians(rng.uniform(0, 360))
    dist = rng.uniform(3.5, 6.0)
    eye = [dist * math.sin(angle), rng.uniform(0.6, 2.5), dist * math.cos(angle)]
    return shapes, {"eye": eye, "target": [0, 0.5, 0], "up": [0, 1, 0], "fov": 45}, {"statues": n}


def used_materials(shapes):
    return sorted({s["material"] for s in shapes if "material" in s})


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--count", type=int, default=24, help="layouts (each at depth 1 and 5)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--data", default=os.environ.get("ENVTRACE_DATA", "../shared/data").split(":")[0])
    ap.add_argument("--render-check", metavar="ENVTRACE",
                    help="render every scene at 1 spp natively with this binary; fail if one fails")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    rng = random.Random(args.seed)
    maps_dir = os.path.join(args.data, "envmaps")
    maps = sorted("envmaps/" + f for f in os.listdir(maps_dir)) if os.path.isdir(maps_dir) else []
    os.makedirs(args.out, exist_ok=True)
    layouts = []
    for i in range(args.count):
        name = f"{'room' if i % 2 == 0 else 'open'}{i:03d}"
        if i % 2 == 0:
            shapes, camera, facts = room(rng, args.data, args.out, name)
        else:
            shapes, camera, facts = open_scene(rng, args.data)
        env = environment(rng, maps)
        materials = {m: material(rng) for m in used_materials(shapes) if m != "ground"}
        if any(s.get("material") == "ground" for s in shapes):
            materials["ground"] = {"type": "diffuse", "albedo": colour(rng, 0.3, 0.6)}
        files = []
        for depth in (1, 5):
            scene = {"camera": camera, "film": {"width": w, "height": h}, "environment": env,
                     "materials": materials, "shapes": shapes,
                     "render": {"spp": 64, "max_depth": depth}}
            path = os.path.join(args.out, f"{name}_d{depth}.json")
            with open(path, "w") as f:
                json.dump(scene, f, indent=1)
                f.write("\n")
            files.append(path)
        layouts.append({"name": name, "files": files, "environment": env, **facts})
    order = list(range(len(layouts)))
    random.Random(args.seed * 7919 + 1).shuffle(order)
    halves = {"tune": [], "report": []}
    for rank, i in enumerate(order):
        halves["tune" if rank % 2 == 0 else "report"] += layouts[i]["files"]
    for half, files in halves.items():
        with open(os.path.join(args.out, half + ".txt"), "w") as f:
            f.write("\n".join(sorted(files)) + "\n")
    with open(os.path.join(args.out, "manifest.json"), "w") as f:
        json.dump({"seed": args.seed, "layouts": layouts,
                   "tune": sorted(halves["tune"]), "report": sorted(halves["report"])}, f, indent=1)
    print(f"scene_set: {len(layouts)} layouts, {2 * len(layouts)} scenes in {args.out} "
          f"(tune {len(halves['tune'])}, report {len(halves['report'])})")
    if args.render_check:
        render_check(args.render_check, halves["tune"] + halves["report"])


def render_check(exe, files):
    """Every scene loads and renders (1 spp, native): the generator writes only valid scenes."""
    failed = 0
    for path in sorted(files):
        r = subprocess.run([exe, "render", path, "--spp", "1", "--backend", "cpu", "--threads", "1",
                            "-o", path[:-5] + ".pfm"], capture_output=True, text=True)
        if r.returncode != 0:
            failed += 1
            print(f"scene_set: {path} did not render:\n{r.stderr}", file=sys.stderr)
    if failed:
        sys.exit(1)
    print(f"scene_set: all {len(files)} scenes rendered")


if __name__ == "__main__":
    main()
