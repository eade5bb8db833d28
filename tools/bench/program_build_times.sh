#!/usr/bin/env bash
# Cold and warm OpenCL program build times of kernels/envmap_sample.cl, through the real command:
# `envtrace sample` prints "program build X s (compiled|cached binary), N samples in Y ms".
#   cold: empty ENVTRACE_CACHE_DIR and empty POCL_CACHE_DIR (nothing cached anywhere)
#   warm: both caches populated by the previous run
# Y (the first launch) includes PoCL compiling the work-group function for the local size,
# which PoCL caches in POCL_CACHE_DIR. Prints every run and the medians.
# Usage: tools/bench/program_build_times.sh [runs=5] [envtrace binary=build/envtrace]
set -euo pipefail
cd "$(dirname "$0")/../.."
runs=${1:-5}
bin=${2:-build/envtrace}
map=${ENVTRACE_BENCH_MAP:-../shared/data/envmaps/royal_esplanade_1k.hdr}
[ -x "$bin" ] || { echo "program_build_times.sh: $bin not found; build first (tools/setup)" >&2; exit 1; }
[ -f "$map" ] || { echo "program_build_times.sh: $map not found (set ENVTRACE_BENCH_MAP)" >&2; exit 1; }

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# Runs envtrace once with the given caches; prints "<build s> <kind> <first launch ms>".
measure() {
  local out
  out=$(ENVTRACE_CACHE_DIR="$1" POCL_CACHE_DIR="$2" "$bin" sample "$map" -n 1024 -o "$tmp/points.png")
  echo "$out" | sed -n 's/.*program build \([0-9.]*\) s (\([a-z]*\)[a-z ]*), [0-9]* samples in \([0-9.]*\) ms.*/\1 \2 \3/p'
}

median() { sort -g | awk '{a[NR]=$1} END {if (NR % 2) print a[(NR+1)/2]; else print (a[NR/2]+a[NR/2+1])/2}'; }

: >"$tmp/cold" && : >"$tmp/warm"
for i in $(seq "$runs"); do
  et="$tmp/et$i" pc="$tmp/pocl$i"
  mkdir -p "$et" "$pc"
  read -r b kind launch < <(measure "$et" "$pc")
  echo "run $i cold: program build $b s ($kind), first launch $launch ms"
  echo "$b $launch" >>"$tmp/cold"
  read -r b kind launch < <(measure "$et" "$pc")
  echo "run $i warm: program build $b s ($kind), first launch $launch ms"
  echo "$b $launch" >>"$tmp/warm"
done
for w in cold warm; do
  printf '%s: median program build %s s, median first launch %s ms (%s runs)\n' "$w" \
    "$(cut -d' ' -f1 "$tmp/$w" | median)" "$(cut -d' ' -f2 "$tmp/$w" | median)" "$runs"
done
