#!/usr/bin/python3
"""Efficiency of envtrace's estimators: relative MSE x time against a converged reference, relative to the
paper's MIS.

    tools/experiments/efficiency.py [--budgets 0.5 2 | --spp N] [--seeds 3] [--maps ...] [--depths 1 5]
                                    [--strategies light bsdf mis ...] [--out DIR] [--tiny]

The suite: five maps (a tiny intense sun: royal_esplanade_1k, spot1Lux; few small sources:
grace; broad light: pedestrian_overpass_1k, venice_sunset_1k; `--maps studio` adds a generated
map of three softboxes on black), each lighting one scene of five
spheres in a row on a diffuse ground -- diffuse, plastic (GGX alpha 0.3), metal alpha 0.2, metal
alpha 0.05, mirror -- at path depth 1 and 5. Strategies are --strategy names with options:
`mis+vndf` (--bsdf-sampling vndf), `visibility+power` (--mis-heuristic power), `compensated+ndf`,
`compensated+x0.5` (the distribution built on luminance^0.5, the paper's tone-mapped future-work
item), `mis+l4+b2` (splitting: 4 light and 2 BSDF samples per vertex), `visibility+noverdict`
(the learned tables throughout, without the verdict that measures them against MIS). Each
sphere's pixels and the ground's are measured on their own (regions(): masks from the camera), so
one render measures every material.

For each scene, strategy, wall-clock budget and seed: a render with --time-limit BUDGET (the
native back end, PFM output), its MSE per material region and over the image against the
reference, and its render time (render_seconds of --stats: the pass loop, not loading). The
efficiency of a strategy is 1 / (MSE x time) with MSE averaged over the seeds and time the mean
time; the table gives it relative to `mis` (the paper's estimator): 2.0 means the strategy reaches
the same error in half the time. Per scene, the gain is the geometric mean over the budgets.

The reference: two renders with `mis`, different seeds, --time-limit REF/2 each; their mean is the
reference and half their difference estimates its own noise (relative error: per pixel
channel (x - ref)^2 / (ref^2 + (0.01 mean ref)^2)), which is subtracted from every
measured MSE (so a reference that is not quite converged does not flatten the ratios). Cached in
OUT/ref/ by scene and duration.

How sure: each gain comes with a 90% bootstrap interval over the seeds -- every (scene,
strategy, budget)'s seeds resampled with replacement, `mis`'s too, 2000 times with a fixed
generator (so the tables are reproducible), and the gain and the geometric mean recomputed. A
scene whose error is a few rare fireflies (caustics of a tiny sun) shows a wide interval: its
gain in one run says little, and more seeds or longer budgets are needed to rank estimators on it.
`--tables-from OUT/efficiency.csv` rewrites the tables of an earlier run without rendering.
The seeds are resampled together: a seed's renders by two strategies share sample points and are
correlated, so their ratio is surer than either.

Equal samples (`--spp N ...`, with --ref-seconds): renders of N samples per pixel instead of N
seconds, each timed by its render_seconds; the efficiency is the same 1 / (MSE x time). A seed's
image is then the same whatever the machine's load, only its time moves, so a scene whose error
is rare fireflies can be given many seeds on a busy machine, and the seed-by-seed pairing of the
strategies is closer (at equal time they render different sample counts). The strategies
alternate seed by seed in both modes, so a drifting load times them alike.

Fireflies: the brightest pixel of each render over the brightest pixel of the reference (max over
seeds); NaN/Inf: the renders' nonfinite_samples and any non-finite pixel.

--scenes FILE... measures given scene files instead (the interiors of the visibility
strategy), each at its own depth and film size (--size overrides it), the whole image as one
region: `tools/experiments/efficiency.py --scenes scenes/interiors/window_room.json --strategies
mis visibility --budgets 4 16 --ref-seconds 240 --out docs/figures/visibility`.

Writes OUT/efficiency.csv (every render), OUT/efficiency.md (the tables for
docs/history/results-journal.md) and
OUT/efficiency.png."""
import json
import math
import os
import sys

import numpy as np

import common

