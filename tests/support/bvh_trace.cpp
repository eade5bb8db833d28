#include "bvh_trace.h"
#include "test_kernels.h"

namespace ett {

std::vector<etk::float4> trace_bvh_kernel(et::ClRuntime& rt, const std::vector<etk::float4>& nodes,
                                          const std::vector<etk::float4>& packets,
                                          const std::vector<etk::float4>& org,
                                          const std::vector<etk::float4>& dir, int any_hit) {
    cl::Program program = build_test_kernel(rt, "bvh_test.cl");
    cl::Kernel k(program, "bvh_trace");
    const int n = static_cast<int>(org.size());
    auto buf = [&](const std::vector<etk::float4>& v) {
        return cl::Buffer(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                          v.size() * sizeof(etk::float4), const_cast<etk::float4*>(v.data()));
    };
    cl::Buffer bn = buf(nodes), bt = buf(packets), bo = buf(org), bd = buf(dir);
    cl::Buffer out(rt.context(), CL_MEM_WRITE_ONLY, n * sizeof(etk::float4));
    k.setArg(0, bn);
    k.setArg(1, bt);
    k.setArg(2, bo);
    k.setArg(3, bd);
    k.setArg(4, any_hit);
    k.setArg(5, n);
    k.setArg(6, out);
    const size_t local = et::choose_local_size(k, rt.device().device, rt.limits());
    rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((n + local - 1) / local * local),
                                    cl::NDRange(local));
    std::vector<etk::float4> v(n);
    rt.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(etk::float4), v.data());
    return v;
}

} // namespace ett
