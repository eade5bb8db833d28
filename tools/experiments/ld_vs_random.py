#!/usr/bin/python3
"""Low-discrepancy vs independent random samples: relative L2 error of light sampling at 16, 64
and 256 spp with the scrambled (0,2)-sequence ('sobol') and with independent uniform values
('random'), bunny on a plane at depth 1 (plastic, roughness 0.3) under grace.hdr and
pedestrian_overpass_1k.hdr. Random is averaged over --seeds seeds, as is Sobol' (other scrambles).

Writes ld_vs_random.csv and ld_vs_random.png to --out (default docs/figures/ld_vs_random)."""
import os

import common as c


def main():
    a = c.parser(__doc__.splitlines()[0])
    a.add_argument("--size", type=int, default=96)
    a.add_argument("--ref-spp", type=int, default=2048)
    a.add_argument("--seeds", type=int, default=3)
    args = a.parse_args()
    out = c.out_dir(args, "ld_vs_random")
    tmp = c.tmpdir("ld")
    maps = ["grace.hdr", "pedestrian_overpass_1k.hdr"]
    spps, size, ref_spp, seeds = [16, 64, 256], args.size, args.ref_spp, args.seeds
    if args.tiny:
        maps, spps, size, ref_spp, seeds = ["grace.hdr"], [4, 16], 24, 64, 1
    rows = []
    for m in maps:
        stem = m.split(".")[0]
        scene = c.scene_variant("bunny_grace", os.path.join(tmp, stem + ".json"), size, size, envmap=m)
        ref = c.reference(scene, ref_spp)
        for sampler in ["sobol", "random"]:
            for spp in spps:
                errs = []
                for seed in range(1, seeds + 1):
                    img = os.path.join(tmp, f"{stem}-{sampler}-{spp}-{seed}.exr")
                    c.render(scene, img, ["--spp", str(spp), "--strategy", "light", "--sampler",
                                          sampler, "--seed", str(seed)])
                    errs.append(c.compare(img, ref)["l2"])
                mean = sum(errs) / len(errs)
                rows.append([m, sampler, spp, mean, min(errs), max(errs), len(errs)])
                print(f"{m} {sampler} {spp} spp: L2 {mean:.4f}")
    c.write_csv(os.path.join(out, "ld_vs_random.csv"),
                ["map", "sampler", "spp", "l2_mean", "l2_min", "l2_max", "seeds"], rows)
    plt = c.pyplot()
    fig, axes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 3.8), squeeze=False)
    for ax, m in zip(axes[0], maps):
        for sampler, style in [("sobol", "o-"), ("random", "s--")]:
            pts = [(r[2], r[3]) for r in rows if r[0] == m and r[1] == sampler]
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], style,
                      label="(0,2)-sequence" if sampler == "sobol" else "independent random")
        x0, y0 = rows[[r[0] for r in rows].index(m) + len(spps)][2:4]
        ax.loglog(spps, [y0 * (x0 / s) ** 0.5 for s in spps], ":", color="gray", label="N^-1/2")
        ax.set_title(f"{m}: light sampling")
        ax.set_xlabel("samples per pixel")
        ax.set_ylabel("relative L2 error")
        ax.grid(alpha=0.3, which="both")
        ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "ld_vs_random.png"), dpi=110)
    print(f"wrote {os.path.join(out, 'ld_vs_random.png')}")


if __name__ == "__main__":
    main()
