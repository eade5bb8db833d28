// The OpenCL back end: the wavefront stages of kernels/wavefront.cl driven over work queues.
#pragma once
#include "render/renderer.h"

#include <cstdint>
#include <string>
#include <vector>

namespace et {

class WavefrontCL : public Renderer {
  public:
    // paths: paths in flight (0: the film, capped by memory).
    WavefrontCL(std::unique_ptr<ClRuntime> rt, const SceneArrays& arrays,
                const etk::EtkParams& params, int paths, ProgramBuildInfo* build = nullptr);

    // Adds one sample to every pixel (index `sample_index` of each pixel's sequence).
    void render_sample(uint32_t sample_index) override;
    std::vector<float> image() override;
    const RenderStats& stats() override;
    int paths() const override { return paths_; }
    std::string name() const override { return "opencl"; }

  private:
    void launch(int stage, int n);
    void set_queue_args(const cl::Buffer& in, const cl::Buffer& out);
    void zero_counters();
    void read_counters(uint32_t* out);

    std::unique_ptr<ClRuntime> rt_;
    etk::EtkParams params_;
    int pixels_, paths_;
    cl::CommandQueue queue_;
    cl::Program program_;
    std::vector<cl::Kernel> kernels_;
    std::vector<std::vector<cl::Event>> events_;
    cl::Buffer nodes_, tris_, normals_, tri_material_, materials_, env_dist_, env_texels_;
    cl::Buffer ray_o_, ray_d_, beta_, radiance_, hit_, shadow_o_, shadow_d_, shadow_L_, pixel_;
    cl::Buffer queue_a_, queue_b_, escaped_, shade_, shadow_, counters_, film_;
    RenderStats stats_;
};

} // namespace et
