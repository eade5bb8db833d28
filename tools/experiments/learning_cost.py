#!/usr/bin/python3
"""What a learning strategy's learning costs in a short render: for each scene and seed, renders of
64, 136 and 200 samples (render_seconds of the stats: no loading or writing). The two longer ones
learn the same passes (a sample count more than twice the passes learnt keeps the learning to its
end, 64 passes: host/lib/render/visibility_learning.cpp), so T200 - T136 is 64 steady passes, and the
learning's share of the 64-sample render -- its learning passes' extra cost, the table updates,
the verdict's measuring passes -- is (T64 - (T200 - T136)) / T64. Reported per scene as the median
over the seeds, and the median and range over the scenes. Beside it, the same share measured
inside the 64-sample render alone (its stats: learning_seconds of its L learning passes,
verdict_seconds, and the 64 - L passes after them as the steady ones): (T64 - 64 x steady) / T64,
free of the drift between three processes that moves the first by several points a seed. With
several executables (--exes, e.g.
the build before and after a change), each render runs on each in turn, so that a slower spell of
a shared host falls on all of them.

    tools/experiments/learning_cost.py --scenes ROOM.json ... [--seeds 3] [--strategy auto]
        [--exes A B]

writes docs/figures/learning_cost/learning_cost.{md,csv}."""
import json
import os
import statistics
import tempfile

import common
from efficiency import file_scene, scene_names

SAMPLES = (64, 136, 200)


def render_stats(exe, scene, spp, seed, strategy, tmp):
    out = os.path.join(tmp, "lc.pfm")
    stats = out + ".stats.json"
    common.run([exe, "render", scene, "-o", out, "--backend", "cpu", "--spp", str(spp), "--seed",
                str(seed), "--strategy", strategy, "--stats", stats])
    with open(stats) as f:
        return json.load(f)


def share_in_run(stats):
    """(T - n x steady) / T of one render: its steady passes timed beside its learning passes."""
    learning = stats.get("auto") or stats.get("visibility") or {}
    n, passes = stats["spp"], learning.get("learning_passes", 0)
    if not learning or passes >= n:
        return float("nan")
    t = float(stats["render_seconds"])
    steady = (t - learning["learning_seconds"] - learning["verdict_seconds"]) / (n - passes)
    return (t - n * steady) / t


def main():
    p = common.parser(__doc__.split("\n\n")[0])
    p.add_argument("--scenes", nargs="+", default=None, help="scene files (default: window_room)")
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--strategy", default="auto")
    p.add_argument("--exes", nargs="+", default=None, help="envtrace executables to compare")
    args = p.parse_args()
    common.data_dir()
    out = common.out_dir(args, "learning_cost")
    exes = args.exes or [common.envtrace()]
    scenes = args.scenes or [os.path.join(common.REPO, "scenes", "interiors", "window_room.json")]
    size = (32, 24) if args.tiny else None
    seeds = 1 if args.tiny else args.seeds
    rows, share, in_run = [], {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for path, name in zip(scenes, scene_names(scenes)):
            name, scene = file_scene(path, tmp, size, name)
            for seed in range(1, seeds + 1):
                st = {(e, n): render_stats(exes[e], scene, n, seed, args.strategy, tmp)
                      for n in SAMPLES for e in range(len(exes))}
                for e in range(len(exes)):
                    t64, t136, t200 = (float(st[(e, n)]["render_seconds"]) for n in SAMPLES)
                    s = (t64 - (t200 - t136)) / t64
                    r = share_in_run(st[(e, 64)])
                    share.setdefault((e, name), []).append(s)
                    in_run.setdefault((e, name), []).append(r)
                    rows.append([exes[e], name, seed, t64, t136, t200, round(s, 4), round(r, 4)])
                    print(f"{name:<16} seed {seed} exe {e}: T64 {t64:.3f} s, 64 steady passes "
                          f"{t200 - t136:.3f} s, learning share {s:.3f} (in the run {r:.3f})",
                          flush=True)
    common.write_csv(os.path.join(out, "learning_cost.csv"),
                     ["exe", "scene", "seed", "t64", "t136", "t200", "learning_share",
                      "share_in_run"], rows)
    names = sorted({n for _, n in share})
    lines = [f"Learning's share of a 64-sample `{args.strategy}` render, median over {seeds} "
             "seed(s): (T64 - (T200 - T136)) / T64, and in brackets the same share inside the "
             "64-sample render (its steady passes timed beside its learning passes).", "",
             "| scene | " + " | ".join(f"exe {e}" for e in range(len(exes))) + " |",
             "|---|" + "---|" * len(exes)]
    for n in names:
        lines.append(f"| {n} | " + " | ".join(
            f"{statistics.median(share[(e, n)]):.3f} ({statistics.median(in_run[(e, n)]):.3f})"
            for e in range(len(exes))) + " |")
    for e in range(len(exes)):
        for label, table in (("", share), (" in the run", in_run)):
            med = [statistics.median(table[(e, n)]) for n in names]
            lines.append(f"\nexe {e} ({exes[e]}){label}: median {statistics.median(med):.3f}, "
                         f"range {min(med):.3f}-{max(med):.3f}")
    with open(os.path.join(out, "learning_cost.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
