#!/usr/bin/env python3
"""envtrace from Python: a scene built from numpy arrays, rendered, its map turned, denoised,
compared.

    PYTHONPATH=build/python /usr/bin/python3 docs/python-example.py --out renders/example

A box (8 vertices, 12 triangles) on a ground quad, lit by a map made here: a blue-white sky
gradient with a small bright sun. The film is rendered progressively (8 + 8 samples), then the
map is turned by 90 degrees (the film restarts; nothing is reloaded), and the two images and
their difference are compared with the metrics of `envtrace compare`. docs/python.md is the
reference; ctest python_example runs this.
"""

import argparse
import os

import numpy as np

import envtrace


def sky_map(width=256, height=128):
    """A lat-long sky: brighter towards the zenith, a sun 40 degrees up (row 0 looks up)."""
    v = (np.arange(height) + 0.5) / height                  # 0 at the zenith, 1 at the nadir
    up = np.clip(1.0 - 2.0 * v, 0.0, 1.0)[:, None, None]
    sky = np.float32([0.35, 0.55, 1.0]) * (0.3 + 0.7 * up) + np.float32([0.2, 0.2, 0.2]) * (1 - up)
    image = np.broadcast_to(sky, (height, width, 3)).copy()
    sun_row, sun_col = int((0.5 - 40 / 180) * height), width // 3
    image[sun_row - 1:sun_row + 2, sun_col - 1:sun_col + 2] = 20000.0
    return image.astype(np.float32)


def box(size=0.8):
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (0, 2) for z in (-1, 1)],
                       dtype=np.float32) * (size / 2)
    # Each face as two counter-clockwise triangles seen from outside.
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    indices = [t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))]
    return corners, np.array(indices, dtype=np.int32)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="renders/python-example", help="folder for the images")
    ap.add_argument("--backend", default="cpu", choices=["cpu", "opencl"])
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    vertices, indices = box()
    scene = {
        "camera": {"eye": [1.6, 1.2, 2.4], "target": [0, 0.35, 0], "fov": 40},
        "film": {"width": 64, "height": 48},
        "environment": {"map": sky_map()},
        "materials": {
            "ground": {"type": "diffuse", "albedo": 0.5},
            "paint": {"type": "plastic", "albedo": [0.7, 0.2, 0.1], "roughness": 0.2},
        },
        "shapes": [
            {"type": "quad", "size": 8, "material": "ground"},
            {"type": "mesh", "vertices": vertices, "indices": indices, "material": "paint",
             "transform": {"rotate": [0, 1, 0, 30]}},
        ],
        "render": {"max_depth": 4, "seed": 1},
    }

    r = envtrace.Renderer(scene, backend=args.backend, aovs=True)  # aovs: to denoise
    r.render(spp=8)
    before = r.render(spp=8)  # the same film: 16 samples, the bits of one render of 16
    stats = r.stats()
    print(f"rendered {r.spp} spp in {stats['render_seconds']:.3f} s, "
          f"estimated relative error {r.noise():.3f}")
    envtrace.write_image(os.path.join(args.out, "before.exr"), before)

    r.set_environment(rotation=90)  # the sun moves a quarter turn; the film restarts
    after = r.render(spp=16)
    envtrace.write_image(os.path.join(args.out, "after.exr"), after)
    try:  # Open Image Denoise, guided by the film's albedo and normal
        envtrace.write_image(os.path.join(args.out, "after.denoised.exr"), r.denoised())
        print("denoised the turned map's film")
    except envtrace.Error as e:  # the denoiser is optional: tools/setup installs it
        print(f"no denoiser: {e}")

    errors = envtrace.compare(after, before)
    print(f"turned map against the first: rmse {errors['rmse']:.4f}, "
          f"relative MSE {errors['rel_mse']:.4f}")
    # The samples the light strategy draws from the map: most land on the sun.
    samples = envtrace.load_map(sky_map()).sample(256, backend=args.backend)
    on_sun = np.mean(samples["radiance"][:, 0] > 100)
    print(f"{on_sun:.0%} of 256 map samples fall on the sun")
    assert errors["rmse"] > 0 and on_sun > 0.5, "the turned map should light the box otherwise"


if __name__ == "__main__":
    main()
