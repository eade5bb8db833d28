#!/usr/bin/env bash
# Runs a test program with Oclgrind's checks on (OpenCL API errors, data races, uninitialised
# values; out-of-bounds accesses are always checked) and its report log at LOG, then fails if
# Oclgrind reported anything. With --expect REGEX (repeatable) it inverts: the log must match
# every REGEX (the control that proves reports are caught).
#
# usage: oclgrind_run.sh [--expect REGEX]... LOG COMMAND [ARGS...]
set -uo pipefail
expect=()
while [ "${1:-}" = "--expect" ]; do
  expect+=("$2")
  shift 2
done
log=$1
shift
rm -f "$log"
export OCLGRIND_LOG="$log" OCLGRIND_CHECK_API=1 OCLGRIND_DATA_RACES=1 OCLGRIND_UNINITIALIZED=1
# Oclgrind 21.10 cannot interpret llvm.experimental.noalias.scope.decl, which LLVM's inliner
# emits when it inlines a function returning a struct (sret), as the shared headers do: its
# builds run unoptimised. The arithmetic is the same IEEE single precision either way
# (contraction off), so the images still equal PoCL's bit for bit.
export OCLGRIND_BUILD_OPTIONS="${OCLGRIND_BUILD_OPTIONS:--cl-opt-disable}"
# Program binaries built under these options are cached apart (the cache key cannot see them).
export ENVTRACE_CACHE_DIR="${ENVTRACE_CACHE_DIR:-${TMPDIR:-/tmp}/envtrace-cache}/oclgrind${OCLGRIND_BUILD_OPTIONS//[^a-z]/_}"
out="$log.out"
"$@" 2>&1 | tee "$out"
rc=${PIPESTATUS[0]}
# Fatal simulator errors and API errors are printed rather than logged.
if [ ${#expect[@]} -eq 0 ] && grep -Eq "OCLGRIND FATAL|Oclgrind - OpenCL runtime error" "$out"; then
  echo "FAIL: Oclgrind printed a fatal or API error (above)"
  exit 1
fi
if [ ${#expect[@]} -gt 0 ]; then
  for re in "${expect[@]}"; do
    if ! grep -Eq "$re" "$log" 2>/dev/null; then
      echo "FAIL: Oclgrind's log $log does not report /$re/ for a kernel that has that error:"
      cat "$log" 2>/dev/null
      exit 1
    fi
  done
  echo "ok: Oclgrind reported every expected error ($(grep -c . "$log") log lines)"
  exit $rc
fi
if [ -s "$log" ]; then
  echo "FAIL: Oclgrind reported errors (log $log):"
  head -c 20000 "$log"
  exit 1
fi
echo "ok: no Oclgrind report (checks: API, data races, uninitialised values, bounds)"
exit $rc
