#!/usr/bin/python3
"""Figure 6: 128 directions drawn by warping the scrambled (0,2)-sequence through the map's
distribution, drawn on the map (royal_esplanade_1k.hdr: a tiny sun; grace.hdr: small sources).

Writes fig6_points_<map>.csv (u, v, pdf-free power share of each point), the envtrace plots and
fig6_points.png to --out (default docs/figures/fig6)."""
import json
import os

import common as c


def main():
    a = c.parser(__doc__.splitlines()[0])
    a.add_argument("-n", type=int, default=128)
    args = a.parse_args()
    out = c.out_dir(args, "fig6")
    tmp = c.tmpdir("fig6")
    maps = ["royal_esplanade_1k.hdr", "grace.hdr"]
    n = 16 if args.tiny else args.n
    import numpy as np

    plt = c.pyplot()
    fig, axes = plt.subplots(len(maps), 1, figsize=(8, 4.3 * len(maps)), squeeze=False)
    for ax, m in zip(axes[:, 0], maps):
        path = os.path.join(c.data_dir(), "envmaps", m)
        stem = m.split(".")[0]
        lights = os.path.join(tmp, stem + ".json")
        plot = os.path.join(out, f"fig6_{stem}.png")
        log = c.run([c.envtrace(), "lights", path, "-n", str(n), "-o", lights, "--plot", plot])
        with open(lights) as f:
            j = json.load(f)
        rows = []
        for l in j["lights"]:
            x, y, z = l["direction"]
            u = (1 + np.arctan2(x, -z) / np.pi) / 2
            v = np.arccos(np.clip(y, -1, 1)) / np.pi
            rows.append([u, v, *l["power"]])
        c.write_csv(os.path.join(out, f"fig6_points_{stem}.csv"),
                    ["u", "v", "power_r", "power_g", "power_b"], rows)
        ax.imshow(plt.imread(plot))
        ax.set_title(f"{n} points on {m}: " + log.strip().splitlines()[2])
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig6_points.png"), dpi=100)
    print(f"wrote {os.path.join(out, 'fig6_points.png')}")


if __name__ == "__main__":
    main()
