#!/usr/bin/python3
"""Splits every triangle of an OBJ mesh into four at its edges' midpoints, LEVELS times, and
writes the result as binary little-endian PLY (bench_rays' larger meshes: the same shape with
4^LEVELS times the triangles, so that traversal is measured on one scene at several sizes; a
flat split keeps the surface, hence the rays' hits, where they were).

Usage: subdivide_mesh.py IN.obj LEVELS OUT.ply"""
import sys

import numpy as np


def read_obj(path):
    verts, tris = [], []
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                verts.append([float(x) for x in p[1:4]])
            elif p[0] == "f":
                idx = [int(x.split("/")[0]) for x in p[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                for k in range(1, len(idx) - 1):  # a fan for polygons
                    tris.append([idx[0], idx[k], idx[k + 1]])
    return np.array(verts, dtype=np.float64), np.array(tris, dtype=np.int64)


def subdivide(v, t):
    # One midpoint per undirected edge, shared by the edge's two triangles (no cracks).
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    mids = 0.5 * (v[uniq[:, 0]] + v[uniq[:, 1]])
    m = inv + len(v)
    n = len(t)
    m01, m12, m20 = m[:n], m[n : 2 * n], m[2 * n :]
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    out = np.concatenate(
        [
            np.stack([a, m01, m20], axis=1),
            np.stack([m01, b, m12], axis=1),
            np.stack([m20, m12, c], axis=1),
            np.stack([m01, m12, m20], axis=1),
        ]
    )
    return np.concatenate([v, mids]), out


def write_ply(path, v, t):
    head = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(v)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(t)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    face = np.zeros(len(t), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"] = 3
    face["i"] = t
    with open(path, "wb") as f:
        f.write(head.encode("ascii"))
        f.write(v.astype("<f4").tobytes())
        f.write(face.tobytes())


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    v, t = read_obj(sys.argv[1])
    for _ in range(int(sys.argv[2])):
        v, t = subdivide(v, t)
    write_ply(sys.argv[3], v, t)
    print(f"{sys.argv[3]}: {len(v)} vertices, {len(t)} triangles")


if __name__ == "__main__":
    main()
