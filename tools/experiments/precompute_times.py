#!/usr/bin/python3
"""Precomputation + selection time of a set of N directional lights, ours vs SIS, on the maps of
the experiments (median of --runs runs of `envtrace lights`, in one process each, so the map's
distribution build is included for ours and the whole level/placement/Voronoi pass for SIS;
reading the file is not). Paper: < 0.025 s for ours, 76 s for SIS (32 lights); 50-100 s of SIS
precomputation in general.

Writes precompute_times.csv and precompute_times.png to --out (default docs/figures/precompute)."""
import json
import os
import statistics

import common as c


def main():
    a = c.parser(__doc__.splitlines()[0])
    a.add_argument("--runs", type=int, default=5)
    args = a.parse_args()
    out = c.out_dir(args, "precompute")
    tmp = c.tmpdir("precompute")
    maps = ["grace.hdr", "royal_esplanade_1k.hdr", "pedestrian_overpass_1k.hdr"]
    counts, runs = [32, 128], args.runs
    if args.tiny:
        maps, counts, runs = ["grace.hdr"], [8], 1
    rows = []
    for m in maps:
        for n in counts:
            for method in ["ours", "sis"]:
                pre, sel = [], []
                for _ in range(runs):
                    lights = os.path.join(tmp, "l.json")
                    c.run([c.envtrace(), "lights", os.path.join(c.data_dir(), "envmaps", m), "-n",
                           str(n), "--method", method, "-o", lights])
                    with open(lights) as f:
                        j = json.load(f)
                    pre.append(j["precompute_seconds"])
                    sel.append(j["selection_seconds"])
                p, s = statistics.median(pre), statistics.median(sel)
                rows.append([m, n, method, p, s, p + s, runs])
                print(f"{m} {n} {method}: {p + s:.4f} s")
    c.write_csv(os.path.join(out, "precompute_times.csv"),
                ["map", "lights", "method", "precompute_seconds", "selection_seconds",
                 "total_seconds", "runs"], rows)
    plt = c.pyplot()
    fig, ax = plt.subplots(figsize=(8, 3.8))
    labels = [f"{r[0].split('.')[0]}\nN={r[1]}" for r in rows if r[2] == "ours"]
    x = range(len(labels))
    for k, (method, off) in enumerate([("ours", -0.2), ("sis", 0.2)]):
        ax.bar([i + off for i in x], [r[5] for r in rows if r[2] == method], width=0.4,
               label=method)
    ax.axhline(0.025, color="gray", ls=":", label="paper: ours < 0.025 s")
    ax.set_yscale("log")
    ax.set_xticks(list(x))
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel("precompute + selection (s)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "precompute_times.png"), dpi=110)
    print(f"wrote {os.path.join(out, 'precompute_times.png')}")


if __name__ == "__main__":
    main()
