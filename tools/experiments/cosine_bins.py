#!/usr/bin/python3
"""How much a light sample drawn from the map times the cosine to the vertex's normal bin could
gain, in a model with no renderer in it (the cosine strategy, kernels/normal_bins.h).

    tools/experiments/cosine_bins.py [--maps ...] [--sides 8 16 32] [--normals 80] [--out DIR]

For each map (efficiency.py's suite), at N normals spread evenly over the sphere, a diffuse vertex
with one light and one cosine-distributed BSDF sample, weighted by the balance heuristic: the
variance of the estimate of the reflected light, summed over the normals, for light samples from
the map's own distribution (the paper's) and from the bin's table (the normal's octahedral bin of
SIDE x SIDE; 16 x 32 regions of the map, each weighted by its light times max(0, cos) to the bin's
centre -- the renderer's tables bound it over the bin's normals instead -- the map inside a
region; a defensive share 0.1 of the map). Exact sums over a 256 x 128 copy of the map, independent samples: the variance of one sample, not what the Sobol' points
make of it. Twice: open (the whole sphere lights the vertex) and with the lower hemisphere hidden
(the suite's ground under the spheres). Writes OUT/cosine_bins.md."""
import argparse
import os
import subprocess

import common
from efficiency import MAPS, SUITE

ALPHA = 0.1
W, H = 256, 128
RH, RW = 16, 32


def load(path, scratch):
    import numpy as np
    pfm = os.path.join(scratch, os.path.basename(path) + ".pfm")
    subprocess.run([common.envtrace(), "convert", path, pfm], check=True, capture_output=True)
    img = common.read_pfm(pfm)
    h0, w0 = img.shape[:2]
    fy, fx = h0 // H, w0 // W
    img = img[:H * fy, :W * fx].reshape(H, fy, W, fx, 3).mean(axis=(1, 3))
    lum = img @ np.array([0.2126, 0.7152, 0.0722])
    # envtrace's lat-long (kernels/latlong.h): y up, row 0 straight up.
    th = np.pi * (np.arange(H) + 0.5) / H
    ph = 2 * np.pi * (np.arange(W) + 0.5) / W - np.pi
    TH, PH = np.meshgrid(th, ph, indexing="ij")
    d = np.stack([np.sin(TH) * np.sin(PH), np.cos(TH), -np.sin(TH) * np.cos(PH)], -1)
    dA = (np.pi / H) * (2 * np.pi / W) * np.sin(TH)
    return lum.ravel(), d.reshape(-1, 3), dA.ravel()


def fibonacci(n):
    import numpy as np
    i = np.arange(n) + 0.5
    y = 1 - 2 * i / n
    r = np.sqrt(1 - y * y)
    a = np.pi * (1 + 5 ** 0.5) * i
    return np.stack([r * np.cos(a), y, r * np.sin(a)], -1)


def bin_centre(n, side):
    """The centre of n's bin: etk_normal_bin and etk_normal_bin_centre (kernels/normal_bins.h)."""
    import numpy as np
    s = np.abs(n).sum()
    x, z = n[0] / s, n[2] / s
    if n[1] < 0:
        x, z = (1 - abs(z)) * (1 if x >= 0 else -1), (1 - abs(x)) * (1 if z >= 0 else -1)
    i = min(int((0.5 * x + 0.5) * side), side - 1)
    j = min(int((0.5 * z + 0.5) * side), side - 1)
    x, z = 2 * (i + 0.5) / side - 1, 2 * (j + 0.5) / side - 1
    y = 1 - abs(x) - abs(z)
    if y < 0:
        x, z = (1 - abs(z)) * (1 if x >= 0 else -1), (1 - abs(x)) * (1 if z >= 0 else -1)
    c = np.array([x, y, z])
    return c / np.linalg.norm(c)


def mis_variance(g, pdfs, dA):
    """Variance of one sample of each technique, balance heuristic, integrand g."""
    import numpy as np
    total = sum(pdfs)
    v = 0.0
    for p in pdfs:
        w = np.divide(p, total, out=np.zeros_like(p), where=total > 0)
        m = p > 0
        v += (g[m] ** 2 * w[m] ** 2 / p[m] * dA[m]).sum() - ((g * w * dA).sum()) ** 2
    return v


def binned_pdf(lum, weight, dA):
    """Regions chosen in proportion to sum(weight dA), the map inside each."""
    import numpy as np
    t = (weight * dA).reshape(RH, H // RH, RW, W // RW).sum(axis=(1, 3))
    m = (lum * dA).reshape(RH, H // RH, RW, W // RW).sum(axis=(1, 3))
    if not t.sum() > 0:  # a bin facing away from all the light: the map's own (as the host does)
        t = m
    ratio = np.divide(t / t.sum(), m, out=np.zeros_like(t), where=m > 0)
    return (lum.reshape(RH, H // RH, RW, W // RW) * ratio[:, None, :, None]).ravel()


def main():
    import numpy as np
    p = common.parser(__doc__)
    p.add_argument("--maps", nargs="+", default=[m for m in SUITE if MAPS[m][0]])
    p.add_argument("--sides", nargs="+", type=int, default=[8, 16, 32])
    p.add_argument("--normals", type=int, default=80)
    a = p.parse_args()
    out_dir = common.out_dir(a, "cosine_bins")
    scratch = common.tmpdir("cosine_bins")
    rows = []
    for name in a.maps:
        lum, d, dA = load(os.path.join(common.data_dir(), "envmaps", MAPS[name][0]), scratch)
        p_map = lum / (lum * dA).sum()
        for hidden in (False, True):
            vis = (d[:, 1] > 0) if hidden else np.ones(len(lum), bool)
            sums = {"map": 0.0, **{s: 0.0 for s in a.sides}}
            for n in fibonacci(a.normals):
                cos = d @ n
                g = lum * np.maximum(cos, 0) / np.pi * vis
                if (g * dA).sum() <= 0:
                    continue
                p_bsdf = np.maximum(cos, 0) / np.pi
                sums["map"] += mis_variance(g, [p_map, p_bsdf], dA)
                for side in a.sides:
                    c = bin_centre(n, side)
                    p_bin = (1 - ALPHA) * binned_pdf(lum, lum * np.maximum(d @ c, 0), dA) + ALPHA * p_map
                    sums[side] += mis_variance(g, [p_bin, p_bsdf], dA)
            rows.append([name, "lower half hidden" if hidden else "open"] +
                        [sums[s] / sums["map"] for s in a.sides])
            print(*rows[-1], flush=True)
    with open(os.path.join(out_dir, "cosine_bins.md"), "w") as f:
        f.write("Variance of a diffuse vertex's MIS estimate (one light, one cosine sample, balance), "
                "light samples from the normal bin's table over those from the map, summed over "
                f"{a.normals} normals (tools/experiments/cosine_bins.py)\n\n")
        f.write("| map | lighting | " + " | ".join(f"{s} x {s} bins" for s in a.sides) + " |\n")
        f.write("|---|---|" + "---|" * len(a.sides) + "\n")
        for r in rows:
            f.write(f"| {r[0]} | {r[1]} | " + " | ".join(f"{x:.2f}" for x in r[2:]) + " |\n")


if __name__ == "__main__":
    main()
