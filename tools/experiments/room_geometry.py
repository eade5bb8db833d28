"""Boxes, rectangles and walls with openings, written as OBJ + MTL: the geometry of generated
rooms (scenes/interiors/make_interiors.py, tools/experiments/scene_set.py)."""
import os


class Obj:
    def __init__(self):
        self.v, self.f = [], []

    def quad(self, a, b, c, d, mtl):
        """A rectangle a-b-c-d (counter-clockwise seen from the side its normal points to)."""
        base = len(self.v) + 1
        self.v += [a, b, c, d]
        self.f.append((mtl, [base, base + 1, base + 2, base + 3]))

    def box(self, lo, hi, mtl, skip=()):
        x0, y0, z0 = lo
        x1, y1, z1 = hi
        faces = {
            "-x": [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)],
            "+x": [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)],
            "-y": [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],
            "+y": [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)],
            "-z": [(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)],
            "+z": [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],
        }
        for k, q in faces.items():
            if k not in skip:
                self.quad(*q, mtl)

    def write(self, folder, name, materials, writer):
        """name.obj and name.mtl in folder; materials: name -> Kd (diffuse); writer: the script
        named in the files' first line."""
        with open(os.path.join(folder, name + ".mtl"), "w") as f:
            f.write(f"# written by {writer}\n")
            for m, kd in materials.items():
                f.write(f"newmtl {m}\nKd {kd[0]} {kd[1]} {kd[2]}\nKs 0 0 0\n\n")
        with open(os.path.join(folder, name + ".obj"), "w") as f:
            f.write(f"# written by {writer}\nmtllib {name}.mtl\n")
            for v in self.v:
                f.write("v %g %g %g\n" % v)
            cur = None
            for m, idx in self.f:
                if m != cur:
                    f.write(f"usemtl {m}\n")
                    cur = m
                f.write("f " + " ".join(map(str, idx)) + "\n")


def wall_with_holes(o, axis_pts, holes, mtl):
    """A wall in the plane z = z0 from x0..x1, y0..y1 with rectangular holes [(hx0, hx1, hy0,
    hy1)], split into rectangles: full-height strips between holes, and above/below each hole.
    Faces +Z (into a room that lies at z > z0)."""
    (x0, x1, y0, y1, z0) = axis_pts
    xs = [x0] + [c for h in sorted(holes) for c in (h[0], h[1])] + [x1]

    def rect(a, b, c, d):  # x a..b, y c..d, facing +z
        o.quad((a, c, z0), (b, c, z0), (b, d, z0), (a, d, z0), mtl)

    for k in range(0, len(xs), 2):
        if xs[k + 1] > xs[k]:
            rect(xs[k], xs[k + 1], y0, y1)
    for hx0, hx1, hy0, hy1 in holes:
        rect(hx0, hx1, y0, hy0)
        rect(hx0, hx1, hy1, y1)
