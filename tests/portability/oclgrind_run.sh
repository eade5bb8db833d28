#!/usr/bin/env bash
# Runs a test program with Oclgrind's checks on (OpenCL API errors, data races, uninitialised
# values; out-of-bounds accesses are always checked), keeps every report in LOG, then fails if
# Oclgrind reported anything. With --expect REGEX (repeatable) it inverts: the reports must match
# every REGEX (the control that proves reports are caught). --no-uninitialized leaves that one
# check off (see tests/portability/CMakeLists.txt for where and why).
#
# usage: oclgrind_run.sh [--expect REGEX]... [--no-uninitialized] LOG COMMAND [ARGS...]
#
# Reports are read from the program's stderr, not from OCLGRIND_LOG: Oclgrind reopens (truncates)
# its log file for every context a process creates, so a program that renders on several
# contexts kept only the last one's reports there, and it stops reporting after
# OCLGRIND_MAX_ERRORS (1000) per process, so a flood in one test silenced the others. Both hid
# real reports until this script changed.
set -uo pipefail
expect=()
uninit=1
while :; do
  case "${1:-}" in
  --expect) expect+=("$2"); shift 2 ;;
  --no-uninitialized) uninit=0; shift ;;
  *) break ;;
  esac
done
log=$1
shift
rm -f "$log"
unset OCLGRIND_LOG
export OCLGRIND_CHECK_API=1 OCLGRIND_DATA_RACES=1 OCLGRIND_UNINITIALIZED=$uninit
export OCLGRIND_MAX_ERRORS="${OCLGRIND_MAX_ERRORS:-100000}"
# Oclgrind 21.10 cannot interpret llvm.experimental.noalias.scope.decl, which LLVM's inliner
# emits when it inlines a function returning a struct (sret), as the shared headers do: its
# builds run unoptimised. The arithmetic is the same IEEE single precision either way
# (contraction off), so the images still equal PoCL's bit for bit.
export OCLGRIND_BUILD_OPTIONS="${OCLGRIND_BUILD_OPTIONS:--cl-opt-disable}"
# Program binaries built under these options are cached apart (the cache key cannot see them).
export ENVTRACE_CACHE_DIR="${ENVTRACE_CACHE_DIR:-${TMPDIR:-/tmp}/envtrace-cache}/oclgrind${OCLGRIND_BUILD_OPTIONS//[^a-z]/_}"
out="$log.out"
"$@" >"$out" 2>&1
rc=$?
# Every Oclgrind diagnostic names its kernel and work-item on tab-indented lines; keep each
# report (the blank-line-separated paragraph holding them) in the log.
awk 'BEGIN { RS = ""; ORS = "\n\n" } /\n\tKernel: / || /\n\tEntity: / { print }' "$out" >"$log"
reports=$(grep -c $'^\tEntity: ' "$log")
# Fatal simulator errors and API errors are printed without that shape.
if [ ${#expect[@]} -eq 0 ] && grep -Eq "OCLGRIND FATAL|Oclgrind - OpenCL runtime error" "$out"; then
  cat "$out"
  echo "FAIL: Oclgrind printed a fatal or API error (above)"
  exit 1
fi
if [ ${#expect[@]} -gt 0 ]; then
  for re in "${expect[@]}"; do
    if ! grep -Eq "$re" "$log"; then
      cat "$out"
      echo "FAIL: Oclgrind reported no /$re/ for a kernel that has that error (log $log)"
      exit 1
    fi
  done
  echo "ok: Oclgrind reported every expected error ($reports reports)"
  exit $rc
fi
# The program's own output without the reports (gtest's verdicts).
awk 'BEGIN { RS = ""; ORS = "\n\n" } !(/\n\tKernel: / || /\n\tEntity: /) { print }' "$out"
if [ "$reports" -gt 0 ] || [ -s "$log" ]; then
  echo "FAIL: Oclgrind reported $reports errors; the first of them (all in $log):"
  head -c 20000 "$log"
  exit 1
fi
checks="API, data races, bounds"
[ "$uninit" = 1 ] && checks="$checks, uninitialised values"
echo "ok: no Oclgrind report (checks: $checks)"
exit $rc