MAPS = {  # name -> (file, kind)
    "esplanade": ("royal_esplanade_1k.hdr", "tiny sun"),
    "spot": ("spot1Lux.hdr", "tiny sun"),
    "grace": ("grace.hdr", "few small sources"),
    "overpass": ("pedestrian_overpass_1k.hdr", "broad"),
    "venice": ("venice_sunset_1k.hdr", "broad"),
    # Not in the suite (--maps studio): three softboxes on black, generated (studio_map), where
    # the black mask and the compensated strategy's last BSDF share act on area lights.
    "studio": (None, "softboxes on black"),
}
SUITE = ["esplanade", "spot", "grace", "overpass", "venice"]


def studio_map(cache):
    """A 1024 x 512 lat-long map, black but for three rectangular softboxes of radiance 10-30
    (0.34 sr left clear by the black mask, margins included), written as PFM into the cache.
    Returns its path."""
    w, h = 1024, 512
    img = np.zeros((h, w, 3), np.float32)
    for c0, r0, bw, bh, L in [(100, 120, 60, 30, (20, 20, 20)), (400, 90, 40, 50, (30, 28, 25)),
                              (700, 160, 80, 20, (10, 12, 15))]:
        img[r0:r0 + bh, c0:c0 + bw] = L
    path = os.path.join(cache, "studio.pfm")
    with open(path, "wb") as f:  # PFM: rows bottom to top, little-endian floats
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(img[::-1].astype("<f4").tobytes())
    return path
MATERIALS = [  # region name, material
    ("diffuse", {"type": "diffuse", "albedo": 0.8}),
    ("plastic 0.3", {"type": "plastic", "albedo": 0.6, "specular": 0.04, "roughness": 0.3}),
    ("metal 0.2", {"type": "microfacet", "specular": [0.95, 0.8, 0.6], "roughness": 0.2}),
    ("metal 0.05", {"type": "microfacet", "specular": [0.9, 0.9, 0.9], "roughness": 0.05}),
    ("mirror", {"type": "mirror", "specular": 0.9}),
]


def scene_json(map_file, depth, width, height):
    mats = {f"m{i}": m for i, (_, m) in enumerate(MATERIALS)}
    mats["ground"] = {"type": "diffuse", "albedo": 0.5}
    n = len(MATERIALS)
    shapes = [{"type": "quad", "center": [0, 0, 0], "size": 40, "material": "ground"}]
    for i in range(n):
        x = (i - (n - 1) / 2) * 1.1
        shapes.append({"type": "sphere", "center": [x, 0.5, 0], "radius": 0.5, "segments": 48,
                       "smooth": True, "material": f"m{i}"})
    return {
        "camera": {"eye": [0, 1.1, 9.0], "target": [0, 0.45, 0], "fov": 13},
        "film": {"width": width, "height": height},
        "environment": {"map": os.path.join(common.data_dir(), "envmaps", map_file)},
        "materials": mats,
        "shapes": shapes,
        "render": {"max_depth": depth},
    }


def scene_names(paths):
    """A name per scene file: its base name, or, where two files share one (the same layout name
    in two generated sets), its folder's name and base name for every file, so that no two scenes
    share a cached scene file, a reference or a row of the tables."""
    base = [os.path.splitext(os.path.basename(p))[0] for p in paths]
    if len(set(base)) == len(base):
        return base
    full = [f"{os.path.basename(os.path.dirname(os.path.abspath(p)))}-{b}"
            for p, b in zip(paths, base)]
    if len(set(full)) != len(full):
        sys.exit("experiments: scene files share a name and their folders' names: "
                 + " ".join(paths))
    return full


def check_scene_names():
    """--tiny: scenes of one name in two folders get their folders' names, others their own."""
    assert scene_names(["a/x.json", "b/x.json", "b/y.json"]) == ["a-x", "b-x", "b-y"]
    assert scene_names(["a/x.json", "a/y.json"]) == ["x", "y"]


