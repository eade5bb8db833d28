#!/usr/bin/python3
"""How much of the paper's MIS variance a light-sampling estimator could remove at all.

    tools/experiments/split_ceiling.py [--spp 128] [--split 32] [--maps ...] [--depths 1 5] [--out DIR]

Renders each scene of the efficiency suite (efficiency.py's maps, spheres and ground) with `mis`
and with `mis` split into N light and N BSDF samples per vertex (--light-samples N
--bsdf-samples N), two seeds each at equal spp, and measures the per-pixel relative variance
mean((a - b)^2 / 2 / (m^2 + (0.01 mean m)^2)), m the two seeds' mean. With N large the direct
light at every vertex is almost exact, so what the split render keeps is the variance no choice
of light and BSDF samples at a vertex reaches: pixel integration, indirect light, roulette. Its
share of MIS's variance bounds the gain of any such estimator at equal spp and no extra cost;
the table also gives each one's time per sample. Writes OUT/split_ceiling.md and .csv."""
import json
import math
import os

import common
import efficiency


def main():
    p = common.parser(__doc__.splitlines()[0])
    p.add_argument("--spp", type=int, default=128)
    p.add_argument("--split", type=int, default=32, help="light and BSDF samples per vertex")
    p.add_argument("--maps", nargs="+", default=efficiency.SUITE,
                   choices=list(efficiency.MAPS))
    p.add_argument("--depths", type=int, nargs="+", default=[1, 5])
    a = p.parse_args()
    width, height = 320, 72
    if a.tiny:
        a.spp, a.split, a.maps, a.depths, width, height = 4, 4, ["grace"], [1], 40, 10
    out_dir = common.out_dir(a, "split_ceiling")
    work = common.tmpdir("split_ceiling")
    variants = {"mis": [], "split": ["--light-samples", str(a.split), "--bsdf-samples",
                                     str(a.split)]}
    rows, table = [], []
    for m in a.maps:
        for depth in a.depths:
            scene = os.path.join(work, f"{m}-d{depth}.json")
            with open(scene, "w") as f:
                map_file = efficiency.MAPS[m][0] or efficiency.studio_map(work)
                json.dump(efficiency.scene_json(map_file, depth, width, height), f)
            res = {}
            for name, extra in variants.items():
                imgs, spp_s = [], None
                for seed in (1, 2):
                    out = os.path.join(work, f"{m}-d{depth}-{name}-{seed}.pfm")
                    stats = common.render(scene, out, ["--spp", str(a.spp), "--seed", str(seed),
                                                       "--strategy", "mis"] + extra)
                    imgs.append(common.read_pfm(out))
                    spp_s = stats["seconds_per_spp"]
                res[name] = (common.relative_variance(*imgs), spp_s)
            left = res["split"][0] / res["mis"][0] if res["mis"][0] > 0 else float("nan")
            name = f"{m}-d{depth}"
            print(f"{name:14s} mis {res['mis'][0]:.3g}  split {res['split'][0]:.3g}  "
                  f"left {left:.2f}", flush=True)
            rows.append([name, res["mis"][0], res["split"][0], left, res["mis"][1],
                         res["split"][1]])
            table.append(f"| {name} | {res['mis'][0]:.3g} | {res['split'][0]:.3g} | {left:.2f} | "
                         f"{1 / left:.1f}x | {res['mis'][1]:.4f} / {res['split'][1]:.4f} |")
    common.write_csv(os.path.join(out_dir, "split_ceiling.csv"),
                     ["scene", "mis", "split", "left", "mis_s_per_spp", "split_s_per_spp"], rows)
    lefts = [r[3] for r in rows if r[3] > 0]
    gmean = math.exp(sum(-math.log(x) for x in lefts) / len(lefts)) if lefts else float("nan")
    md = [f"Per-pixel relative variance, two seeds, {a.spp} spp, {width}x{height}; split: "
          f"{a.split} light + {a.split} BSDF samples per vertex. Command: "
          f"`tools/experiments/split_ceiling.py --spp {a.spp} --split {a.split}`.", "",
          "| scene | mis | split | variance left | ceiling (equal spp, free) | s/spp mis / split |",
          "|---|---|---|---|---|---|"] + table + ["", f"Geometric mean of the ceilings: "
                                                   f"**{gmean:.2f}x**."]
    with open(os.path.join(out_dir, "split_ceiling.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
