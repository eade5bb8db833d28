#!/usr/bin/python3
"""Runs every experiment (pass --tiny for the quick end-to-end check ctest runs)."""
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPTS = ["fig5_roughness.py", "fig6_points.py", "fig8_lights.py", "ld_vs_random.py",
           "precompute_times.py", "efficiency.py", "split_ceiling.py", "roulette_depth.py",
           "learning_cost.py"]

if __name__ == "__main__":
    args = sys.argv[1:]
    out = None
    if "--out" in args:
        i = args.index("--out")
        out = args[i + 1]
        args = args[:i] + args[i + 2:]
    for s in SCRIPTS:
        extra = ["--out", os.path.join(out, s.split(".")[0])] if out else []
        print(f"== {s}", flush=True)
        r = subprocess.run([sys.executable, os.path.join(HERE, s)] + args + extra)
        if r.returncode == 77:
            sys.exit(77)  # no shared data: ctest reports a skip
        if r.returncode != 0:
            sys.exit(f"run_all: {s} failed ({r.returncode})")
