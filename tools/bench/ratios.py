#!/usr/bin/env python3
"""Kernel/native throughput ratios from a bench_sampling JSON file (--benchmark_out=FILE.json),
using the medians of --benchmark_repetitions. Usage: tools/bench/ratios.py FILE.json"""
import json
import sys

runs = json.load(open(sys.argv[1]))["benchmarks"]
med = {}
for b in runs:
    if b.get("aggregate_name") == "median" and "samples/s" in b:
        med[b["run_name"]] = b["samples/s"]
pairs = [("kernel_records", "native_records_2threads")]
for p in (1, 64):
    pairs.append((f"kernel_reduce/per_item:{p}/local:64", f"native_reduce_2threads/per_item:{p}"))
for local in (0, 8, 16, 256):
    pairs.append((f"kernel_reduce/per_item:64/local:{local}", "native_reduce_2threads/per_item:64"))
pairs.append(("native_reduce_1thread/per_item:64", "native_reduce_2threads/per_item:64"))
maps = sorted({n.split("/")[1] for n in med})
print(f"{'map':<20} {'kernel (M samples/s)':<42} {'native (M samples/s)':<38} ratio")
for m in maps:
    for k, n in pairs:
        kk, nn = f"BM_Sample/{m}/{k}/real_time", f"BM_Sample/{m}/{n}/real_time"
        if kk in med and nn in med:
            print(f"{m:<20} {k:<34} {med[kk]/1e6:6.2f}  {n:<30} {med[nn]/1e6:6.2f}  "
                  f"{med[kk]/med[nn]:.2f}")
