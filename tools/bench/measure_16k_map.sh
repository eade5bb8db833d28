#!/bin/sh
# Time and peak memory of loading a 16384x8192 map and rendering a tiny frame with it (the
# input-hardening issue's large legal input). The map is generated from royal_esplanade_1k
# (oiiotool, from tools/setup's OpenImageIO) in a temporary folder and removed afterwards, or in
# $MAPDIR, where it is kept and reused (generating it takes minutes on a loaded machine).
# Usage: [RUNS=3] [MAPDIR=dir] tools/bench/measure_16k_map.sh [exe[,exe2...]] [hdr|exr] [cpu|opencl]
# Several executables are run in turn, RUNS rounds, so that they see the same load; the last
# lines give each one's median wall time, CPU time (user + system) and peak RSS.
set -eu
exes=${1:-build/envtrace}
format=${2:-hdr}
backend=${3:-cpu}
runs=${RUNS:-1}
data=${ENVTRACE_DATA:-$(dirname "$0")/../../../shared/data}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
dir=${MAPDIR:-$tmp}
mkdir -p "$dir"
if [ ! -f "$dir/big.$format" ]; then
    if [ "$format" = exr ]; then
        oiiotool "$data/envmaps/royal_esplanade_1k.hdr" --resize 16384x8192 -d float \
            --compression zip -o "$dir/big.exr"
    else
        oiiotool "$data/envmaps/royal_esplanade_1k.hdr" --resize 16384x8192 -o "$dir/big.hdr"
    fi
fi
cat > "$tmp/scene.json" <<JSON
{"camera": {"eye": [0, 1, 4], "target": [0, 0, 0]}, "film": {"width": 64, "height": 32},
 "environment": {"map": "$(cd "$dir" && pwd)/big.$format"}, "shapes": [{"type": "sphere", "radius": 1}],
 "render": {"spp": 1}}
JSON
run=1
while [ "$run" -le "$runs" ]; do
    for exe in $(echo "$exes" | tr ',' ' '); do
        /usr/bin/time -f "time: %e %U %S %M" "$exe" render "$tmp/scene.json" --backend "$backend" \
            -o "$tmp/out.exr" > "$tmp/log" 2>&1 || { cat "$tmp/log"; exit 1; }
        dist=$(sed -n 's/.*distribution in \([0-9.]*\) ms.*/\1/p' "$tmp/log")
        set -- $(sed -n 's/^time: //p' "$tmp/log")
        echo "$exe run $run: wall $1 s, user $2 s, sys $3 s, peak RSS $(($4 / 1024)) MB, distribution in $dist ms"
        echo "$exe $1 $2 $3 $4" >> "$tmp/all"
    done
    run=$((run + 1))
done
for exe in $(echo "$exes" | tr ',' ' '); do
    awk -v e="$exe" 'BEGIN { n = 0 } $1 == e { w[n] = $2; c[n] = $3 + $4; m[n] = $5; n++ }
        function med(a, n,   i, j, t) { for (i = 0; i < n; i++) for (j = i + 1; j < n; j++)
            if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
            return n % 2 ? a[(n - 1) / 2] : (a[n / 2 - 1] + a[n / 2]) / 2 }
        END { printf "%s: median of %d: wall %.2f s, CPU %.2f s, peak RSS %d MB\n", e, n,
              med(w, n), med(c, n), med(m, n) / 1024 }' "$tmp/all"
done
