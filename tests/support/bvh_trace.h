// tests/kernels/cl/bvh_test.cl run on an OpenCL device: the BVH tests' rays traced there (PoCL in
// tests/prepare/bvh_build_test.cpp, Oclgrind in tests/portability/oclgrind_test.cpp).
#pragma once
#include "opencl/opencl_runtime.h"
#include "kernels/compat.h"

#include <vector>

namespace ett {

// One closest-hit (any_hit 0) or any-hit query per ray: org (xyz, tmax in w) and dir (xyz)
// through the flattened BVH `nodes` and triangle `packets`; per ray (t, prim's bits, b1, b2).
std::vector<etk::float4> trace_bvh_kernel(et::ClRuntime& rt, const std::vector<etk::float4>& nodes,
                                          const std::vector<etk::float4>& packets,
                                          const std::vector<etk::float4>& org,
                                          const std::vector<etk::float4>& dir, int any_hit);

} // namespace ett
