// The native back end: the same integrator stages (kernels/integrator.h), compiled for the host
// ISA and run as C++ loops. Each thread renders tiles of consecutive pixels as a small wavefront
// of its own (SoA buffers and queues sized to stay in cache), so threads share nothing but the
// scene and the film, whose tiles are disjoint.
#pragma once
#include "render/renderer.h"

namespace et {

class WavefrontCPU : public Renderer {
  public:
    WavefrontCPU(const SceneArrays& arrays, const etk::EtkParams& params, int threads,
                 int tile = 0);

    void render_sample(uint32_t sample_index) override;
    std::vector<float> image() override;
    const RenderStats& stats() override { return stats_; }
    int paths() const override { return threads_ * tile_; }
    std::string name() const override { return "cpu"; }

  private:
    const SceneArrays& arrays_;
    etk::EtkParams params_;
    int pixels_, threads_, tile_;
    std::vector<etk::float4> film_;
    RenderStats stats_;
};

} // namespace et
