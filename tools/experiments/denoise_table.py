#!/usr/bin/python3
"""Denoising (render --denoise: Open Image Denoise 2, guided by the albedo and normal AOVs)
against converged references: the relative MSE (envtrace compare's rel_mse) of the noisy image
and of the denoised one at 4, 16 and 64 spp on three shipped scenes, and the denoiser's time
(the stats' denoise.seconds: starting the device, the two guide prefilters and the beauty).

    tools/experiments/denoise_table.py [--size 160 120] [--spps 4 16 64] [--ref-spp 2048]

References: tools/make_reference (MIS, Sobol', seed 7919, native), cached in build/reference-cache;
the renders use seed 1 and each scene's own strategy. A reference of R spp adds about
E(N) x N / R to the relative MSE measured at N spp (E(N) that of the noisy image), the floor
the last column gives. Writes docs/figures/denoise/denoise.{md,csv}."""
import os

import common
from efficiency import file_scene

SCENES = ["cornell_box", "matpreview", "bunny_grace"]


def measure(scene, ref, spp, scratch):
    out = os.path.join(scratch, f"{os.path.basename(scene)[:-5]}-{spp}.exr")
    stats = common.render(scene, out, ["--spp", str(spp), "--seed", "1", "--denoise"])
    noisy = common.compare(out, ref)["rel_mse"]
    denoised = common.compare(out[:-4] + ".denoised.exr", ref)["rel_mse"]
    return noisy, denoised, stats["denoise"]["seconds"]


def main():
    p = common.parser(__doc__.split("\n\n")[0])
    p.add_argument("--size", type=int, nargs=2, default=[160, 120])
    p.add_argument("--spps", type=int, nargs="+", default=[4, 16, 64])
    p.add_argument("--ref-spp", type=int, default=2048)
    p.add_argument("--scenes", nargs="+", default=SCENES)
    a = p.parse_args()
    if a.tiny:
        a.size, a.spps, a.ref_spp = [32, 24], [4, 16], 64
    out = common.out_dir(a, "denoise")
    scratch = common.tmpdir("denoise")
    common.data_dir()
    rows = []
    for name in a.scenes:
        _, scene = file_scene(os.path.join(common.REPO, "scenes", name + ".json"), scratch,
                              tuple(a.size))
        ref = common.reference(scene, a.ref_spp)
        for spp in a.spps:
            noisy, denoised, seconds = measure(scene, ref, spp, scratch)
            floor = noisy * spp / a.ref_spp
            rows.append([name, spp, f"{noisy:.4g}", f"{denoised:.4g}", f"{denoised / noisy:.3f}",
                         f"{seconds:.3f}", f"{floor:.2g}"])
            print(" ".join(map(str, rows[-1])), flush=True)
    header = ["scene", "spp", "rel_mse_noisy", "rel_mse_denoised", "ratio", "denoise_seconds",
              "reference_floor"]
    common.write_csv(os.path.join(out, "denoise.csv"), header, rows)
    w, h = a.size
    md = [f"Film {w}x{h}; reference {a.ref_spp} spp (MIS); relative MSE against it "
          "(`envtrace compare`), noisy and denoised; the denoiser's seconds (device start, two "
          "guide prefilters, the beauty); the floor the reference's own noise adds "
          "(noisy x spp / reference spp).", "",
          "| scene | spp | noisy | denoised | denoised / noisy | denoise s | reference floor |",
          "|---|---|---|---|---|---|---|"]
    md += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    with open(os.path.join(out, "denoise.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    print(f"wrote {os.path.join(out, 'denoise.md')}")


if __name__ == "__main__":
    main()
