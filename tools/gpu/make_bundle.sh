#!/usr/bin/env bash
# Everything tools/gpu/check_opencl_device.sh needs on a GPU machine that has a driver and
# python3 with numpy but none of envtrace's libraries (docs/devices.md), in one folder:
#   bin/envtrace     a build without OpenImageIO (PFM only), -march=x86-64-v3, static libstdc++
#   tests.tar.xz     the test binaries of that build (kernel against host, chi-square, BVH, back ends)
#   lib/             the shared libraries it still needs (tinyobjloader, tinygltf, stb, ICD loader)
#   data.tar.xz      the maps of ENVTRACE_DATA converted to PFM under their own names, the meshes
#
#   tools/gpu/make_bundle.sh BUNDLE_DIR [BUILD_DIR (default build-gpu)]
# Then, on the GPU machine, from a checkout with BUNDLE_DIR beside it:
#   tar -xJf B/data.tar.xz -C /tmp && tar -xJf B/tests.tar.xz -C /tmp
#   LD_LIBRARY_PATH=B/lib ENVTRACE_DATA=/tmp/data tools/gpu/check_opencl_device.sh B/bin/envtrace /tmp/tests OUT
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
bundle=$(realpath -m "$1")
build=$(realpath -m "${2:-$root/build-gpu}")
data=${ENVTRACE_DATA:-$root/../shared/data}
host_envtrace=$root/build/envtrace # the full build reads every format, for the conversion
[ -x "$host_envtrace" ] || { echo "make_bundle.sh: $host_envtrace: build envtrace first (README, 'Set up and test')" >&2; exit 1; }
[ -d "$data/envmaps" ] || { echo "make_bundle.sh: $data/envmaps: no data folder (set ENVTRACE_DATA)" >&2; exit 1; }
mkdir -p "$bundle/bin" "$bundle/lib"

cmake -S "$root" -B "$build" -DENVTRACE_OPENIMAGEIO=OFF -DENVTRACE_MARCH=x86-64-v3 \
    -DENVTRACE_MPI=OFF -DENVTRACE_BUILD_BENCHMARKS=OFF \
    -DCMAKE_EXE_LINKER_FLAGS="-static-libstdc++ -static-libgcc" >/dev/null
# The tests of the device code that this build has (those that include OpenImageIO it has not).
targets=$(make -C "$build" help | sed -n 's/^\.\.\. //p')
tests=$(sed -n 's/^envtrace_test(\(kernels\|prepare\|opencl\|render\)\/\([a-z_]*\)).*/\2/p' \
    "$root/tests/CMakeLists.txt" | grep -Fx "$targets")
make -C "$build" -j"$(nproc)" envtrace $tests >/dev/null
cp "$build/envtrace" "$bundle/bin/" && strip "$bundle/bin/envtrace"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/tests" "$tmp/data/envmaps"
for t in $tests; do [ -x "$build/tests/$t" ] && cp "$build/tests/$t" "$tmp/tests/"; done
strip "$tmp/tests"/*
tar -C "$tmp" -cJf "$bundle/tests.tar.xz" tests
for f in "$data"/envmaps/*; do
    "$host_envtrace" convert "$f" "$tmp/map.pfm" >/dev/null
    mv "$tmp/map.pfm" "$tmp/data/envmaps/$(basename "$f")"
done
cp -r "$data/meshes" "$tmp/data/"
mkdir -p "$tmp/data/reference/matpreview"
cp "$data"/reference/matpreview/*.obj "$tmp/data/reference/matpreview/" 2>/dev/null || true
tar -C "$tmp" -cJf "$bundle/data.tar.xz" data
ldd "$bundle/bin/envtrace" | awk '/libtinyobjloader|libtinygltf|libstb|libOpenCL/{print $3}' |
    xargs -I{} cp -L {} "$bundle/lib/"
du -sh "$bundle"/*
