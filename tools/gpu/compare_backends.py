#!/usr/bin/env python3
"""Compares envtrace renders of the same scene, seed and sample count from different back ends
(tools/gpu/check_opencl_device.sh): PFM images, numpy only.

  compare_backends.py DEPTH REFERENCE.pfm OTHER.pfm [NOISE_A.pfm NOISE_B.pfm]

Prints one line of key=value pairs: how many values differ at all, then by depth. Depth 1 (direct light; the same samples and rays, so the
images differ by float rounding only): the share of values whose relative difference exceeds
1e-4 and 1e-3, and the largest. Depth > 1 (paths may part ways where rounding flips a
decision): the relative difference of the image means and the relative MSE between the images,
set against the relative MSE between two renders of REFERENCE's back end with different seeds
(NOISE_A, NOISE_B), the size of the Monte Carlo noise itself, and a z-score per 16x16 block:
the blocks' mean differences in units of their noise (from the two seeds), which for back ends
that agree are about N(0, 1).
"""
import sys

import numpy as np


def read_pfm(path):
    with open(path, "rb") as f:
        magic = f.readline().strip()
        w, h = (int(t) for t in f.readline().split())
        scale = float(f.readline())
        ch = 3 if magic == b"PF" else 1
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(h, w, ch)[::-1].astype(np.float64)


def blocks(img, n=16):
    h, w = img.shape[0] // n * n, img.shape[1] // n * n
    lum = img[:h, :w].mean(axis=2)
    return lum.reshape(h // n, n, w // n, n).mean(axis=(1, 3))


def main():
    depth, ref, other = int(sys.argv[1]), read_pfm(sys.argv[2]), read_pfm(sys.argv[3])
    out = {}
    finite = np.isfinite(other).all() and np.isfinite(ref).all()
    out["finite"] = int(finite)
    out["values_differing"] = int((other != ref).sum())
    scale = max(ref.mean(), 1e-30)
    out["mean_rel_diff"] = (other.mean() - ref.mean()) / scale
    out["rel_mse"] = float(((other - ref) ** 2).mean() / scale**2)
    if depth == 1:
        # Relative to the value, with a floor at 1e-3 of the mean so that black pixels count
        # absolutely.
        rel = np.abs(other - ref) / np.maximum(np.abs(ref), 1e-3 * scale)
        out["values"] = rel.size
        out["over_1e-4"] = int((rel > 1e-4).sum())
        out["over_1e-3"] = int((rel > 1e-3).sum())
        out["max_rel"] = float(rel.max())
    if len(sys.argv) >= 6:
        a, b = read_pfm(sys.argv[4]), read_pfm(sys.argv[5])
        out["seed_rel_mse"] = float(((a - b) ** 2).mean() / scale**2)
        noise = np.abs(blocks(a) - blocks(b)) / np.sqrt(2.0)  # one render's block error
        sigma = np.sqrt(max(np.mean(noise**2), 1e-300))  # pooled, per image
        z = (blocks(other) - blocks(ref)) / sigma
        out["block_z_rms"] = float(np.sqrt(np.mean(z**2)))
        out["block_z_max"] = float(np.abs(z).max())
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in out.items()))


if __name__ == "__main__":
    main()
