#!/usr/bin/python3
"""Figure 5: relative L2 error vs Cook-Torrance roughness for light sampling, MIS and SIS at the
same number of shadow rays per pixel (64), bunny on a plane, depth 1, under a map of a few small
bright sources (grace.hdr) and one of broad light (pedestrian_overpass_1k.hdr).

Writes fig5_roughness.csv and fig5_roughness.png to --out (default docs/figures/fig5)."""
import os

import common as c

MATERIAL = {"type": "microfacet", "specular": [0.5, 0.5, 0.5], "albedo": [0.3, 0.3, 0.3]}


def main():
    a = c.parser(__doc__.splitlines()[0])
    a.add_argument("--spp", type=int, default=64)
    a.add_argument("--ref-spp", type=int, default=1024)
    a.add_argument("--size", type=int, default=80)
    args = a.parse_args()
    out = c.out_dir(args, "fig5")
    maps = ["grace.hdr", "pedestrian_overpass_1k.hdr"]
    rough = [0.02, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8]
    size, spp, ref_spp = args.size, args.spp, args.ref_spp
    if args.tiny:
        maps, rough, size, spp, ref_spp = ["grace.hdr"], [0.05, 0.5], 24, 16, 64
    tmp = c.tmpdir("fig5")
    rows = []
    for m in maps:
        for r in rough:
            scene = c.scene_variant("bunny_grace", os.path.join(tmp, f"{m}-{r}.json"), size, size,
                                    envmap=m, roughness=r, material=MATERIAL)
            ref = c.reference(scene, ref_spp)
            for method in ["light", "mis", "sis"]:
                img = os.path.join(tmp, f"{m}-{r}-{method}.exr")
                extra = ["--spp", str(spp), "--strategy", method, "--seed", "1"]
                if method == "sis":
                    extra += ["--sis-samples", str(spp)]
                st = c.render(scene, img, extra)
                e = c.compare(img, ref)
                sis_s = st.get("sis", {}).get("precompute_seconds", "")
                rows.append([m, r, method, spp, e["l2"], e["rmse"], e["rel_mse"],
                             st["render_seconds"], sis_s])
                print(f"{m} roughness {r} {method}: L2 {e['l2']:.4f}")
    c.write_csv(os.path.join(out, "fig5_roughness.csv"),
                ["map", "roughness", "method", "spp", "l2", "rmse", "rel_mse", "render_seconds",
                 "sis_precompute_seconds"], rows)
    plt = c.pyplot()
    fig, axes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 3.8), squeeze=False)
    for ax, m in zip(axes[0], maps):
        for method, style in [("light", "o-"), ("mis", "s-"), ("sis", "^-")]:
            pts = [(r[1], r[4]) for r in rows if r[0] == m and r[2] == method]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], style, label=method.upper() if method != "light" else "light")
        ax.set_title(f"{m}, {spp} shadow rays/pixel")
        ax.set_xlabel("roughness (GGX alpha)")
        ax.set_ylabel("relative L2 error")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig5_roughness.png"), dpi=110)
    print(f"wrote {os.path.join(out, 'fig5_roughness.png')}")


if __name__ == "__main__":
    main()
