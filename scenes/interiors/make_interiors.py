#!/usr/bin/python3
"""Writes the interior scenes of the visibility strategy: rooms whose only light is a
procedural sun and sky seen through openings, so that most directions the map's distribution
picks are blocked. Geometry is generated here (OBJ + MTL beside each scene JSON); nothing is
copied from outside data.

    scenes/interiors/make_interiors.py            # rewrites window_room.* and skylight_room.*

window_room: a closed 6 x 3 x 5 m room with two windows in its south wall (the sun's side, -Z),
  a table, a cabinet and a bench (boxes); the sun at 30 degrees shines through the windows onto
  the floor. skylight_room: a closed 5 x 3 x 5 m room lit only through a 0.8 x 0.8 m opening in
  the ceiling, a box below it; the sun at 65 degrees."""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools", "experiments"))
from room_geometry import Obj, wall_with_holes  # noqa: E402


def scene_json(name, camera, sky, spp=64):
    return {
        "camera": camera,
        "film": {"width": 160, "height": 120},
        "environment": {"sky": sky},
        "shapes": [{"type": "mesh", "file": f"{name}.obj"}],
        "render": {"spp": spp, "max_depth": 5, "strategy": "visibility", "sampler": "sobol", "seed": 1},
        "output": f"{name}.exr",
    }


def window_room():
    o = Obj()
    W, H, D = 6.0, 3.0, 5.0  # x 0..6, y 0..3, z 0..5; windows in the wall z = 0
    o.quad((0, 0, 0), (0, 0, D), (W, 0, D), (W, 0, 0), "floor")          # +y
    o.quad((0, H, 0), (W, H, 0), (W, H, D), (0, H, D), "ceiling")        # -y
    o.quad((0, 0, D), (0, H, D), (W, H, D), (W, 0, D), "wall")           # north, faces -z
    o.quad((0, 0, 0), (0, H, 0), (0, H, D), (0, 0, D), "wall")           # west, faces +x
    o.quad((W, 0, 0), (W, 0, D), (W, H, D), (W, H, 0), "wall")           # east, faces -x
    wall_with_holes(o, (0, W, 0, H, 0.0), [(1.0, 2.2, 1.0, 2.2), (3.8, 5.0, 1.0, 2.2)], "wall")
    o.box((2.2, 0.0, 2.0), (3.8, 0.75, 3.0), "table")                   # table (a block)
    o.box((0.2, 0.0, 4.2), (1.4, 1.8, 4.8), "cabinet")                  # tall cabinet
    o.box((4.2, 0.0, 3.6), (5.7, 0.45, 4.3), "bench")                   # low bench
    o.write(HERE, "window_room", {"floor": (0.55, 0.45, 0.35), "ceiling": (0.8, 0.8, 0.8),
                             "wall": (0.75, 0.75, 0.72), "table": (0.5, 0.3, 0.15),
                             "cabinet": (0.3, 0.4, 0.6), "bench": (0.6, 0.2, 0.2)}, "make_interiors.py")
    # The sun to the south (-Z) at 30 degrees: azimuth picks where it stands (sky.h).
    sky = {"resolution": [1024, 512], "sun_elevation": 30, "sun_azimuth": 20,
           "sun_radius": 0.8, "sun_radiance": 3000, "sky_radiance": 1}
    cam = {"eye": [3.0, 1.6, 4.7], "target": [3.0, 1.0, 0.0], "up": [0, 1, 0], "fov": 70}
    return scene_json("window_room", cam, sky)


def skylight_room():
    o = Obj()
    W, H, D = 5.0, 3.0, 5.0
    o.quad((0, 0, 0), (0, 0, D), (W, 0, D), (W, 0, 0), "floor")
    o.quad((0, 0, D), (0, H, D), (W, H, D), (W, 0, D), "wall")
    o.quad((0, 0, 0), (W, 0, 0), (W, H, 0), (0, H, 0), "wall")
    o.quad((0, 0, 0), (0, H, 0), (0, H, D), (0, 0, D), "wall")
    o.quad((W, 0, 0), (W, 0, D), (W, H, D), (W, H, 0), "wall")
    # The ceiling with a 0.8 x 0.8 opening centred at (2.5, 2.5), facing -y.
    a, b = 2.1, 2.9
    def ceil(x0, x1, z0, z1):
        o.quad((x0, H, z0), (x1, H, z0), (x1, H, z1), (x0, H, z1), "ceiling")
    ceil(0, W, 0, a)
    ceil(0, W, b, D)
    ceil(0, a, a, b)
    ceil(b, W, a, b)
    o.box((1.8, 0.0, 1.0), (3.2, 0.9, 2.0), "box")
    o.write(HERE, "skylight_room", {"floor": (0.5, 0.5, 0.5), "ceiling": (0.8, 0.8, 0.8),
                               "wall": (0.7, 0.72, 0.75), "box": (0.7, 0.5, 0.3)}, "make_interiors.py")
    sky = {"resolution": [1024, 512], "sun_elevation": 65, "sun_azimuth": 20,
           "sun_radius": 0.8, "sun_radiance": 3000, "sky_radiance": 1}
    cam = {"eye": [0.4, 1.7, 4.6], "target": [2.6, 0.6, 1.5], "up": [0, 1, 0], "fov": 70}
    return scene_json("skylight_room", cam, sky)


def main():
    for name, js in (("window_room", window_room()), ("skylight_room", skylight_room())):
        with open(os.path.join(HERE, name + ".json"), "w") as f:
            json.dump(js, f, indent=1)
            f.write("\n")
        print("wrote", os.path.join(HERE, name + ".json"))


if __name__ == "__main__":
    main()
