#!/bin/sh
# Time and peak memory of loading a 16384x8192 map and rendering a tiny frame with it (the
# input-hardening issue's large legal input). The map is generated in a temporary folder from
# royal_esplanade_1k (oiiotool, from tools/setup's OpenImageIO) and removed afterwards.
# Usage: tools/bench/measure_16k_map.sh [build/envtrace] [hdr|exr] [cpu|opencl]
set -eu
exe=${1:-build/envtrace}
format=${2:-hdr}
backend=${3:-cpu}
data=${ENVTRACE_DATA:-$(dirname "$0")/../../../shared/data}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ "$format" = exr ]; then
    oiiotool "$data/envmaps/royal_esplanade_1k.hdr" --resize 16384x8192 -d float \
        --compression zip -o "$tmp/big.exr"
else
    oiiotool "$data/envmaps/royal_esplanade_1k.hdr" --resize 16384x8192 -o "$tmp/big.hdr"
fi
cat > "$tmp/scene.json" <<JSON
{"camera": {"eye": [0, 1, 4], "target": [0, 0, 0]}, "film": {"width": 64, "height": 32},
 "environment": {"map": "big.$format"}, "shapes": [{"type": "sphere", "radius": 1}],
 "render": {"spp": 1}}
JSON
/usr/bin/time -v "$exe" render "$tmp/scene.json" --backend "$backend" -o "$tmp/out.exr" 2>&1 |
    grep -E "distribution in|Elapsed|Maximum resident|User time|System time|error"
