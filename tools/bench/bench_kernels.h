// The benchmarks' own OpenCL programs (tools/bench/*.cl), embedded in the benchmark binaries
// only (cmake/embed_kernels.cmake); they include the product's kernels/ headers by name.
#pragma once
#include "opencl/kernel_sources.h"
#include "opencl/opencl_runtime.h"

#include <map>
#include <string>

namespace etb {

// File name -> contents; generated.
const std::map<std::string, std::string>& bench_kernel_sources();

// Builds tools/bench/<file> on `rt` (from its binary cache when it can).
inline cl::Program build_bench_kernel(et::ClRuntime& rt, const std::string& file) {
    return rt.build_source(file,
                           et::expand_kernel_source(file, bench_kernel_sources(), "tools/bench"));
}

} // namespace etb
