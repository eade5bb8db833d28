// The native back end: the stages of kernels/integrator.h compiled for the host ISA and run as
// C++ loops. Each thread is a lane with a small wavefront of its own (path state and queues
// sized to stay in cache) rendering waves of consecutive pixels (of every lanes-th pixel where the
// pass is one wave a lane: WaveDealer), so threads share nothing but the scene and the film, whose
// waves are disjoint.
#pragma once
#include "prepare/device_scene.h"
#include "render/film.h"
#include "render/schedule.h"

#include <memory>

namespace et {

class CpuDevice : public WavefrontDevice {
  public:
    // threads: 0 for all cores; wave: paths per lane (0: 1024).
    CpuDevice(const DeviceScene& scene, Film& film, int threads, int wave = 0);
    ~CpuDevice() override;

    std::string name() const override { return "cpu"; }
    int lanes() const override;
    int wave_size() const override { return wave_; }
    StageExecutor& lane(int k) override;
    void run_lanes(const std::function<void(int)>& f) override;
    void finish() override {}
    // The stages write the host film directly: zeroed here (element-wise: the lanes hold
    // pointers into it), nothing to hand back.
    void clear_film(bool aovs) override;
    void download_film(Film&, bool) override {}
    std::vector<std::pair<std::string, double>> stage_seconds() override;
    void upload_guide(const std::vector<float>& cells,
                      const std::vector<FloatSpan>& changed) override;
    void absorb_guide_sums(const GuideSumsAbsorb& absorb) override;

  private:
    std::vector<float> guide_cells_;   // the visibility strategy's tables, read by every lane
    std::vector<uint32_t> guide_sums_; // its record sums, added to by every lane
    Film& film_;
    class Lane;
    std::vector<std::unique_ptr<Lane>> lanes_;
    int wave_;
};

} // namespace et
