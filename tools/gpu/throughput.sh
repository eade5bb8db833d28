#!/usr/bin/env bash
# Throughput on a GPU (docs/devices.md): rays a second end to end (camera, continuation and shadow
# rays over the render's seconds) on a 1.1M-triangle bunny at 2048x2048 (and 4096x4096) at depth
# 1 and 5, the paths in flight, the film's sums on the device against the host's fold and the
# queue sizes kept on the device against the host's reads (the films compared bit for bit), and
# the native back end on the machine's CPU threads for the ratio; then the learning strategies'
# rays a second against mis's in the window room.
#
#   tools/gpu/throughput.sh ENVTRACE OUT_DIR [PLATFORM]
#
# ENVTRACE_DATA must name the data folder (a bundle's PFM maps will do: tools/gpu/make_bundle.sh);
# python3 with numpy makes the mesh (tools/bench/subdivide_mesh.py). Writes OUT_DIR/summary.txt
# and each render's --stats JSON. About two minutes on an H200. SIZE (2048), BIG (4096) and ROOM
# (1024) set the films' sides (small ones to try the script on a CPU device).
set -u
exe=$(realpath "$1")
out=$(realpath -m "$2")
platform=${3:-NVIDIA}
root=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out/stats"
. "$root/tools/gpu/common.sh"
export ENVTRACE_CACHE_DIR=$out/kernel-cache
python3 "$root/tools/bench/subdivide_mesh.py" "$ENVTRACE_DATA/meshes/stanford-bunny.obj" 2 \
    "$out/bunny1m.ply" >/dev/null || exit 1
python3 - "$root/scenes/bunny_esplanade.json" "$out/bunny1m.json" "${SIZE:-2048}" <<'PY' || exit 1
import json, sys
s = json.load(open(sys.argv[1]))
s["shapes"][1]["file"] = "bunny1m.ply"
s["film"] = {"width": int(sys.argv[3]), "height": int(sys.argv[3])}
s["render"].update(strategy="mis")
json.dump(s, open(sys.argv[2], "w"), indent=1)
PY
scene=$out/bunny1m.json
render() { # name backend args...: one render, its line in the summary
    local n=$1 b=$2
    shift 2
    ENVTRACE_CL_PLATFORM=$platform "$exe" render "$scene" --backend "$b" "$@" -o "$out/$n.pfm" \
        --stats "$out/stats/$n.json" >"$out/$n.log" 2>&1 || { say "FAILED $n: $(tail -1 "$out/$n.log")"; return; }
    say "$n: $(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); t=sum(d['rays'].values()); s=sum(d['stage_seconds'].values()); print('%.1f Mrays/s, render %.3f s, stage time %.3f s, film sums on the device: %s, queue counts on the device: %s' % (t / d['render_seconds'] / 1e6, d['render_seconds'], s, d.get('film_sums_on_device'), d.get('queue_counts_on_device')))" "$out/stats/$n.json")"
}
same() { cmp -s "$out/$1.pfm" "$out/$2.pfm" && say "  $1 = $2, bit for bit" || say "  $1 and $2 DIFFER"; }
say "== $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null); $(nproc) CPU threads"
render warm opencl --spp 1 --max-depth 1 # the program built and cached
for d in 1 5; do
    for k in 1 2 3; do render "d${d}_$k" opencl --spp 16 --max-depth $d; done
    for m in host device; do render "d${d}_sums_$m" opencl --spp 8 --max-depth $d --film-sums $m; done
    same "d${d}_sums_host" "d${d}_sums_device"
    for m in host device; do render "d${d}_counts_$m" opencl --spp 8 --max-depth $d --queue-counts $m; done
    same "d${d}_counts_host" "d${d}_counts_device"
    render "d${d}_native" cpu --spp 2 --max-depth $d
done
for p in 1048576 2097152; do render "d5_paths_$p" opencl --spp 16 --max-depth 5 --paths $p; done
render d5_big opencl --spp 4 --max-depth 5 --width "${BIG:-4096}" --height "${BIG:-4096}"
# The learning strategies' rays a second against mis's in a room lit through a window (their
# records are summed on the device; the host reads them only at the tables' updates): the tables
# throughout, auto as the user gets it, and mis, at depth 5 on a film of ROOM (1024) pixels a side;
# 64 samples, so that the learning passes and the steady passes after them are both in it.
scene=$root/scenes/interiors/window_room.json
room=${ROOM:-1024}
for st in mis auto visibility; do
    extra=()
    [ "$st" = visibility ] && extra=(--guide-verdict off)
    render "room_$st" opencl --spp 64 --max-depth 5 --strategy "$st" --width "$room" \
        --height "$room" "${extra[@]}"
done
rm -f "$out"/*.pfm
