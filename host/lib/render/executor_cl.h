// The OpenCL back end: the kernels of kernels/wavefront.cl, one per stage, over device buffers
// allocated and bound from the declarations of kernels/path_state.h. Each lane runs waves of up to
// `paths` pixels one after another on a command queue of its own.
#pragma once
#include "opencl/opencl_runtime.h"
#include "prepare/device_scene.h"
#include "render/film.h"
#include "render/schedule.h"

#include <memory>
#include <string>
#include <vector>

namespace et {

// The work-group size asked for; each kernel gets the largest size up to it that the kernel and
// the device allow (choose_local_size). Fixed per kernel for the whole render: PoCL compiles a
// work-group function per distinct local size. Also the most a stage may get: wavefront.cl
// sizes its work-group push arrays by ETK_STAGE_LOCAL_MAX.
constexpr size_t kStageLocalTarget = ETK_STAGE_LOCAL_MAX;

// What the device reports for each stage kernel of wavefront.cl and the work-group size the
// renderer will launch it with (`envtrace devices --kernels`).
struct StageKernelInfo {
    std::string name;
    size_t work_group_size = 0;    // CL_KERNEL_WORK_GROUP_SIZE
    size_t preferred_multiple = 0; // CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE
    uint64_t private_bytes = 0;    // CL_KERNEL_PRIVATE_MEM_SIZE
    size_t local = 0;              // what the renderer launches it with
};
std::vector<StageKernelInfo> stage_kernel_info(ClRuntime& rt);

// Whether --light-batch auto batches the light samples on a device: on CPUs, where one
// work-item's batch keeps its cache misses in flight together; not on GPUs, where other
// work-items hide the latency (measured: docs/history/bench-journal.md).
inline bool prefers_light_batches_on(const DeviceLimits& limits) {
    return limits.cpu;
}

// Whether a render keeps the film's exact sums on this device (RenderSettings::film_sums; the
// sums take `bytes`): automatic on a GPU, where reading each pass back and adding it on the host
// took two thirds of a 2048x2048 pass (docs/devices.md), if they fit in a quarter of its memory;
// never for a render with AOVs, whose sums the host keeps. Throws where device is asked for a
// film too large for one buffer of words a kernel can count.
bool wants_film_sums_on_device(const RenderSettings& st, const DeviceLimits& limits,
                               uint64_t bytes);

// Whether a render's waves keep their queue sizes on this device (RenderSettings::queue_counts):
// automatic on a GPU, where each of the host's reads leaves the device idle until its next
// launch; on a CPU device the host's reads cost microseconds, and the launches sized for a
// whole wave would cost more.
bool wants_queue_counts_on_device(const RenderSettings& st, const DeviceLimits& limits);

// One lane of the OpenCL back end: a command queue with path state, queues and counters of its
// own (kernels/path_state.h), running waves one after another; the scene, the film and the
// visibility tables are the device's, shared by every lane.
class ClLane : public StageExecutor {
  public:
    // shared: every kernel argument that is not the lane's own (by ETK_ARG_*; the lane's own
    // entries are ignored); local: the work-group size per stage.
    // counted: whether its waves keep their queue sizes on the device (counts_on_device).
    // device: where its queue sends the kernels (the runtime's device or one of its sub-devices).
    ClLane(ClRuntime& rt, const cl::Device& device, const cl::Program& program,
           const std::vector<size_t>& local, size_t zero_local,
           const std::vector<cl::Buffer>& shared, int paths, bool counted);

    void bind_queues(bool swapped) override;
    void reset_counters() override;
    void read_counters(uint32_t* counters) override;
    void read_fields(int n, const std::vector<FieldRead>& reads) override;
    void launch(int stage, int n, const etk::EtkParams& params) override;
    bool counts_on_device() const override { return counted_; }
    void next_bounce(int first_rays) override;
    void launch_counted(int stage, int most, const etk::EtkParams& params) override;

    void zero_words(const cl::Buffer& buffer, uint64_t words);
    // Launches every kernel once, doing nothing, over the widest range it will ever be given:
    // `paths` work-items for the stages, `words` for zero_words (why: executor_cl.cpp).
    void prime_kernels(int paths, uint64_t words);
    void finish();
    cl::CommandQueue& queue() { return queue_; }
    size_t pending_events() const { return pending_.size(); }
    const std::vector<double>& seconds() const { return seconds_; }

  private:
    void collect_events();
    void enqueue_stage(int stage, int n, int items, const etk::EtkParams& params);

