// The OpenCL back end: the wavefront stages of kernels/wavefront.cl driven over work queues.
#pragma once
#include "opencl_runtime.h"
#include "scene_arrays.h"

#include <cstdint>
#include <string>
#include <vector>

namespace et {

struct RenderStats {
    uint64_t camera_rays = 0, continuation_rays = 0, shadow_rays = 0;
    int samples_per_pixel = 0;
    double seconds = 0.0;
    // Device time per stage, from OpenCL profiling events (seconds).
    std::vector<std::pair<std::string, double>> stage_seconds;
    uint64_t rays() const { return camera_rays + continuation_rays + shadow_rays; }
};

class WavefrontCL {
  public:
    // paths: paths in flight (0: the film, capped by memory).
    WavefrontCL(ClRuntime& rt, const SceneArrays& arrays, const etk::EtkParams& params, int paths,
                ProgramBuildInfo* build = nullptr);

    // Adds one sample to every pixel (index `sample_index` of each pixel's sequence).
    void render_sample(uint32_t sample_index);

    // Mean radiance per pixel (RGB, row-major, row 0 at the top).
    std::vector<float> image();
    const RenderStats& stats() const { return stats_; }
    int paths() const { return paths_; }

  private:
    void launch(int stage, int n);
    void set_queue_args(const cl::Buffer& in, const cl::Buffer& out);
    void zero_counters();
    void read_counters(uint32_t* out);

    ClRuntime& rt_;
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
