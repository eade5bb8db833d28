#!/usr/bin/env bash
# The control of memcheck_native_renders: memcheck must report the unwritten path state that
# MemcheckControl.* branches on, naming the native lane's allocation as its origin, or the clean
# runs prove nothing.
#
# usage: memcheck_control.sh VALGRIND MEMCHECK_TEST
set -uo pipefail
out=$("$1" --tool=memcheck --error-exitcode=42 --leak-check=no --track-origins=yes \
  --num-callers=30 "$2" --gtest_filter=MemcheckControl.* 2>&1)
rc=$?
echo "$out" | tail -40
if [ $rc -ne 42 ]; then
  echo "FAIL: memcheck exited $rc, not 42 (its error exit): nothing was reported"
  exit 1
fi
if ! echo "$out" | grep -q "depends on uninitialised value"; then
  echo "FAIL: no 'depends on uninitialised value' report"
  exit 1
fi
if ! echo "$out" | grep -A3 "created by a heap allocation" | grep -q "CpuDevice::Lane\|uninitialised<"; then
  echo "FAIL: the report does not trace the value to the lane's allocation (CpuDevice::Lane)"
  exit 1
fi
echo "ok: memcheck reported the unwritten path state, from the lane's allocation"
