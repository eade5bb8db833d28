#!/usr/bin/env bash
# envtrace on a second OpenCL implementation with a GPU behind it (docs/devices.md): NVIDIA's
# OpenCL driver, with PoCL on the same machine (when installed) and the native back end as the
# references. Needs only a built envtrace (a build without OpenImageIO will do: PFM in and out),
# optionally the test binaries, numpy, and the driver's libnvidia-opencl.so.1.
#
#   tools/gpu/check_opencl_device.sh ENVTRACE TEST_BIN_DIR|- OUT_DIR [PLATFORM]
#
# PLATFORM (default NVIDIA) is matched against the OpenCL platform names (ENVTRACE_CL_PLATFORM).
# Environment: SCENES, SPP (64), STRATEGIES (the scene's own; e.g. "mis visibility" renders each
# scene with each), BATCH_SCENES and BATCH_SPP (256: --light-batch on against off),
# BENCH_SCENES choose the work (each set but empty: none); TEST_JOBS (6) test binaries run at
# once, each for at most TEST_TIMEOUT seconds (600); PYTHON names a python3 with numpy.
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
. "$here/common.sh"
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
        while [ "$(jobs -r | wc -l)" -ge "${TEST_JOBS:-6}" ]; do sleep 0.2; done
    done
    wait
    for t in "$out"/tests/*.rc; do
        n=$(basename "$t" .rc)
        say "$(cat "$t") $(grep -E '^\[  (PASSED|FAILED|SKIPPED) ' "$out/tests/$n.log" | tr '\n' ' ')"
        grep -E '^\[  FAILED  \] [A-Za-z]' "$out/tests/$n.log" | sed 's/^/    /' | tee -a "$summary" >/dev/null
    done
fi

# Renders: each scene at depth 1 and 5 on the GPU, on PoCL and natively, same seed and spp.
render() { # name scene depth backend platform seed [strategy]
    local o=$out/img/$1.pfm
    ENVTRACE_CL_PLATFORM=$5 "$exe" render "$2" --spp "${SPP:-64}" --max-depth "$3" --backend "$4" \
        --seed "$6" ${7:+--strategy "$7"} -o "$o" --stats "$out/img/$1.json" >"$out/img/$1.log" 2>&1 ||
        say "FAILED: render $1 ($(tail -1 "$out/img/$1.log"))"
}
stat() { # json key
    "$py" -c "import json,sys; print(round(json.load(open(sys.argv[1]))[sys.argv[2]], 4))" "$1" "$2" 2>/dev/null
}
say "== renders: $platform / PoCL ($has_pocl) / native, ${SPP:-64} spp"
for s in ${SCENES-default cornell_box bunny_grace bunny_esplanade bunny_overpass ogre matpreview glass mesh_formats interiors/window_room interiors/skylight_room}; do
  for st in ${STRATEGIES:-scene}; do
    [ "$st" = scene ] && st=
    for d in 1 5; do
        n=$(echo "$s" | tr / _)${st:+_$st}_d$d
        render "$n.gpu" "$root/scenes/$s.json" $d opencl "$platform" 1 $st
        render "$n.cpu" "$root/scenes/$s.json" $d cpu "" 1 $st
        render "$n.cpu2" "$root/scenes/$s.json" $d cpu "" 2 $st
        [ $has_pocl = 1 ] && render "$n.pocl" "$root/scenes/$s.json" $d opencl portable 1 $st
        line="$n: gpu $(stat "$out/img/$n.gpu.json" mrays_per_second) Mrays/s build $(stat "$out/img/$n.gpu.json" program_build_seconds) s (cached $(stat "$out/img/$n.gpu.json" program_from_cache)); cpu $(stat "$out/img/$n.cpu.json" mrays_per_second) Mrays/s"
        [ $has_pocl = 1 ] && line="$line; pocl $(stat "$out/img/$n.pocl.json" mrays_per_second) Mrays/s"
        say "$line"
        say "   gpu vs cpu:  $("$py" "$here/compare_backends.py" $d "$out/img/$n.cpu.pfm" "$out/img/$n.gpu.pfm" "$out/img/$n.cpu.pfm" "$out/img/$n.cpu2.pfm" 2>&1)"
        [ $has_pocl = 1 ] && say "   gpu vs pocl: $("$py" "$here/compare_backends.py" $d "$out/img/$n.pocl.pfm" "$out/img/$n.gpu.pfm" "$out/img/$n.cpu.pfm" "$out/img/$n.cpu2.pfm" 2>&1)"
        [ $has_pocl = 1 ] && say "   pocl vs cpu: $("$py" "$here/compare_backends.py" $d "$out/img/$n.cpu.pfm" "$out/img/$n.pocl.pfm" "$out/img/$n.cpu.pfm" "$out/img/$n.cpu2.pfm" 2>&1)"
    done
  done
done

# Light samples in batches (--light-batch on) against one at a time (off) on this device, with
# the paper's estimator (the scenes may name the visibility strategy, which has no batches):
# render seconds and the shade + sample_lights stages' device seconds, alternating; the films
# must be equal bit for bit. auto picks off on a GPU (RenderSettings::light_batch).
batch_stat() { # json: render seconds, stage seconds of shade_hits + sample_lights
    "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); s=d['stage_seconds']; print('%.3f/%.3f' % (d['render_seconds'], s.get('shade_hits',0)+s.get('sample_lights',0)))" "$1" 2>/dev/null
}
[ -n "${BATCH_SCENES-bunny_esplanade bunny_grace}" ] && say "== --light-batch on / off on $platform: render s / shade+sample_lights device s, ${BATCH_SPP:-256} spp"
for s in ${BATCH_SCENES-bunny_esplanade bunny_grace}; do
    for d in 1 5; do
        line="$s depth $d:"
        ENVTRACE_CL_PLATFORM=$platform "$exe" render "$root/scenes/$s.json" --spp 1 --max-depth $d \
            --strategy mis --backend opencl -o "$out/batch_warm.pfm" >/dev/null 2>&1 # the program built and cached
        for r in 1 2 3; do
            for m in on off; do
                ENVTRACE_CL_PLATFORM=$platform "$exe" render "$root/scenes/$s.json" --spp "${BATCH_SPP:-256}" \
                    --max-depth $d --strategy mis --backend opencl --light-batch $m -o "$out/batch_$m.pfm" \
                    --stats "$out/batch_$m.json" >/dev/null 2>&1 || line="$line FAILED($m)"
                line="$line $m $(batch_stat "$out/batch_$m.json")"
            done
            cmp -s "$out/batch_on.pfm" "$out/batch_off.pfm" && line="$line (same bits);" || line="$line (FILMS DIFFER);"
        done
        say "$line"
    done
done

# Throughput against the native back end on all cores, alternating (envtrace bench), of the
# paper's estimator whatever the scene names (comparable across versions).
say "== envtrace bench, $platform against native"
for s in ${BENCH_SCENES-bunny_grace bunny_esplanade}; do
    for d in 1 5; do
        say "$s depth $d: $(ENVTRACE_CL_PLATFORM=$platform "$exe" bench "$root/scenes/$s.json" --strategy mis --max-depth $d --runs 3 --target-seconds 1 2>&1 | tail -4 | tr '\n' ' ')"
    done
done
