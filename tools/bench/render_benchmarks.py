#!/usr/bin/python3
"""Renderer benchmarks: `envtrace bench` on the bunny under grace, royal_esplanade_1k
and pedestrian_overpass_1k, and on ogre, at depth 1 and 5, 512x512. Each invocation renders with
both back ends in alternation (see host/cli/bench_command.cpp), and tools/bench/render_probes
(environment-sampling share, program builds); this script collects their JSON
into one markdown file (default tools/bench/render_results.md) and keeps the raw JSON and logs.

Usage: tools/bench/render_benchmarks.py [--runs 5] [--bin build/envtrace] [--out FILE]
                                        [--raw DIR] [--scenes a.json,b.json] [--depths 1,5]
Not a test: nothing registers it with ctest.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCENES = ["scenes/bunny_grace.json", "scenes/bunny_esplanade.json",
          "scenes/bunny_overpass.json", "scenes/ogre.json"]


def loadavg():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def git(*args):
    try:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "?"


def fmt_range(s, digits):
    return f"{s['median']:.{digits}f} [{s['min']:.{digits}f}–{s['max']:.{digits}f}]"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "envtrace"))
    ap.add_argument("--out", default=os.path.join(ROOT, "tools", "bench", "render_results.md"))
    ap.add_argument("--raw", default=os.path.join(ROOT, "build", "render_bench"),
                    help="folder for each invocation's JSON and log")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--depths", default="1,5")
    # The throughput of one estimator across versions: the paper's, as these results have always
    # measured, whatever the scenes name (some name visibility, which learns).
    ap.add_argument("--strategy", default="mis", help="estimator (default mis, the paper's)")
    ap.add_argument("--spp", type=int, default=0, help="spp per run (default: envtrace chooses)")
    args = ap.parse_args()
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"render_benchmarks.py: {args.bin} not found; build first (tools/setup)")
    os.makedirs(args.raw, exist_ok=True)

    load_before = loadavg()
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    results = []
    first = True
    for scene in args.scenes.split(","):
        for depth in [int(d) for d in args.depths.split(",")]:
            name = os.path.splitext(os.path.basename(scene))[0]
            stem = os.path.join(args.raw, f"{name}_d{depth}")
            cmd = [args.bin, "bench", os.path.join(ROOT, scene) if not os.path.isabs(scene)
                   else scene, "--max-depth", str(depth), "--runs", str(args.runs),
                   "--json", stem + ".json", "--strategy", args.strategy]
            if args.spp > 0:
                cmd += ["--spp", str(args.spp)]
            print("+", " ".join(cmd), flush=True)
            with open(stem + ".log", "w") as log:
                proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                      text=True)
                log.write(proc.stdout)
            print(proc.stdout, flush=True)
            if proc.returncode != 0:
                sys.exit(f"render_benchmarks.py: {' '.join(cmd)} failed ({proc.returncode})")
            with open(stem + ".json") as f:
                j = json.load(f)
            # The environment-sampling share and the program builds: tools/bench/render_probes.
            probe = [os.path.join(os.path.dirname(args.bin), "tools", "bench", "render_probes"),
                     cmd[2], "--max-depth", str(depth), "--runs", str(args.runs),
                     "--strategy", args.strategy, "--envtrace",
                     args.bin, "--json", stem + "_probes.json"]
            print("+", " ".join(probe), flush=True)
            proc = subprocess.run(probe, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            print(proc.stdout, flush=True)
            if proc.returncode != 0:
                sys.exit(f"render_benchmarks.py: {' '.join(probe)} failed ({proc.returncode})")
            with open(stem + "_probes.json") as f:
                p = json.load(f)
            j["env_sampling"] = p["env_sampling"]
            j["program_build"].update(p["program_build"])
            j["name"] = name
            results.append(j)
            first = False
    load_after = loadavg()
    finished = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())

    host = results[0]["host"]
    L = []
    L.append("# Renderer benchmarks: OpenCL (PoCL) vs native, 512x512\n")
    L.append(f"Generated by `tools/bench/render_benchmarks.py --runs {args.runs}` "
             f"({started} – {finished}), commit `{git('rev-parse', '--short', 'HEAD')}`"
             f"{' with uncommitted changes in the working tree' if git('status', '--porcelain', '--', 'kernels', 'host') else ''}.")
    shown = os.path.relpath(args.bin, ROOT)
    shown = args.bin if shown.startswith("..") else shown
    L.append(f"Binary `{shown}` built "
             f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime(os.path.getmtime(args.bin)))} "
             "from the working tree (kernels embedded at build time).")
    L.append(f"Machine: {host['hardware_threads']} hardware threads, OpenCL device "
             f"{host.get('opencl_device', '?')}, native back end on {host['native_threads']} "
             f"threads; {host['kernel']}. Load average (1/5/15 min) before {load_before}, "
             f"after {load_after}.\n")
    L.append("Each row is one `envtrace bench SCENE --max-depth D --runs R` invocation: a warm-up "
             "render per back end (not counted), then R runs per back end in alternation "
             "(opencl, cpu, opencl, cpu, ...), each a fresh renderer rendering the same spp. "
             "Medians with [min–max] over the R runs. Mrays/s counts camera + continuation + "
             "shadow rays. **Ratio** = OpenCL/native throughput (> 1: OpenCL faster); *of medians* "
             "and *per pair* (median over the R alternating pairs of the pair's ratio, which is "
             "robust to load that drifts over the run).\n")
    L.append("| scene | depth | spp/run | rays/spp (cam+cont+shadow) | OpenCL Mrays/s | native Mrays/s "
             "| OpenCL s/spp | native s/spp | ratio of medians | ratio per pair |")
    L.append("|---|---|---|---|---|---|---|---|---|---|")
    for j in results:
        s = j["summary"]
        r = j["ratio_opencl_over_native"]
        rays = j["runs_detail"]["cpu"][0]["rays"]
        spp = j["spp_per_run"]
        per_spp = (rays["camera"] + rays["continuation"] + rays["shadow"]) / spp
        L.append(f"| {j['name']} | {j['max_depth']} | {spp} | {per_spp / 1e3:.0f} k "
                 f"| {fmt_range(s['opencl']['mrays_per_second'], 3)} "
                 f"| {fmt_range(s['cpu']['mrays_per_second'], 3)} "
                 f"| {fmt_range(s['opencl']['seconds_per_spp'], 3)} "
                 f"| {fmt_range(s['cpu']['seconds_per_spp'], 3)} "
                 f"| **{r['of_medians']:.2f}** "
                 f"| {r['per_pair_summary']['median']:.2f} [{r['per_pair_summary']['min']:.2f}–"
                 f"{r['per_pair_summary']['max']:.2f}] |")
    L.append("")

    L.append("## Environment-sampling share of the frame\n")
    L.append("Two independent measurements, both side by side with the renders (see README.md, "
             "\"Environment-sampling share\"):\n")
    L.append("- **isolated**: right after each render, the frame's light samples are drawn again on "
             "their own, with the sampler dimensions the shade stage uses, on the same threads "
             "(native: all threads; OpenCL: `envmap_sample_reduce`, one sample per work-item, "
             "work-groups of 64, which also does the radiance lookup). Their number is exact at "
             "depth 1 (the camera rays that hit, found by running `etk_generate` and "
             "`etk_intersect`) and an upper bound at depth 5 (plus every continuation ray). "
             "Share = that time / the frame time of the render just before it. *sample* = "
             "`etk_env_sample` alone (the binary searches and the direction; the cost of "
             "generating the two sample values subtracted), *+values* includes it, *+lookup* also "
             "the radiance lookup in the sampled direction.")
    L.append("- **in situ**: each pair also renders the same spp with `--strategy uniform` (the "
             "light direction from `etk_sample_uniform_sphere` instead of `etk_env_sample`, no MIS "
             "weight; the rest of the shade stage unchanged). Shade-stage time saved / all stage "
             "time of the real render (native: thread time summed over the lanes; OpenCL: device "
             "time from profiling events, summed over the lanes -- on PoCL each lane's kernels "
             "run on a compute unit of its own, as a native lane runs on its thread).")
    L.append("- the whole shade stage's share (sample, BSDF evaluation and sampling, shading "
             "frame) is an upper bound.\n")
    L.append("Medians over the pairs.\n")
    L.append("| scene | depth | light samples/frame | isolated native: sample / +values / +lookup "
             "| isolated OpenCL: values+sample+lookup | in situ native | in situ OpenCL "
             "| shade stage, native / OpenCL |")
    L.append("|---|---|---|---|---|---|---|---|")
    for j in results:
        e = j["env_sampling"]
        ins_n = e.get("insitu_uniform_saving_native")
        ins_c = e.get("insitu_uniform_saving_opencl")
        L.append(f"| {j['name']} | {j['max_depth']} "
                 f"| {e['samples'] / 1e3:.0f} k{'' if e.get('samples_exact') else ' (bound)'} "
                 f"| {100 * e['share_native_sample_only']['median']:.1f}% / "
                 f"{100 * e['share_native_with_values']['median']:.1f}% / "
                 f"{100 * e['share_native_with_lookup']['median']:.1f}% "
                 f"| {100 * e['share_opencl']['median']:.1f}% "
                 f"| {'%.1f%%' % (100 * ins_n['median']) if ins_n else '–'} "
                 f"| {'%.1f%%' % (100 * ins_c['median']) if ins_c else '–'} "
                 f"| {100 * e['shade_stage_share_native']:.1f}% / "
                 f"{100 * e['shade_stage_share_opencl']:.1f}% |")
    L.append("")

    L.append("## OpenCL program build (kernels/wavefront.cl)\n")
    pb = results[0]["program_build"]
    L.append("| | program build | render of 2 spp (PoCL compiles work-group functions at the first) |")
    L.append("|---|---|---|")
    for label, key in [("cold: child process, empty ENVTRACE_CACHE_DIR and POCL_CACHE_DIR",
                        "cold_child"),
                       ("warm: child process, the same caches again", "warm_child")]:
        c = pb.get(key)
        if c:
            L.append(f"| {label} | {c['program_build_seconds']:.3f} s "
                     f"({'cached binary' if c['from_cache'] else 'compiled'}) "
                     f"| {c['render_seconds_2spp']:.3f} s |")
    builds = [j["program_build"]["warm_in_process"]["median"] for j in results]
    L.append(f"| warm: in process, normal cache (median over every renderer of every row) "
             f"| {statistics.median(builds) * 1e3:.1f} ms | – |")
    L.append(f"\nCold/warm measured once, in the first invocation ({results[0]['name']}, depth "
             f"{results[0]['max_depth']}); the cold render includes PoCL compiling each "
             "kernel's work-group function, the warm child loads them from POCL_CACHE_DIR.\n")

    L.append("## BVH (binned SAH, host)\n")
    L.append("| mesh (scene) | triangles | nodes | depth | SAH cost | build time (median of the "
             "invocations) |")
    L.append("|---|---|---|---|---|---|")
    by_mesh = {}
    for j in results:
        key = "ogre" if "ogre" in j["name"] else "stanford-bunny + ground quad"
        by_mesh.setdefault(key, []).append(j)
    for key, js in by_mesh.items():
        b = js[0]["bvh"]
        t = statistics.median(x["bvh"]["build_seconds"] for x in js)
        L.append(f"| {key} | {js[0]['triangles']} | {b['nodes']} | {b['depth']} "
                 f"| {b['sah_cost']:.1f} | {t * 1e3:.1f} ms ({len(js)} builds) |")
    L.append("")
    with open(args.out, "w") as f:
        f.write("\n".join(L))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
