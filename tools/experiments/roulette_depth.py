#!/usr/bin/python3
"""Where Russian roulette should start (render.rr_depth, kernels/integrator.h): for each scene,
strategy and roulette depth, two renders of equal spp with two seeds give the relative variance
per pixel (mean over the image of (a - b)^2 / (m^2 + (0.01 mean m)^2) / 2, a and b the two
renders' luminance (the mean of the channels), m their mean) and their mean render time (the
stats' render_seconds: no loading or writing); efficiency is 1 / (variance x time), reported
relative to the first depth. Equal spp rather than equal time: the two seeds' difference needs
no reference.

    tools/experiments/roulette_depth.py [--depths 2 4 5 1000] [--strategies mis visibility]

writes docs/figures/roulette/roulette.{md,csv}."""
import math
import os
import sys

import common
from efficiency import file_scene

# (scene, film, spp): the interiors at the size the visibility figures use, the others small.
SCENES = [("interiors/window_room", (320, 240), 128), ("interiors/skylight_room", (320, 240), 128),
          ("cornell_box", (256, 256), 64), ("glass", (320, 200), 64), ("matpreview", (342, 256), 64),
          ("bunny_grace", (256, 256), 64), ("textures", (240, 180), 64)]


def main():
    p = common.parser(__doc__.split("\n\n")[0])
    p.add_argument("--depths", type=int, nargs="+", default=[2, 4, 5, 1000])
    p.add_argument("--strategies", nargs="+", default=["mis", "visibility"])
    p.add_argument("--scenes", nargs="+", default=None, help="names of SCENES (default: all)")
    a = p.parse_args()
    common.data_dir()
    out = common.out_dir(a, "roulette")
    work = common.tmpdir("roulette")
    cases = [c for c in SCENES if not a.scenes or c[0] in a.scenes]
    if a.tiny:
        cases, a.depths, a.strategies = [("interiors/window_room", (32, 24), 4)], [2, 5], ["mis"]
    rows = []
    for name, size, spp in cases:
        # bunny_grace's own depth is 1, where the roulette never runs: measured at 5.
        depth = ["--max-depth", "5"] if name == "bunny_grace" else []
        _, scene = file_scene(os.path.join(common.REPO, "scenes", name + ".json"), work, size)
        for strategy in a.strategies:
            base = None
            for rr in a.depths:
                images, seconds = [], []
                for seed in (1, 2):
                    img = os.path.join(work, f"{os.path.basename(name)}-{strategy}-{rr}-{seed}.pfm")
                    stats = common.render(scene, img, ["--strategy", strategy, "--seed", str(seed),
                                                       "--spp", str(spp), "--rr-depth", str(rr)] +
                                          depth)
                    seconds.append(stats["render_seconds"])
                    images.append(common.read_pfm(img))
                # On the luminance (the channels' mean), as docs/history/results-journal.md's
                # figures are.
                lum = [img.mean(axis=2, keepdims=True) for img in images]
                v, t = common.relative_variance(*lum), sum(seconds) / 2
                cost = v * t
                if base is None:
                    base = cost
                gain = base / cost if cost > 0 and math.isfinite(base) else float("nan")
                rows.append([name, strategy, rr, f"{v:.5g}", f"{t:.3g}", f"{gain:.2f}"])
                print(" ".join(str(x) for x in rows[-1]), flush=True)
    header = ["scene", "strategy", "rr_depth", "relative variance", "seconds", "efficiency"]
    common.write_csv(os.path.join(out, "roulette.csv"), header, rows)
    with open(os.path.join(out, "roulette.md"), "w") as f:
        f.write("Command: `tools/experiments/roulette_depth.py " + " ".join(sys.argv[1:]) +
                "` (two seeds at equal spp; efficiency relative to the first rr_depth)\n\n")
        f.write("| " + " | ".join(header) + " |\n|" + "---|" * len(header) + "\n")
        for r in rows:
            f.write("| " + " | ".join(str(x) for x in r) + " |\n")
    print(f"wrote {os.path.join(out, 'roulette.md')}")


if __name__ == "__main__":
    sys.exit(main())