def file_scene(path, cache, size, name=None):
    """A scene file copied into the cache with its relative files made absolute (so it renders
    from there) and, with `size`, its film resized; name: what the cache calls it (scene_names;
    default its base name). Returns (name, path)."""
    path = os.path.abspath(path)
    with open(path) as f:
        s = json.load(f)
    here = os.path.dirname(path)
    for shape in s.get("shapes", []):
        if "file" in shape and os.path.exists(os.path.join(here, shape["file"])):
            shape["file"] = os.path.join(here, shape["file"])
    env = s.get("environment", {})
    if "map" in env and os.path.exists(os.path.join(here, env["map"])):
        env["map"] = os.path.join(here, env["map"])
    if size:
        s.setdefault("film", {})["width"], s["film"]["height"] = size
    s.pop("output", None)
    name = name or os.path.splitext(os.path.basename(path))[0]
    w, h = s.get("film", {}).get("width", 0), s.get("film", {}).get("height", 0)
    out = os.path.join(cache, f"{name}-{w}x{h}.json")
    with open(out, "w") as f:
        json.dump(s, f, indent=1)
    return name, out


def regions(width, height):
    """Boolean pixel masks of the material regions, from the suite's camera and spheres
    (scene_json): each sphere's pixels (the pixel centre's camera ray hits it first; the
    tessellated sphere differs from the analytic one by a pixel at most along its outline), then
    the ground's. The spheres fill the image's middle 60% of columns, so columns split evenly
    (what an earlier version of this tool measured) mixed the ground and two spheres in each band.
    Returns [(name, mask)] in MATERIALS order, then ("ground", mask); the rest is the map."""
    s = scene_json("", 1, width, height)
    cam = s["camera"]
    eye, target = np.array(cam["eye"], float), np.array(cam["target"], float)
    f = (target - eye) / np.linalg.norm(target - eye)  # as set_camera (device_scene.cpp)
    r = np.cross(f, [0.0, 1.0, 0.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    th = math.tan(math.radians(cam["fov"]) / 2)
    sx = 2 * (np.arange(width) + 0.5) / width - 1
    sy = 1 - 2 * (np.arange(height) + 0.5) / height
    d = f + r * th * width / height * sx[None, :, None] + u * th * sy[:, None, None]
    d /= np.linalg.norm(d, axis=2, keepdims=True)
    nearest = np.full((height, width), np.inf)
    owner = np.full((height, width), -1)
    for k, shape in enumerate(s["shapes"]):
        if shape["type"] == "sphere":
            oc = eye - np.array(shape["center"], float)
            b = (d * oc).sum(axis=2)
            disc = b * b - (oc @ oc - shape["radius"] ** 2)
            t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
        else:  # the ground quad, y = 0, half-size size / 2
            with np.errstate(divide="ignore", invalid="ignore"):
                t = -eye[1] / d[..., 1]
            hit = eye + t[..., None] * d
            inside = (np.abs(hit[..., 0]) <= shape["size"] / 2) & (np.abs(hit[..., 2]) <= shape["size"] / 2)
            t = np.where((t > 0) & inside, t, np.inf)
        closer = (t > 0) & (t < nearest)
        nearest = np.where(closer, t, nearest)
        owner = np.where(closer, k, owner)
    out = [(name, owner == k + 1) for k, (name, _) in enumerate(MATERIALS)]
    return out + [("ground", owner == 0)]


def check_regions(work, width=320, height=72):
    """regions() against the renderer: two 16-spp renders of the suite's scene at depth 1, the
    ground black in both, the spheres grey in the first and black in the second. A sphere's
    pixels are then lit in the first and black in the second, the ground's black in both. Each
    region must agree on at least 90% of its pixels (outline pixels mix; the lowest rim, turned
    to the black ground, can render black). Exits non-zero otherwise: every per-material figure
    rests on these masks."""
    imgs = []
    for grey in (0.5, 0.0):
        s = scene_json(MAPS["grace"][0], 1, width, height)
        for name in s["materials"]:
            s["materials"][name] = {"type": "diffuse", "albedo": 0.0 if name == "ground" else grey}
        scene = os.path.join(work, f"regions-{grey:g}.json")
        with open(scene, "w") as f:
            json.dump(s, f)
        out = scene[:-5] + ".pfm"
        common.render(scene, out, ["--spp", "16", "--max-depth", "1"])
        imgs.append(common.read_pfm(out).max(axis=2))
    sphere_like = (imgs[0] > 0) & (imgs[1] == 0)
    for name, mask in regions(width, height):
        agree = float((imgs[0][mask] == 0).mean() if name == "ground" else sphere_like[mask].mean())
        print(f"region {name}: {mask.sum()} pixels, {100 * agree:.1f}% as rendered")
        if not mask.any() or agree < 0.9:
            sys.exit(f"efficiency.py: the {name} region does not match the rendered scene "
                     f"({100 * agree:.1f}% of its pixels)")


def render(scene, out, strategy, budget, seed, extra, unit="s"):
    """One render of `budget` seconds (unit "s") or samples per pixel (unit "spp")."""
    args, exponent = strategy_args(strategy)
    if exponent is not None:  # a scene variant with a tone-mapped distribution
        with open(scene) as f:
            s = json.load(f)
        s["environment"]["distribution_exponent"] = exponent
        scene = out + ".json"
        with open(scene, "w") as f:
            json.dump(s, f)
    limit = ["--time-limit", str(budget)] if unit == "s" else ["--spp", str(int(budget))]
    args = limit + ["--seed", str(seed)] + args + extra
    stats = common.render(scene, out, args)
    return common.read_pfm(out), stats


def strategy_args(strategy):
    """A strategy of the table: a --strategy name, optionally with +options: ndf or vndf (GGX
    sampling), balance or power (the MIS heuristic), xE (the map's distribution built on
    luminance^E, E < 1: tone-mapped), lN / bN (N light / BSDF samples per vertex), verdict or
    noverdict (the visibility strategy's verdict on or off)."""
    parts = strategy.split("+")
    a, exponent = ["--strategy", parts[0]], None
    for opt in parts[1:]:
        if opt in ("ndf", "vndf"):
            a += ["--bsdf-sampling", opt]
        elif opt in ("balance", "power"):
            a += ["--mis-heuristic", opt]
        elif opt.startswith("x"):
            exponent = float(opt[1:])
        elif opt in ("verdict", "noverdict"):
            a += ["--guide-verdict", "on" if opt == "verdict" else "off"]
        elif opt[:1] in ("l", "b") and opt[1:].isdigit():
            a += ["--light-samples" if opt[0] == "l" else "--bsdf-samples", opt[1:]]
        else:
            sys.exit(f"efficiency: unknown strategy option '{opt}' in '{strategy}'")
    return a, exponent


def reference(scene, name, ref_seconds, cache, extra):
    """Mean of two independent MIS renders, and the per-pixel variance of that mean."""
    halves = []
    for seed in (7919, 7920):
        out = os.path.join(cache, f"{name}-ref{ref_seconds:g}-{seed}.pfm")
        if not os.path.exists(out):
            common.render(scene, out, ["--time-limit", str(ref_seconds / 2), "--seed", str(seed),
                                       "--strategy", "mis"] + extra)
        halves.append(common.read_pfm(out))
    ref = 0.5 * (halves[0] + halves[1])
    var = 0.25 * (halves[0] - halves[1]) ** 2  # E[(h1-h2)^2/4] = var(mean of two)
    return ref, var


def main():
    p = common.parser(__doc__.splitlines()[0])
    p.add_argument("--budgets", type=float, nargs="+", default=[0.5, 2.0])
    p.add_argument("--spp", type=int, nargs="+", default=None,
                   help="equal samples instead of equal time: renders of N spp, each timed")
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--maps", nargs="+", default=SUITE, choices=list(MAPS))
    p.add_argument("--depths", type=int, nargs="+", default=[1, 5])
    p.add_argument("--strategies", nargs="+", default=["light", "bsdf", "mis"])
    p.add_argument("--ref-seconds", type=float, default=None,
                   help="reference render time (default 40 x the largest budget)")
    p.add_argument("--size", type=int, nargs=2, default=None, help="film (default 320 x 72; "
                   "with --scenes, each scene's own)")
    p.add_argument("--scenes", nargs="+", default=None, help="scene files instead of the suite")
    p.add_argument("--tables-from", default=None, metavar="CSV",
                   help="write the tables of an earlier run's efficiency.csv (no rendering)")
    a = p.parse_args()
    if a.tables_from:
        return tables_from(a)
    if a.tiny:
        a.budgets, a.seeds, a.maps, a.depths = [0.05], 2, ["grace"], [1]
        a.size, a.ref_seconds = [60, 16], 0.4
    unit = "s"
    if a.spp:
        if any(n < 1 for n in a.spp):
            sys.exit("efficiency: --spp takes positive sample counts")
        a.budgets, unit = [float(n) for n in a.spp], "spp"
        if a.ref_seconds is None:
            sys.exit("efficiency: --spp needs --ref-seconds (the reference's duration)")
    a.unit = unit
    ref_seconds = a.ref_seconds or 40 * max(a.budgets)
    out_dir = common.out_dir(a, "efficiency")
    cache = os.path.join(out_dir, "ref")
    os.makedirs(cache, exist_ok=True)
    work = common.tmpdir("efficiency")
    if a.tiny:
        check_regions(work)
        check_intervals()
        check_scene_names()
    extra = []  # common.render: the native back end
    if a.size is None and not a.scenes:
        a.size = [320, 72]
    width, height = a.size or (0, 0)
    strategies = a.strategies if "mis" in a.strategies else ["mis"] + a.strategies
    region_names = [b for b, _ in MATERIALS] + ["ground"]

    rows = []  # one per render
    if a.scenes:
        region_names = []
        cases = [file_scene(f, cache, a.size, n) + (None, None)
                 for f, n in zip(a.scenes, scene_names(a.scenes))]
    else:
        cases = []
        for map_key in a.maps:
            for depth in a.depths:
                name = f"{map_key}-d{depth}"
                scene = os.path.join(cache, f"{name}-{width}x{height}.json")
                with open(scene, "w") as f:
                    map_file = MAPS[map_key][0] or studio_map(cache)
                    json.dump(scene_json(map_file, depth, width, height), f, indent=1)
                cases.append((name, scene, map_key, depth))
    for name, scene, map_key, depth in cases:
            tag = os.path.splitext(os.path.basename(scene))[0] if a.scenes else f"{name}-{width}x{height}"
            ref, ref_var = reference(scene, tag, ref_seconds, cache, extra)
            ref_max = float(ref.mean(axis=2).max())
            width = ref.shape[1]
            masks = [np.ones(ref.shape[:2], bool)]
            masks += [m for _, m in regions(width, ref.shape[0])] if region_names else []
            rel_denom = ref ** 2 + (0.01 * float(ref.mean())) ** 2
            ref_noise = [float((ref_var / rel_denom)[m].mean()) for m in masks]
            # The strategies alternate seed by seed, so that a machine whose load drifts during
            # the run times them alike.
            for budget in a.budgets:
                for seed in range(1, a.seeds + 1):
                    for strategy in strategies:
                        out = os.path.join(work, f"{name}-{strategy}-{budget:g}-{seed}.pfm")
                        img, stats = render(scene, out, strategy, budget, seed, extra, unit)
                        finite = bool(np.isfinite(img).all())
                        # Relative squared error per pixel channel: (x - ref)^2 / (ref^2 + eps),
                        # eps = (1% of the image mean)^2, so that dark and bright pixels weigh
                        # alike (the measure of Karlik et al. and of most sampling papers).
                        err = (np.nan_to_num(img, nan=0.0, posinf=0.0) - ref) ** 2 / rel_denom
                        mse = [max(float(err[m].mean()) - n, 0.0) for m, n in zip(masks, ref_noise)]
                        rows.append({
                            "scene": name, "map": map_key, "depth": depth, "strategy": strategy,
                            "budget": budget, "unit": unit, "seed": seed,
                            "seconds": stats["render_seconds"],
                            "spp": stats["spp"], "nonfinite": stats["nonfinite_samples"] +
                            (0 if finite else 1),
                            "max_ratio": float(img.mean(axis=2).max()) / max(ref_max, 1e-30),
                            "mse": mse[0], **{f"mse {b}": m for b, m in zip(region_names, mse[1:])},
                            "ref_noise": ref_noise[0],
                        })
                        print(f"{name} {strategy:>16} {budget:g}{unit} seed {seed}: {stats['spp']} spp "
                              f"{stats['render_seconds']:.2f}s mse {mse[0]:.4g}", flush=True)
    common.write_csv(os.path.join(out_dir, "efficiency.csv"), list(rows[0]), [list(r.values()) for r in rows])
    write_tables(rows, strategies, region_names, a, ref_seconds, out_dir)


def tables_from(a):
    """The tables of an earlier run, from its CSV: its strategies, budgets, seeds and film as the
    rows give them; the reference's duration is not in the CSV (--ref-seconds, else `?`)."""
    import csv

    with open(a.tables_from, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"efficiency: {a.tables_from}: no rows")
    for r in rows:
        for k in r:
            if k in ("budget", "seconds", "max_ratio", "ref_noise") or k.startswith("mse"):
                r[k] = float(r[k])
        r["nonfinite"], r["seed"] = int(r["nonfinite"]), int(r["seed"])
    strategies = list(dict.fromkeys(r["strategy"] for r in rows))
    region_names = [k[4:] for k in rows[0] if k.startswith("mse ")]
    a.budgets = sorted(set(r["budget"] for r in rows))
    a.unit = rows[0].get("unit", "s")  # runs before --spp existed are equal-time
    a.seeds = len(set(r["seed"] for r in rows))
    a.strategies = strategies
    a.size = a.size or ([320, 72] if region_names else None)
    out_dir = a.out or os.path.dirname(os.path.abspath(a.tables_from))
    os.makedirs(out_dir, exist_ok=True)
    write_tables(rows, strategies, region_names, a, a.ref_seconds or "?", out_dir)


def costs_by_group(rows, column):
    """{(scene, strategy, budget): (errors, seconds)} over the group's seeds, as arrays in the
    order of the seeds (so that entry k of two strategies is the same seed's)."""
    groups = {}
    for r in sorted(rows, key=lambda r: int(r["seed"])):
        groups.setdefault((r["scene"], r["strategy"], r["budget"]), []).append(
            (r[column], r["seconds"]))
    return {k: (np.array([e for e, _ in v]), np.array([t for _, t in v])) for k, v in groups.items()}


def gain_table(cost, scenes, strategies, budgets):
    """{(scene, strategy): gain over mis} from {(scene, strategy, budget): MSE x time}: the
    geometric mean over budgets of the cost ratio."""
    out = {}
    for sc in scenes:
        for st in strategies:
            logs = []
            for b in budgets:
                c, m = cost[(sc, st, b)], cost[(sc, "mis", b)]
                logs.append(math.log(m / c) if c > 0 and m > 0 else float("nan"))
            out[(sc, st)] = math.exp(np.mean(logs))
    return out


def gain_intervals(rows, strategies, column, level=0.90, draws=2000):
    """Bootstrap interval over the seeds of every gain, of each strategy's geometric mean over
    the scenes, and of every gain over the best strategy measured on its scene in the same draw
    (how far a strategy is from the best envtrace has there): {(scene, strategy): (lo, hi)},
    {strategy: (lo, hi)}, {(scene, strategy): (lo, hi)}. Each draw resamples every group's seeds with replacement (the
    error and the time of a render stay together); the generator's seed is fixed, so a table is
    the same every time it is written."""
    groups = costs_by_group(rows, column)
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    budgets = sorted(set(r["budget"] for r in rows))
    rng = np.random.default_rng(20261128)
    per_scene = {(sc, st): [] for sc in scenes for st in strategies}
    overall = {st: [] for st in strategies}
    vs_best = {(sc, st): [] for sc in scenes for st in strategies}
    seeds = {}  # (scene, budget) -> number of seeds, the same for each strategy
    for (sc, st, b), (err, _) in groups.items():
        if seeds.setdefault((sc, b), len(err)) != len(err):
            sys.exit(f"efficiency: {sc} at {b:g} has {len(err)} seeds of {st}, "
                     f"{seeds[(sc, b)]} of another strategy")
    for _ in range(draws):
        picks = {k: rng.integers(0, n, n) for k, n in seeds.items()}
        cost = {}
        for (sc, st, b), (err, sec) in groups.items():
            pick = picks[(sc, b)]
            cost[(sc, st, b)] = float(err[pick].mean()) * float(sec[pick].mean())
        g = gain_table(cost, scenes, strategies, budgets)
        for k, v in g.items():
            per_scene[k].append(v)
        for st in strategies:
            overall[st].append(geomean([g[(sc, st)] for sc in scenes]))
            for sc in scenes:
                vs_best[(sc, st)].append(g[(sc, st)] / max(g[(sc, b)] for b in strategies))
    q = [50 * (1 - level), 50 * (1 + level)]

    def band(xs):
        xs = [x for x in xs if math.isfinite(x)]
        return tuple(np.percentile(xs, q)) if xs else (float("nan"), float("nan"))

    return ({k: band(v) for k, v in per_scene.items()}, {k: band(v) for k, v in overall.items()},
            {k: band(v) for k, v in vs_best.items()})


def check_intervals():
    """gain_intervals on made-up runs whose answer is known (run by --tiny): seeds that agree give
    a point; one outlier seed of three widens the interval to the gains without it (2.0: a draw
    misses it with probability 8/27) and with it twice (0.29), around the gain with it (0.5);
    seeds whose errors differ but are always half of mis's in the same seed give a point (the
    seeds are resampled together)."""
    def rows(errors):
        return rows_of([1.0] * 3, errors)

    def rows_of(mis, errors):
        return [{"scene": "s", "strategy": st, "budget": 1.0, "seed": k + 1, "seconds": 1.0,
                 "mse": e} for st, es in (("mis", mis), ("x", errors)) for k, e in enumerate(es)]

    band, _, _ = gain_intervals(rows([0.5] * 3), ["mis", "x"], "mse")
    lo, hi = band[("s", "x")]
    if not (abs(lo - 2.0) < 1e-9 and abs(hi - 2.0) < 1e-9):
        sys.exit(f"efficiency: interval of agreeing seeds is {lo}-{hi}, not 2-2")
    _, g = gains(rows([0.5, 0.5, 5.0]), ["mis", "x"], "mse")
    band, _, _ = gain_intervals(rows([0.5, 0.5, 5.0]), ["mis", "x"], "mse")
    lo, hi = band[("s", "x")]
    if not (abs(g[("s", "x")] - 0.5) < 1e-9 and abs(lo - 1 / 3.5) < 1e-6 and abs(hi - 2.0) < 1e-9):
        sys.exit(f"efficiency: outlier seed: gain {g[('s', 'x')]} interval {lo}-{hi}, "
                 "expected 0.5 in 0.286-2")
    band, _, _ = gain_intervals(rows_of([1.0, 4.0, 16.0], [0.5, 2.0, 8.0]), ["mis", "x"], "mse")
    lo, hi = band[("s", "x")]
    if not (abs(lo - 2.0) < 1e-9 and abs(hi - 2.0) < 1e-9):
        sys.exit(f"efficiency: paired seeds give the interval {lo}-{hi}, not 2-2")
    print("efficiency: bootstrap intervals check out")


def gains(rows, strategies, column):
    """{(scene, strategy): gain over mis} of the geometric mean over budgets of
    (MSE x time of mis) / (MSE x time of the strategy), MSE and time averaged over seeds."""
    cost = {k: float(e.mean()) * float(t.mean()) for k, (e, t) in costs_by_group(rows, column).items()}
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    budgets = sorted(set(r["budget"] for r in rows))
    return scenes, gain_table(cost, scenes, strategies, budgets)


def geomean(xs):
    xs = [x for x in xs if x > 0 and math.isfinite(x)]
    return math.exp(np.mean([math.log(x) for x in xs])) if xs else float("nan")


def write_tables(rows, strategies, region_names, a, ref_seconds, out_dir):
    scenes, g = gains(rows, strategies, "mse")
    film = f"{a.size[0]}x{a.size[1]}" if a.size else "each scene's film"
    ref_txt = ref_seconds if isinstance(ref_seconds, str) else f"{ref_seconds:g}"
    scenes_arg = f" --scenes {' '.join(a.scenes)}" if a.scenes else ""
    size_arg = f" --size {a.size[0]} {a.size[1]}" if a.scenes and a.size else ""
    unit = getattr(a, "unit", "s")
    what = ("budgets " + ", ".join(f"{b:g} s" for b in a.budgets) if unit == "s" else
            "equal samples, " + ", ".join(f"{b:g} spp" for b in a.budgets) + " (each render timed)")
    lines = [f"Efficiency (1 / (relative MSE x time)) relative to the paper's MIS; {what}, {a.seeds} seeds, "
             f"{film}, native back end, reference {ref_txt} s of MIS. "
             f"Command: `tools/experiments/efficiency.py{scenes_arg}{size_arg} "
             f"{'--budgets' if unit == 's' else '--spp'} "
             f"{' '.join(f'{b:g}' for b in a.budgets)} "
             f"--seeds {a.seeds} --strategies {' '.join(strategies)}"
             f"{'' if unit == 's' else f' --ref-seconds {ref_txt}'}`.", ""]
    band, band_all, band_best = gain_intervals(rows, strategies, "mse")

    def cell(x, lo_hi):
        return f"{x:.2f}" if lo_hi[0] == lo_hi[1] else f"{x:.2f} ({lo_hi[0]:.2f}-{lo_hi[1]:.2f})"

    # The best strategy measured on each scene: what a default that chose per scene could reach.
    best = {sc: max(strategies, key=lambda s: g[(sc, s)]) for sc in scenes}
    lines.append("| scene | " + " | ".join(strategies) + " | best measured |")
    lines.append("|---" * (len(strategies) + 2) + "|")
    for sc in scenes:
        lines.append(f"| {sc} | " + " | ".join(cell(g[(sc, s)], band[(sc, s)]) for s in strategies)
                     + f" | {g[(sc, best[sc])]:.2f} ({best[sc]}) |")
    lines.append("| **geometric mean** | " + " | ".join(
        f"**{cell(geomean([g[(sc, s)] for sc in scenes]), band_all[s])}**" for s in strategies)
        + f" | **{geomean([g[(sc, best[sc])] for sc in scenes]):.2f}** |")
    lines += ["", "In brackets: 90% bootstrap interval over the seeds (see the script's header)."]
    if len(strategies) > 1:
        lines += ["", "Over the best strategy measured on each scene (1.00: the best there; "
                  "interval as above, the best taken in each draw):", ""]
        lines.append("| scene | " + " | ".join(strategies) + " |")
        lines.append("|---" * (len(strategies) + 1) + "|")
        for sc in scenes:
            lines.append(f"| {sc} | " + " | ".join(
                cell(g[(sc, s)] / g[(sc, best[sc])], band_best[(sc, s)]) for s in strategies)
                + " |")
        lines.append("| **lowest** | " + " | ".join(
            f"**{min(g[(sc, s)] / g[(sc, best[sc])] for sc in scenes):.2f}**" for s in strategies)
            + " |")
    lines += ["", "Per material region (geometric mean over the scenes; each sphere's pixels, and the ground's):", ""]
    lines.append("| material | " + " | ".join(strategies) + " |")
    lines.append("|---" * (len(strategies) + 1) + "|")
    for b in region_names:
        _, gb = gains(rows, strategies, f"mse {b}")
        lines.append(f"| {b} | " + " | ".join(f"{geomean([gb[(sc, s)] for sc in scenes]):.2f}"
                                             for s in strategies) + " |")
    lines += ["", "Brightest pixel / the reference's brightest (max over seeds and budgets; "
              "fireflies show as > 1) and non-finite samples:", ""]
    lines.append("| scene | " + " | ".join(strategies) + " |")
    lines.append("|---" * (len(strategies) + 1) + "|")
    for sc in scenes:
        cells = []
        for s in strategies:
            rs = [r for r in rows if r["scene"] == sc and r["strategy"] == s]
            nf = sum(r["nonfinite"] for r in rs)
            cells.append(f"{max(r['max_ratio'] for r in rs):.2f}" + (f" ({nf} NaN)" if nf else ""))
        lines.append(f"| {sc} | " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out_dir, "efficiency.md"), "w") as f:
        f.write(text)
    print(text)

    plt = common.pyplot()
    fig, ax = plt.subplots(figsize=(max(6, len(scenes) * 0.9), 3.5))
    w = 0.8 / len(strategies)
    for k, s in enumerate(strategies):
        ax.bar([i + k * w for i in range(len(scenes))], [g[(sc, s)] for sc in scenes], w, label=s)
    ax.set_yscale("log")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks([i + 0.4 - w / 2 for i in range(len(scenes))])
    ax.set_xticklabels(scenes, rotation=30, ha="right")
    ax.set_ylabel("efficiency / paper's MIS")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "efficiency.png"), dpi=120)
    print(f"wrote {os.path.join(out_dir, 'efficiency.png')}")


if __name__ == "__main__":
    main()
