// The tests' own OpenCL programs (tests/kernels/cl/*.cl: BVH traversal, the sampler, texture
// lookups), embedded in the test binaries only (cmake/embed_kernels.cmake); they include the
// product's kernels/ headers by name.
#pragma once
#include "opencl/kernel_sources.h"
#include "opencl/opencl_runtime.h"

#include <map>
#include <string>

namespace ett {

// File name -> contents; generated.
const std::map<std::string, std::string>& test_kernel_sources();

// Builds tests/kernels/cl/<file> on `rt` (from its binary cache when it can).
inline cl::Program build_test_kernel(et::ClRuntime& rt, const std::string& file) {
    return rt.build_source(
        file, et::expand_kernel_source(file, test_kernel_sources(), "tests/kernels/cl"));
}

} // namespace ett
