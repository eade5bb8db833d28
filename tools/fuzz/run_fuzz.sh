#!/usr/bin/env bash
# Runs the libFuzzer harnesses (tools/fuzz) over their seed corpora and prints, per harness, the
# executions done and whether it found anything. Build first (docs/testing.md):
#   CXX=clang++ cmake -S . -B build-asan -DENVTRACE_FUZZ=ON && cmake --build build-asan
# usage: tools/fuzz/run_fuzz.sh [--build DIR] [--runs N | --seconds S] [--out DIR] [--keep-going]
#                               [HARNESS...]
#   --runs N       executions per harness (default 1000000; the seeds count towards them)
#   --seconds S    run each harness for S seconds instead
#   --out DIR      corpus growth, crash artifacts and logs (default BUILD/fuzz/runs); inputs that
#                  add coverage are kept in DIR/HARNESS/corpus and reused by the next run
#   --keep-going   libFuzzer's fork mode: record crashes, out-of-memory and timeouts under
#                  DIR/HARNESS/artifacts and go on instead of stopping at the first
#   HARNESS        fuzz_scene_json fuzz_obj_mtl fuzz_envmap fuzz_light_set fuzz_mesh (default: all five)
# Exit status 0 when no harness found anything. Extra libFuzzer flags: ENVTRACE_FUZZ_FLAGS.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$root/build-asan
limit=(-runs=1000000)
out=
keep=0
harnesses=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$(cd "$2" && pwd); shift 2 ;;
    --runs) limit=(-runs="$2"); shift 2 ;;
    --seconds) limit=(-max_total_time="$2"); shift 2 ;;
    --out) out=$2; shift 2 ;;
    --keep-going) keep=1; shift ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    -*) echo "run_fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
[ ${#harnesses[@]} -gt 0 ] || harnesses=(fuzz_scene_json fuzz_obj_mtl fuzz_envmap fuzz_light_set fuzz_mesh)
out=${out:-$build/fuzz/runs}

# Sanitizer settings shared with the test suite; leak suppressions name third-party code only.
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_stack_use_after_return=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/tools/sanitizers/lsan.supp:print_suppressions=0}

status=0
for h in "${harnesses[@]}"; do
  exe=$build/tools/fuzz/$h
  seeds=$build/fuzz/corpus/$h
  [ -x "$exe" ] || { echo "run_fuzz.sh: $exe not built (configure with -DENVTRACE_FUZZ=ON)" >&2; exit 2; }
  [ -d "$seeds" ] || { echo "run_fuzz.sh: no seed corpus $seeds (build target fuzz_corpus)" >&2; exit 2; }
  case "$h" in
    fuzz_envmap) max_len=32768 ;;
    *) max_len=8192 ;;
  esac
  mkdir -p "$out/$h/corpus" "$out/$h/artifacts"
  log=$out/$h/log.txt
  # fuzz_envmap: no leak checks. OpenImageIO 2.4 leaks an error string when libpng fails (finding
  # T1, tools/fuzz/README.md), in uninstrumented code whose stack the fast unwinder cannot follow
  # past libstdc++, so no suppression can name it.
  leaks=1
  [ "$h" != fuzz_envmap ] || leaks=0
  flags=("${limit[@]}" -detect_leaks=$leaks -max_len=$max_len -rss_limit_mb=2560 -malloc_limit_mb=2048 -timeout=30
         -print_final_stats=1 -artifact_prefix="$out/$h/artifacts/")
  [ $keep = 0 ] || flags+=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1)
  # shellcheck disable=SC2206
  flags+=(${ENVTRACE_FUZZ_FLAGS:-})
  start=$(date +%s)
  rc=0
  (cd "$out/$h" && ASAN_OPTIONS=$ASAN_OPTIONS:detect_leaks=$leaks "$exe" "${flags[@]}" corpus "$seeds") >"$log" 2>&1 || rc=$?
  secs=$(($(date +%s) - start))
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || true)
  [ -n "$execs" ] || execs=$(grep -o '^#[0-9]*' "$log" | tail -1 | tr -d '#' || true)
  found=$(find "$out/$h/artifacts" -type f | wc -l)
  if [ $rc -eq 72 ]; then
    echo "$h: ${execs:-?} executions in ${secs} s: interrupted, no finding so far (log $log)"
    status=1
  elif [ $rc -ne 0 ] || { [ $keep = 1 ] && [ "$found" -gt 0 ]; }; then
    echo "$h: ${execs:-?} executions in ${secs} s: FINDING (exit $rc; $found artifact(s) in $out/$h/artifacts; log $log)"
    grep -E 'ERROR: |SUMMARY: |runtime error|terminate called|==[0-9]+==' "$log" | head -20 || true
    status=1
  else
    echo "$h: ${execs:-?} executions in ${secs} s: no finding (log $log)"
  fi
done
exit $status
