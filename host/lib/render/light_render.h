// Native renders that sum over a finite set of light directions at every shading point, beside the
// wavefront path tracer (which traces one shadow ray per path): directional lights (zero variance
// in the lighting, `envtrace render --lights`) and structured importance sampling (`--strategy
// sis`). Direct lighting only (depth 1); camera rays, shading frames and materials are those of
// kernels/integrator.h through kernels/directional_lights.h. Camera rays that escape see the map.
#pragma once
#include "prepare/light_set.h"
#include "render/renderer.h"
#include "prepare/sis.h"

namespace et {

class LightSetRenderer : public Renderer {
  public:
    // Directional lights: every camera sample sums all lights, one shadow ray each.
    LightSetRenderer(const SceneArrays& arrays, const etk::EtkParams& params,
                     const std::vector<DirectionalLight>& lights, int threads);
    // SIS: camera sample s of a pixel traces one shadow ray into stratum s mod N, jittered
    // uniformly (in solid angle) inside it, weighted by N x the stratum's preintegrated power; so
    // every N consecutive samples visit each stratum once. `strata` must outlive the renderer.
    LightSetRenderer(const SceneArrays& arrays, const etk::EtkParams& params,
                     const VoronoiStrata& strata, int threads);

    void render_sample(uint32_t sample_index) override;
    std::vector<float> image() override;
    const RenderStats& stats() override { return stats_; }
    int paths() const override { return params_.width * params_.height; }
    std::string name() const override { return strata_ ? "cpu-sis" : "cpu-lights"; }

  private:
    const SceneArrays& arrays_;
    etk::EtkParams params_;
    int threads_;
    std::vector<etk::float3> dirs_, power_; // lights, world space
    const VoronoiStrata* strata_ = nullptr;
    std::vector<double> film_; // RGB sums
    int samples_ = 0;
    RenderStats stats_;
};

} // namespace et
