#!/usr/bin/python3
"""Plots tools/bench/scaling/*.csv (the figures and the commands that made them are in
docs/history/bench-journal.md, "How cost grows") into tools/bench/scaling/scaling.png."""
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scaling")


def rows(name):
    with open(os.path.join(HERE, name)) as f:
        return list(csv.DictReader(f))


def col(rs, key, cast=float):
    return [cast(r[key]) for r in rs]


def main():
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    t = rows("triangles.csv")
    n = col(t, "triangles")
    a = ax[0][0]
    for key, label, style in [("native_mrays", "envtrace native", "o-"), ("opencl_mrays", "envtrace OpenCL", "s-"),
                              ("embree_mrays", "Embree 3", "^--")]:
        a.semilogx(n, col(t, key), style, label=label)
    a.set_xlabel("triangles (cube sphere + ground quad)")
    a.set_ylabel("Mrays/s (camera + shadow, 2 threads)")
    a.set_title("Traversal throughput vs triangle count")
    a.legend()
    a = ax[0][1]
    a.loglog(n, col(t, "native_build_ms"), "o-", label="envtrace BVH build")
    a.loglog(n, col(t, "embree_build_ms"), "^--", label="Embree scene build")
    a.loglog(n, [col(t, "native_build_ms")[1] * x / n[1] for x in n], ":", color="gray", label="linear")
    a.set_xlabel("triangles")
    a.set_ylabel("build time (ms)")
    a.set_title("BVH build time vs triangle count")
    a.legend()
    m = [r for r in rows("map_size.csv") if r["map"].startswith("sky")]
    texels = [int(r["width"]) * int(r["height"]) for r in m]
    a = ax[1][0]
    a.loglog(texels, col(m, "build_ms_cpu"), "o-", label="distribution build, 1 core (ms)")
    a.loglog(texels, col(m, "env_sample_plain_ns"), "s--", label="etk_env_sample, plain search (ns)")
    a.loglog(texels, col(m, "env_sample_guided_ns"), "s-", label="etk_env_sample, guide tables (ns)")
    a.set_xlabel("map texels (sky, 256x128 ... 16384x8192)")
    a.set_title("Environment map size")
    a.legend(fontsize=8)
    rp = rows("resolution_paths.csv")
    res = [r for r in rp if r["varied"] == "resolution"]
    paths = [r for r in rp if r["varied"] == "paths"]
    a = ax[1][1]
    px = col(res, "paths_in_flight")
    a.semilogx(px, col(res, "native_mrays"), "o-", label="native, film N pixels")
    a.semilogx(px, col(res, "opencl_mrays"), "s-", label="OpenCL, film N pixels")
    a.semilogx(col(paths, "paths_in_flight"), col(paths, "opencl_mrays"), "s--",
               label="OpenCL, 512x512, N paths in flight")
    a.set_xlabel("N")
    a.set_ylabel("Mrays/s (whole render, depth 1)")
    a.set_title("Resolution and paths in flight (bunny_esplanade)")
    a.legend(fontsize=8)
    for row in ax:
        for a in row:
            a.grid(alpha=0.3, which="both")
    fig.suptitle("envtrace: how cost grows (2 cores; triangle rows idle, the others loaded: see README)")
    fig.tight_layout()
    out = os.path.join(HERE, "scaling.png")
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
