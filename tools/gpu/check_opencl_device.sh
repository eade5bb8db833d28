#!/usr/bin/env bash
# envtrace on a second OpenCL implementation with a GPU behind it (README, "A GPU"): NVIDIA's
# OpenCL driver, with PoCL on the same machine (when installed) and the native back end as the
# references. Needs only a built envtrace (a build without OpenImageIO will do: PFM in and out),
# optionally the test binaries, numpy, and the driver's libnvidia-opencl.so.1.
#
#   tools/gpu/check_opencl_device.sh ENVTRACE TEST_BIN_DIR|- OUT_DIR [PLATFORM]
#
# PLATFORM (default NVIDIA) is matched against the OpenCL platform names (ENVTRACE_CL_PLATFORM).
# Environment: SCENES, SPP (64), BENCH_SCENES (empty: none) choose the work; RENDERS=0 stops after
# the tests; PYTHON names a python3 with numpy.
# ENVTRACE_DATA must name the data folder (maps and meshes). Writes OUT_DIR/summary.txt (and a
# log per step); every image is compared in numpy by tools/gpu/compare_backends.py.
set -u
exe=$(realpath "$1")
tests=$2
out=$(realpath -m "$3")
platform=${4:-NVIDIA}
py=${PYTHON:-python3}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
mkdir -p "$out/img"
summary=$out/summary.txt
: >"$summary"
say() { echo "$*" | tee -a "$summary"; }

# The ICD loader reads the vendor list from OCL_ICD_VENDORS: the GPU driver's library beside
# whatever the system lists (PoCL).
vendors=$out/vendors
mkdir -p "$vendors"
nv=$(ldconfig -p | awk '/libnvidia-opencl\.so\.1 /{print $NF; exit}')
[ -n "$nv" ] && echo "$nv" >"$vendors/nvidia.icd"
cp /etc/OpenCL/vendors/*.icd "$vendors/" 2>/dev/null
export OCL_ICD_VENDORS=$vendors
export ENVTRACE_CACHE_DIR=$out/kernel-cache POCL_CACHE_DIR=$out/pocl-cache
say "== driver: $(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null)"
say "== envtrace devices --kernels"
"$exe" devices --kernels 2>&1 | tee -a "$summary"
has_pocl=0
"$exe" devices 2>/dev/null | grep -qi "portable computing" && has_pocl=1

# The test binaries (kernel against host, chi-square of every sampler, BVH against brute
# force, back end against back end) with the GPU as their OpenCL device.
if [ "$tests" != "-" ]; then
    say "== tests on $platform"
    mkdir -p "$out/tests"
    for t in "$tests"/*_test; do
        n=$(basename "$t")
        (cd "$out/tests" && ENVTRACE_CL_PLATFORM=$platform timeout "${TEST_TIMEOUT:-600}" "$t" \
            >"$out/tests/$n.log" 2>&1; echo "$n exit $?" >"$out/tests/$n.rc") &
        while [ "$(jobs -r | wc -l)" -ge 6 ]; do sleep 0.2; done
    done
    wait
    for t in "$out"/tests/*.rc; do
        n=$(basename "$t" .rc)
        say "$(cat "$t") $(grep -E '^\[  (PASSED|FAILED|SKIPPED) ' "$out/tests/$n.log" | tr '\n' ' ')"
        grep -E '^\[  FAILED  \] [A-Za-z]' "$out/tests/$n.log" | sed 's/^/    /' | tee -a "$summary" >/dev/null
    done
fi

# Renders: each scene at depth 1 and 5 on the GPU, on PoCL and natively, same seed and spp.
render() { # name scene depth backend platform seed
    local o=$out/img/$1.pfm
    ENVTRACE_CL_PLATFORM=$5 "$exe" render "$2" --spp "${SPP:-64}" --max-depth "$3" --backend "$4" \
        --seed "$6" -o "$o" --stats "$out/img/$1.json" >"$out/img/$1.log" 2>&1 ||
        say "FAILED: render $1 ($(tail -1 "$out/img/$1.log"))"
}
stat() { # json key
    "$py" -c "import json,sys; print(round(json.load(open(sys.argv[1]))[sys.argv[2]], 4))" "$1" "$2" 2>/dev/null
}
[ "${RENDERS:-1}" = 0 ] && exit 0
say "== renders: $platform / PoCL ($has_pocl) / native, ${SPP:-64} spp"
for s in ${SCENES:-default cornell_box bunny_grace bunny_esplanade bunny_overpass ogre matpreview glass mesh_formats interiors/window_room interiors/skylight_room}; do
    for d in 1 5; do
        n=$(echo "$s" | tr / _)_d$d
        render "$n.gpu" "$root/scenes/$s.json" $d opencl "$platform" 1
        render "$n.cpu" "$root/scenes/$s.json" $d cpu "" 1
        render "$n.cpu2" "$root/scenes/$s.json" $d cpu "" 2
        [ $has_pocl = 1 ] && render "$n.pocl" "$root/scenes/$s.json" $d opencl portable 1
        line="$n: gpu $(stat "$out/img/$n.gpu.json" mrays_per_second) Mrays/s build $(stat "$out/img/$n.gpu.json" program_build_seconds) s (cached $(stat "$out/img/$n.gpu.json" program_from_cache)); cpu $(stat "$out/img/$n.cpu.json" mrays_per_second) Mrays/s"
        [ $has_pocl = 1 ] && line="$line; pocl $(stat "$out/img/$n.pocl.json" mrays_per_second) Mrays/s"
        say "$line"
        say "   gpu vs cpu:  $("$py" "$here/compare_backends.py" $d "$out/img/$n.cpu.pfm" "$out/img/$n.gpu.pfm" "$out/img/$n.cpu.pfm" "$out/img/$n.cpu2.pfm" 2>&1)"
        [ $has_pocl = 1 ] && say "   gpu vs pocl: $("$py" "$here/compare_backends.py" $d "$out/img/$n.pocl.pfm" "$out/img/$n.gpu.pfm" "$out/img/$n.cpu.pfm" "$out/img/$n.cpu2.pfm" 2>&1)"
        [ $has_pocl = 1 ] && say "   pocl vs cpu: $("$py" "$here/compare_backends.py" $d "$out/img/$n.cpu.pfm" "$out/img/$n.pocl.pfm" "$out/img/$n.cpu.pfm" "$out/img/$n.cpu2.pfm" 2>&1)"
    done
done

# Throughput against the native back end on all cores, alternating (envtrace bench).
say "== envtrace bench, $platform against native"
for s in ${BENCH_SCENES-bunny_grace bunny_esplanade}; do
    for d in 1 5; do
        say "$s depth $d: $(ENVTRACE_CL_PLATFORM=$platform "$exe" bench "$root/scenes/$s.json" --max-depth $d --runs 3 --target-seconds 1 2>&1 | tail -4 | tr '\n' ' ')"
    done
done
