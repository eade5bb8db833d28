"""Shared helpers of the experiment scripts: where envtrace and the data are, scene variants written
to temporary JSON files, cached references (tools/make_reference), renders and comparisons.

Every script takes --tiny (small images and sample counts: the ctest smoke run) and --out DIR."""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def envtrace():
    exe = os.environ.get("ENVTRACE_EXE", os.path.join(REPO, "build", "envtrace"))
    if not os.path.exists(exe):
        sys.exit(f"experiments: {exe} not found: build first (tools/setup) or set ENVTRACE_EXE")
    return exe


def data_dir():
    d = os.environ.get("ENVTRACE_DATA", "").split(":")[0] or os.path.join(REPO, "..", "shared", "data")
    if not os.path.isdir(os.path.join(d, "envmaps")):
        print(f"experiments: no shared data at {d}: set ENVTRACE_DATA (skipping)", file=sys.stderr)
        sys.exit(77)
    return os.path.abspath(d)


def parser(description):
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--tiny", action="store_true", help="small sizes: a quick end-to-end check")
    p.add_argument("--out", default=None, help="output folder (default docs/figures/<experiment>)")
    return p


def out_dir(args, name):
    d = args.out or os.path.join(REPO, "docs", "figures", name)
    os.makedirs(d, exist_ok=True)
    return d


def run(cmd, quiet=True):
    env = dict(os.environ)
    env.setdefault("ENVTRACE_DATA", data_dir())
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    if r.returncode != 0:
        sys.exit(f"experiments: command failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr}")
    if not quiet:
        print(r.stdout, end="")
    return r.stdout


def scene_variant(base, path, width, height, envmap=None, roughness=None, material=None):
    """Writes scenes/<base>.json with a film size, optionally another map and the bunny's and the
    ground's material replaced (Cook-Torrance of the given roughness) to `path`."""
    with open(os.path.join(REPO, "scenes", base + ".json")) as f:
        s = json.load(f)
    s["film"] = {"width": width, "height": height}
    if envmap:
        s["environment"]["map"] = os.path.join(data_dir(), "envmaps", envmap)
    for sh in s["shapes"]:
        if "file" in sh and not os.path.isabs(sh["file"]):
            sh["file"] = os.path.join(data_dir(), sh["file"])
    if not os.path.isabs(s["environment"]["map"]):
        s["environment"]["map"] = os.path.join(data_dir(), s["environment"]["map"])
    if material is not None or roughness is not None:
        m = dict(material or {})
        if roughness is not None:
            m["roughness"] = roughness
        s["materials"] = {"ground": m, "bunny": m}
    s.pop("output", None)
    with open(path, "w") as f:
        json.dump(s, f, indent=1)
    return path


def reference(scene, spp, cache=None):
    """The cached high-spp reference of `scene` (tools/make_reference)."""
    cmd = [sys.executable, os.path.join(REPO, "tools", "make_reference"), scene, "--spp", str(spp)]
    if cache:
        cmd += ["--cache", cache]
    return run(cmd).strip().splitlines()[-1]


def render(scene, out, extra):
    stats = out + ".stats.json"
    run([envtrace(), "render", scene, "-o", out, "--backend", "cpu", "--stats", stats] + extra)
    with open(stats) as f:
        return json.load(f)


def compare(image, ref):
    js = image + ".cmp.json"
    run([envtrace(), "compare", image, ref, "--json", js])
    with open(js) as f:
        return json.load(f)


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    print(f"wrote {path}")


def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def relative_variance(a, b):
    """The two-seed estimate of the per-pixel relative variance of one render, from two renders a
    and b of equal spp and different seeds (arrays of equal shape: channels, or one luminance
    channel): mean((a - b)^2 / 2 / (m^2 + (0.01 mean m)^2)), m = (a + b) / 2; the 1% of the mean
    keeps black pixels from dividing by zero."""
    m = 0.5 * (a + b)
    return float(((a - b) ** 2 / 2 / (m ** 2 + (0.01 * m.mean()) ** 2)).mean())


def read_pfm(path):
    """A PFM image as float64 (h, w, channels), top row first (PFM stores the bottom row first)."""
    import numpy as np
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(h, w, 3 if kind == b"PF" else 1)[::-1].astype(np.float64)


def tmpdir(name):
    """A fresh scratch folder for the renders (build/experiments/NAME-*; never committed)."""
    parent = os.path.join(REPO, "build", "experiments")
    os.makedirs(parent, exist_ok=True)
    return tempfile.mkdtemp(prefix=name + "-", dir=parent)
