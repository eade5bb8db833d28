#!/usr/bin/env bash
# Every OpenCL program under kernels/ (and the test and benchmark programs in the folders named
# after the tools, which include kernels/ headers) compiled offline by clang for spir64, as OpenCL C 1.2 and
# 3.0, translated to SPIR-V by llvm-spirv and accepted by spirv-val: the kernels are portable
# OpenCL C, not "whatever PoCL accepts". Also checks that the optimised LLVM IR holds no
# llvm.bitreverse (Oclgrind and older SPIR-V translators cannot lower it; kernels/sampler.h).
#
# usage: offline_spirv.sh KERNELS_DIR OUT_DIR CLANG LLVM_SPIRV SPIRV_VAL [PROGRAM_DIR...]
# Exit 0: all good; 1: a failure (named); 77: a tool is missing (ctest reports it as skipped;
# tools/setup installs all three: clang, llvm-spirv-<clang major>, spirv-tools).
set -uo pipefail
kernels=$1 out=$2 clang=$3 llvm_spirv=$4 spirv_val=$5
shift 5
for t in "$clang" "$llvm_spirv" "$spirv_val"; do
  if [ -z "$t" ] || [ "${t%NOTFOUND}" != "$t" ] || ! [ -x "$t" ]; then
    echo "SKIPPED: offline SPIR-V check needs clang, llvm-spirv and spirv-val (found: clang='$clang'" \
      "llvm-spirv='$llvm_spirv' spirv-val='$spirv_val'); tools/setup installs them"
    exit 77
  fi
done
mkdir -p "$out"
shopt -s nullglob
programs=("$kernels"/*.cl)
for d in "$@"; do programs+=("$d"/*.cl); done
[ ${#programs[@]} -gt 0 ] || { echo "FAIL: no .cl program under $kernels"; exit 1; }

# OpenCL C version -> SPIR-V version llvm-spirv may emit -> spirv-val target environment.
# (OpenCL 1.2 consumers take SPIR-V 1.0 through cl_khr_il_program; OpenCL 3.0 devices up to 1.2+.)
configs=("CL1.2 1.0 opencl1.2" "CL3.0 1.2 opencl2.2")
failed=0 checked=0
for src in "${programs[@]}"; do
  name=$(basename "$src" .cl)
  shown=$(basename "$(dirname "$src")")/$name.cl
  for cfg in "${configs[@]}"; do
    read -r std spv env <<<"$cfg"
    base="$out/$name.$std"
    # -O0: the translator's input is unoptimised IR, as a driver's SPIR-V consumer expects.
    if ! "$clang" -cl-std="$std" -target spir64 -Xclang -finclude-default-header -O0 \
      -Wall -Wextra -Werror -I"$kernels" -emit-llvm -c "$src" -o "$base.bc" 2>"$base.clang.log"; then
      echo "FAIL: clang -cl-std=$std -target spir64 $shown:"; cat "$base.clang.log"
      failed=1; continue
    fi
    if ! "$llvm_spirv" --spirv-max-version="$spv" "$base.bc" -o "$base.spv" >"$base.spirv.log" 2>&1; then
      echo "FAIL: llvm-spirv (SPIR-V $spv) $shown ($std):"; cat "$base.spirv.log"
      failed=1; continue
    fi
    if ! "$spirv_val" --target-env "$env" "$base.spv" >"$base.val.log" 2>&1; then
      echo "FAIL: spirv-val --target-env $env $shown ($std):"; cat "$base.val.log"
      failed=1; continue
    fi
    echo "ok: $shown  $std -> SPIR-V $spv, spirv-val --target-env $env"
    checked=$((checked + 1))
  done
  # Optimised IR, as a driver built on LLVM would produce it: no intrinsic that not every
  # implementation has.
  if ! "$clang" -cl-std=CL1.2 -target spir64 -Xclang -finclude-default-header -O2 -I"$kernels" -emit-llvm -S \
    "$src" -o "$out/$name.O2.ll" 2>"$out/$name.O2.log"; then
    echo "FAIL: clang -O2 $shown:"; cat "$out/$name.O2.log"; failed=1
  elif grep -q "llvm\.bitreverse" "$out/$name.O2.ll"; then
    echo "FAIL: $shown: clang -O2 turned code into llvm.bitreverse, which Oclgrind" \
      "cannot run (see etk_reverse_bits in kernels/sampler.h)"
    failed=1
  fi
done
echo "$checked program builds translated and validated, ${#programs[@]} programs"
exit $failed
