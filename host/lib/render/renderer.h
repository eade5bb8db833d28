// A back end that renders a prepared scene one sample per pixel at a time: the OpenCL wavefront
// (wavefront_cl.h) or the native C++ one (wavefront_cpu.h), both running kernels/integrator.h.
#pragma once
#include "opencl/opencl_runtime.h"
#include "prepare/device_scene.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace et {

struct RenderStats {
    uint64_t camera_rays = 0, continuation_rays = 0, shadow_rays = 0;
    uint64_t nonfinite_samples = 0; // dropped by the film; anything but 0 is a bug
    int samples_per_pixel = 0;
    double seconds = 0.0;
    // Time per stage (seconds): device time from profiling events for OpenCL, wall time natively.
    std::vector<std::pair<std::string, double>> stage_seconds;
    uint64_t rays() const { return camera_rays + continuation_rays + shadow_rays; }
};

class Renderer {
  public:
    virtual ~Renderer() = default;
    // Adds one sample to every pixel (index `sample_index` of each pixel's sequence).
    virtual void render_sample(uint32_t sample_index) = 0;
    // Mean radiance per pixel (RGB, row-major, row 0 at the top).
    virtual std::vector<float> image() = 0;
    virtual const RenderStats& stats() = 0;
    virtual int paths() const = 0;
    virtual std::string name() const = 0;
};

struct RendererOptions {
    std::string backend = "opencl"; // opencl | cpu
    int device = 0;                 // OpenCL device index
    int paths = 0;                  // paths in flight; 0: the film, capped by memory
    int threads = 0;                // native threads; 0: all cores
};

// `build` receives the OpenCL program build time (untouched for the native back end).
std::unique_ptr<Renderer> make_renderer(const RendererOptions& options, const SceneArrays& arrays,
                                        const etk::EtkParams& params,
                                        ProgramBuildInfo* build = nullptr);

} // namespace et
