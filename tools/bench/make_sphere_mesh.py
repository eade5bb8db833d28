#!/usr/bin/python3
"""Writes a unit sphere of about N triangles as an OBJ (docs/history/bench-journal.md, "How cost
grows"): a cube whose
six faces are n x n grids, projected onto the sphere (12 n^2 triangles of similar size and
shape, unlike a lat-long sphere's slivers at the poles), with vertex normals.

Usage: make_sphere_mesh.py TRIANGLES OUT.obj|OUT.ply   (n = round(sqrt(TRIANGLES / 12)))
A .ply name writes binary little-endian PLY (about a third of the OBJ's bytes, and read without
parsing text: the 16M-triangle point of the scaling table)."""
import sys

import numpy as np


def cube_sphere(n):
    t = np.linspace(-1.0, 1.0, n + 1)
    a, b = np.meshgrid(t, t, indexing="ij")
    a, b, one = a.ravel(), b.ravel(), np.ones((n + 1) * (n + 1))
    faces = [(one, a, b), (-one, b, a), (a, one, b), (b, -one, a), (a, b, one), (b, a, -one)]
    verts, tris = [], []
    idx = np.arange((n + 1) * (n + 1)).reshape(n + 1, n + 1)
    q0, q1, q2, q3 = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    for f, (x, y, z) in enumerate(faces):
        p = np.stack([x, y, z], axis=1)
        verts.append(p / np.linalg.norm(p, axis=1, keepdims=True))
        base = f * (n + 1) * (n + 1)
        t1 = np.stack([q0, q1, q2], axis=1) + base
        t2 = np.stack([q0, q2, q3], axis=1) + base
        tris += [t1, t2]
    v = np.concatenate(verts)
    t = np.concatenate(tris)
    # Wind every triangle outwards (the faces above mix handedness).
    e = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    flip = np.einsum("ij,ij->i", e, v[t[:, 0]]) < 0
    t[flip] = t[flip][:, ::-1]
    return v, t


def write_ply(path, v, t):
    head = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(v)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        f"element face {len(t)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    vert = np.concatenate([v, v], axis=1).astype("<f4")  # unit sphere: the normal is the point
    face = np.zeros(len(t), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"] = 3
    face["i"] = t
    with open(path, "wb") as f:
        f.write(head.encode("ascii"))
        f.write(vert.tobytes())
        f.write(face.tobytes())


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    n = max(1, round((int(sys.argv[1]) / 12) ** 0.5))
    v, t = cube_sphere(n)
    if sys.argv[2].endswith(".ply"):
        write_ply(sys.argv[2], v, t)
        print(f"{sys.argv[2]}: n = {n}, {len(v)} vertices, {len(t)} triangles")
        return
    with open(sys.argv[2], "w") as f:
        f.write(f"# cube sphere, n = {n}: {len(t)} triangles\n")
        np.savetxt(f, v, fmt="v %.7g %.7g %.7g")
        np.savetxt(f, v, fmt="vn %.7g %.7g %.7g")
        t1 = t + 1
        np.savetxt(f, np.repeat(t1, 2, axis=1), fmt="f %d//%d %d//%d %d//%d")
    print(f"{sys.argv[2]}: n = {n}, {len(v)} vertices, {len(t)} triangles")


if __name__ == "__main__":
    main()
