#!/usr/bin/python3
"""Figure 5: relative L2 error vs Cook-Torrance roughness for light sampling, MIS and SIS at the
same number of rays per pixel toward the light (64: light and SIS at 64 spp, MIS at 32 spp with
one light and one BSDF sample each, the paper's "half and half"), bunny on a plane, depth 1, under a map of a few small
bright sources (grace.hdr) and one of broad light (pedestrian_overpass_1k.hdr).

Writes fig5_roughness.csv and fig5_roughness.png to --out (default docs/figures/fig5)."""
import os

import common as c

MATERIAL = {"type": "microfacet", "specular": [0.5, 0.5, 0.5], "albedo": [0.3, 0.3, 0.3]}


def main():
    a = c.parser(__doc__.splitlines()[0])
    a.add_argument("--spp", type=int, default=64)
    a.add_argument("--ref-spp", type=int, default=1024)
    a.add_argument("--mis-spp", type=int, default=0,
                   help="MIS samples per pixel (default spp/2: each takes one light and one BSDF "
                        "sample, so MIS traces as many rays as the others, half from each)")
    a.add_argument("--size", type=int, default=80)
    a.add_argument("--plot-only", action="store_true", help="redraw the plot from the CSV")
    args = a.parse_args()
    out = c.out_dir(args, "fig5")
    maps = ["grace.hdr", "pedestrian_overpass_1k.hdr"]
    rough = [0.02, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8]
    size, spp, ref_spp = args.size, args.spp, args.ref_spp
    if args.tiny:
        maps, rough, size, spp, ref_spp = ["grace.hdr"], [0.05, 0.5], 24, 16, 64
    csv_path = os.path.join(out, "fig5_roughness.csv")
    if args.plot_only:
        import csv

        with open(csv_path) as f:
            rows = [[r[0], float(r[1]), r[2], int(r[3]), float(r[4])] + r[5:]
                    for r in list(csv.reader(f))[1:]]
        maps = sorted({r[0] for r in rows}, key=lambda m: [r[0] for r in rows].index(m))
        spp = max(r[3] for r in rows)
        return plot(rows, maps, spp, out)
    tmp = c.tmpdir("fig5")
    rows = []
    for m in maps:
        for r in rough:
            scene = c.scene_variant("bunny_grace", os.path.join(tmp, f"{m}-{r}.json"), size, size,
                                    envmap=m, roughness=r, material=MATERIAL)
            ref = c.reference(scene, ref_spp)
            for method in ["light", "mis", "sis"]:
                img = os.path.join(tmp, f"{m}-{r}-{method}.exr")
                n = (args.mis_spp or max(1, spp // 2)) if method == "mis" else spp
                extra = ["--spp", str(n), "--strategy", method, "--seed", "1"]
                if method == "sis":
                    extra += ["--sis-samples", str(spp)]
                st = c.render(scene, img, extra)
                e = c.compare(img, ref)
                sis_s = st.get("sis", {}).get("precompute_seconds", "")
                rows.append([m, r, method, n, e["l2"], e["rmse"], e["rel_mse"],
                             st["render_seconds"], sis_s])
                print(f"{m} roughness {r} {method}: L2 {e['l2']:.4f}")
    c.write_csv(csv_path,
                ["map", "roughness", "method", "spp", "l2", "rmse", "rel_mse", "render_seconds",
                 "sis_precompute_seconds"], rows)
    plot(rows, maps, spp, out)


def plot(rows, maps, spp, out):
    """Linear (as the paper) above, logarithmic below."""
    plt = c.pyplot()
    fig, axes = plt.subplots(2, len(maps), figsize=(5 * len(maps), 7), squeeze=False)
    for k, (ax, m) in enumerate([(ax, m) for row in axes for ax, m in zip(row, maps)]):
        for method, style in [("light", "o-"), ("mis", "s-"), ("sis", "^-")]:
            pts = [(r[1], r[4]) for r in rows if r[0] == m and r[2] == method]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], style, label=method.upper() if method != "light" else "light")
        ax.set_title(f"{m.split('.')[0]}: {spp} rays/pixel (MIS {spp // 2}+{spp // 2})", fontsize=10)
        ax.set_xlabel("roughness (GGX alpha)")
        ax.set_ylabel("relative L2 error")
        if k < len(maps):
            ax.set_ylim(bottom=0)
        else:
            ax.set_yscale("log")
        ax.grid(alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig5_roughness.png"), dpi=110)
    print(f"wrote {os.path.join(out, 'fig5_roughness.png')}")


if __name__ == "__main__":
    main()