    cl::CommandQueue queue_;
    std::vector<cl::Kernel> kernels_; // by ETK_STAGE_*: a lane's own (arguments are per kernel)
    std::vector<size_t> local_;       // work-group size per kernel
    cl::Kernel zero_;                 // zero_words
    size_t zero_local_;
    cl::Kernel next_bounce_; // next_bounce (a wave counted on the device)
    bool counted_;
    std::vector<cl::Buffer> args_; // by ETK_ARG_* (buffers only)
    cl::Buffer queue_a_, queue_b_; // bound to ray_in / ray_out
    std::vector<double> seconds_;  // per stage: finished launches
    std::vector<std::pair<int, cl::Event>> pending_;
};

// The lanes of a CPU device: one per sub-device of one_unit_sub_devices (a lane per compute unit,
// as the native back end runs one per thread); two on the whole device where there are none, so
// that while one lane's host thread waits on a counter read or launches its next stage, the
// other's kernels keep the device's threads busy. One on any other device, and on Oclgrind. The
// lanes write disjoint pixels of one film buffer from their queues at once: well defined on a
// device that works in host memory, which OpenCL 1.2 does not promise elsewhere (a GPU with two
// lanes would want a film per lane, or sub-buffers).
int default_cl_lanes(const ClRuntime& rt);

// Where a CPU device's lanes send their kernels: sub-devices of one compute unit each (one PoCL
// thread apiece), so that a lane's stages run on one thread after another as a native lane's do.
// On the whole device PoCL shares every launch out among all its threads, and each stage then
// reads on one core the path state another core wrote: on 2 cores the same kernels took 1.16x the
// CPU time (docs/history/bench-journal.md, "A lane on a compute unit of its own"). PoCL only:
// OpenCL 1.2 asks that a queue's device be one the context was made with, and the context and
// program are the root device's; PoCL takes its sub-devices there, other drivers need not. Empty
// (the lanes use the whole device) on any other platform or device, on one compute unit, and
// where the device cannot be partitioned. The same devices on every call (made once, kept).
std::vector<cl::Device> one_unit_sub_devices(const ClRuntime& rt);

class ClDevice : public WavefrontDevice {
  public:
    // paths: paths in flight per lane (0: the film shared out among the lanes, capped by the
    // device's memory); lanes: 0 for default_cl_lanes.
    ClDevice(std::unique_ptr<ClRuntime> rt, const DeviceScene& scene, int paths,
             ProgramBuildInfo* build = nullptr, int lanes = 0);

    std::string name() const override { return "opencl"; }
    int lanes() const override { return static_cast<int>(lanes_.size()); }
    // Whether the lanes' queues go to sub-devices (one_unit_sub_devices), not the whole device.
    bool lanes_on_sub_devices() const { return !lane_devices_.empty(); }
    int wave_size() const override { return paths_; }
    StageExecutor& lane(int k) override { return *lanes_[k]; }
    void run_lanes(const std::function<void(int)>& f) override;
    void finish() override;
    void clear_film(bool aovs) override;
    void download_film(Film& film, bool aovs) override;
    std::vector<std::pair<std::string, double>> stage_seconds() override;
    bool prefers_light_batches() const override { return prefers_light_batches_on(rt_->limits()); }
    void upload_guide(const std::vector<float>& cells,
                      const std::vector<FloatSpan>& changed) override;
    void absorb_guide_sums(const GuideSumsAbsorb& absorb) override;
    bool folds_film() const override { return fold_; }
    void fold_film() override;
    void take_film_sums(FilmSums& sums) override;

    // Events of launches not yet accounted, all lanes (for tests: stays bounded during a render).
    size_t pending_events() const;
    // Work-group size of each stage's kernel (by ETK_STAGE_*), as chosen for this device.
    const std::vector<size_t>& local_sizes() const { return local_; }

  private:
    std::unique_ptr<ClRuntime> rt_;
    std::vector<cl::Device> lane_devices_; // one_unit_sub_devices; lane k's is [k % size]
    int pixels_, paths_;
    cl::Program program_;
    std::vector<size_t> local_;    // work-group size per kernel
    std::vector<cl::Buffer> args_; // the shared buffers, by ETK_ARG_*
    std::vector<std::unique_ptr<ClLane>> lanes_;
    void zero_guide_sums(); // before the first pass, and after each copy absorb_guide_sums takes
    // The film's exact sums on the device (folds_film; kernels/film_fixed.h): a buffer of
    // FilmSums::Pixel, 28 words each, and the kernel that adds a pass to it.
    bool fold_ = false;
    cl::Buffer film_fixed_;
    cl::Kernel fold_kernel_;
    size_t fold_local_ = 1;
    size_t guide_floats_ = 1; // size of the visibility tables' buffer
    size_t guide_words_ = 1;  // size of the visibility records' sums (visibility_record.h)
    std::vector<uint32_t> guide_sums_copy_; // their copy at each update (unless in place)
    // The device shares the host's memory: the tables and sums are mapped and updated in place
    // (no copy of tens of megabytes each way per update), not transferred whole.
    bool guide_in_place_ = false;
    // Buffer `arg` of `words` 32-bit words mapped for the duration of f(its host pointer).
    void with_mapped(int arg, size_t words, cl_map_flags flags,
                     const std::function<void(void*)>& f);
};

} // namespace et
