#!/usr/bin/python3
"""Figure 8: reference vs 32 directional lights from our sampling vs 32 from SIS, with each
light set's relative L2 error and its precomputation + selection time. Bunny on a plane under
grace.hdr and royal_esplanade_1k.hdr (plastic, roughness 0.3, depth 1).

Writes fig8_lights.csv and fig8_lights.png to --out (default docs/figures/fig8)."""
import json
import os

import common as c


def main():
    a = c.parser(__doc__.splitlines()[0])
    a.add_argument("-n", type=int, default=32)
    a.add_argument("--size", type=int, default=128)
    a.add_argument("--ref-spp", type=int, default=1024)
    args = a.parse_args()
    out = c.out_dir(args, "fig8")
    tmp = c.tmpdir("fig8")
    maps = ["grace.hdr", "royal_esplanade_1k.hdr"]
    size, ref_spp, n = args.size, args.ref_spp, args.n
    if args.tiny:
        maps, size, ref_spp, n = ["grace.hdr"], 24, 32, 8
    rows, panels = [], []
    for m in maps:
        stem = m.split(".")[0]
        scene = c.scene_variant("bunny_grace", os.path.join(tmp, stem + ".json"), size, size, envmap=m)
        ref = c.reference(scene, ref_spp)
        row_panels = [(ref[:-4] + ".png", f"reference ({ref_spp} spp MIS)")]
        for method, power in [("ours", "share"), ("ours", "voronoi"), ("sis", "voronoi")]:
            lights = os.path.join(tmp, f"{stem}-{method}-{power}.json")
            c.run([c.envtrace(), "lights", os.path.join(c.data_dir(), "envmaps", m), "-n", str(n),
                   "--method", method, "--power", power, "-o", lights])
            with open(lights) as f:
                lj = json.load(f)
            img = os.path.join(tmp, f"{stem}-{method}-{power}.exr")
            st = c.render(scene, img, ["--lights", lights, "--spp", "4"])
            e = c.compare(img, ref)
            rows.append([m, method, power, n, e["l2"], e["rmse"], lj["precompute_seconds"],
                         lj["selection_seconds"], lj["total_seconds"], st["render_seconds"]])
            label = f"{n} lights, {method}" + (f" ({power})" if method == "ours" else "")
            row_panels.append((img[:-4] + ".png",
                               f"{label}\nL2 {e['l2']:.3f}, lights in {lj['total_seconds']*1e3:.1f} ms"))
            print(f"{m} {method}/{power}: L2 {e['l2']:.4f}, {lj['total_seconds']:.4f} s")
        panels.append((m, row_panels))
    c.write_csv(os.path.join(out, "fig8_lights.csv"),
                ["map", "method", "power_rule", "lights", "l2", "rmse", "precompute_seconds",
                 "selection_seconds", "total_seconds", "render_seconds"], rows)
    plt = c.pyplot()
    fig, axes = plt.subplots(len(panels), 4, figsize=(13, 3.6 * len(panels)), squeeze=False)
    for r, (m, row_panels) in enumerate(panels):
        for k, (png, title) in enumerate(row_panels):
            axes[r, k].imshow(plt.imread(png))
            axes[r, k].set_title((m + ": " if k == 0 else "") + title, fontsize=9)
            axes[r, k].axis("off")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig8_lights.png"), dpi=100)
    print(f"wrote {os.path.join(out, 'fig8_lights.png')}")


if __name__ == "__main__":
    main()
