#include "render/executor_cl.h"

#include "render/film_sums.h"
#include "util/error.h"
#include "util/parallel.h"

#include <algorithm>
#include <climits>
#include <map>
#include <mutex>
#include <string>
#include <utility>

namespace et {
namespace {

// Device bytes per path in flight: the path fields and the queues (ray_in and ray_out are two
// buffers that swap).
#define ET_FIELD_BYTES(type, name) +sizeof(type)
#define ET_QUEUE_BYTES(name) +sizeof(int)
constexpr size_t kBytesPerPath = 0 ETK_PATH_FIELDS(ET_FIELD_BYTES) ETK_QUEUES(ET_QUEUE_BYTES);
#undef ET_FIELD_BYTES
#undef ET_QUEUE_BYTES

// Every OpenCL 1.2 device takes at least 1024 bytes of kernel arguments
// (CL_DEVICE_MAX_PARAMETER_SIZE): a stage's buffers (a pointer each, at most 8 bytes), its
// parameters and n must fit, or a smaller device could not run the stages at all (856 bytes in
// November 2026).
static_assert(8 * etk::ETK_ARG_params + sizeof(etk::EtkParams) + sizeof(cl_int) <= 1024,
              "the stages' kernel arguments exceed OpenCL 1.2's minimum parameter size");

// A read-only buffer over `v`, which the DeviceScene keeps alive for the renderer's lifetime.
// On a device that shares the host's memory (PoCL on the CPU) CL_MEM_USE_HOST_PTR reads the
// host vector in place instead of holding a second copy of a map that may be gigabytes; any
// other device (a GPU, Oclgrind's simulator) gets its own copy, CL_MEM_COPY_HOST_PTR, which is
// what it would make anyway and which every implementation counts as initialised memory.
// Device buffers cannot be empty: an empty vector gets one zero element.
template <typename T>
cl::Buffer upload(cl::Context& ctx, const std::vector<T>& v, bool host_unified) {
    static const T zero{};
    const void* data = v.empty() ? &zero : v.data();
    const cl_mem_flags where = host_unified ? CL_MEM_USE_HOST_PTR : CL_MEM_COPY_HOST_PTR;
    return cl::Buffer(ctx, CL_MEM_READ_ONLY | where, std::max<size_t>(1, v.size()) * sizeof(T),
                      const_cast<void*>(data));
}

// a / b rounded up, for positive a and b (no overflow near INT_MAX, unlike (a + b - 1) / b).
int ceil_div(int a, int b) {
    return a / b + (a % b ? 1 : 0);
}

} // namespace

std::vector<StageKernelInfo> stage_kernel_info(ClRuntime& rt) {
    const cl::Device& dev = rt.device().device;
    cl::Program program = rt.build("wavefront.cl");
    std::vector<StageKernelInfo> out;
    for (int s = 0; s <= etk::ETK_STAGE_COUNT; ++s) {
        const char* name = s < etk::ETK_STAGE_COUNT ? stage_name(s) : "zero_words";
        cl::Kernel k(program, name);
        StageKernelInfo info;
        info.name = name;
        info.work_group_size = k.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(dev);
        info.preferred_multiple =
            k.getWorkGroupInfo<CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE>(dev);
        info.private_bytes = k.getWorkGroupInfo<CL_KERNEL_PRIVATE_MEM_SIZE>(dev);
        info.local = choose_local_size(k, dev, rt.limits(), kStageLocalTarget);
        out.push_back(info);
    }
    return out;
}

// Paths in flight per lane on a CPU device, by default. With each lane on a compute unit of its own
// (one_unit_sub_devices) a lane that ends its pass early leaves its unit idle: ogre depth 5 on
// PoCL, 512 x 512 in waves of 65,536 (two a lane), took 1.13x the time the whole device took with
// them. Waves of 32,768 and 16,384 each gave 1.02x the whole device's speed in geometric mean
// over six scenes; the larger makes fewer launches and host round trips, and run_pass deals the
// pass's tail in smaller waves (WaveDealer); docs/history/bench-journal.md, "A lane on a compute
// unit of its own".
constexpr int kCpuWave = 32768;

int default_cl_lanes(const ClRuntime& rt) {
    // Oclgrind interprets one kernel at a time (two queues' kernels trip an assertion of its own).
    if (!rt.limits().cpu || rt.is_oclgrind())
        return 1;
    const size_t subs = one_unit_sub_devices(rt).size();
    return subs > 0 ? static_cast<int>(subs) : 2;
}

std::vector<cl::Device> one_unit_sub_devices(const ClRuntime& rt) {
    const bool pocl = rt.device().platform_name.find("Portable Computing Language") !=
                      std::string::npos; // (see the header)
    if (!pocl || !rt.limits().cpu || rt.device().compute_units < 2)
        return {};
    // Made once per device and kept for the process, never released (not even at exit): PoCL
    // 3.1's threads release a finished launch's event after the host has seen it finish, and a
    // sub-device released meanwhile (a renderer's end) crashed them (a third of the runs of a test
    // making many renderers, on a loaded host).
    static std::mutex mutex;
    static auto* made = new std::map<cl_device_id, std::vector<cl::Device>>;
    const std::lock_guard<std::mutex> lock(mutex);
    const cl_device_id id = rt.device().device();
    auto it = made->find(id);
    if (it == made->end()) {
        std::vector<cl::Device> subs;
        try {
            const cl_device_partition_property one_unit[] = {CL_DEVICE_PARTITION_EQUALLY, 1, 0};
            cl::Device(rt.device().device).createSubDevices(one_unit, &subs);
        } catch (const cl::Error&) {
            subs.clear(); // not partitionable (CL_DEVICE_PARTITION_PROPERTIES lacks it)
        }
        if (subs.size() < 2)
            subs.clear(); // the whole device
        it = made->emplace(id, std::move(subs)).first;
    }
    return it->second;
}

bool wants_film_sums_on_device(const RenderSettings& st, const DeviceLimits& lim, uint64_t bytes) {
    const bool countable = bytes / 4 <= static_cast<uint64_t>(INT_MAX); // zero_words' n
    if (st.aovs)
        return false;
    switch (st.film_sums) {
    case FilmSumsAt::host:
        return false;
    case FilmSumsAt::device:
        if (!countable)
            throw Error("--film-sums device: the film's sums (" + std::to_string(bytes >> 20) +
                        " MiB) are too large for one device buffer; use --film-sums host");
        return true;
    case FilmSumsAt::automatic:
        break;
    }
    return !lim.cpu && countable && bytes <= lim.max_alloc && bytes <= lim.global_mem / 4;
}

bool wants_queue_counts_on_device(const RenderSettings& st, const DeviceLimits& lim) {
    switch (st.queue_counts) {
    case QueueCounts::host:
        return false;
    case QueueCounts::device:
        return true;
    case QueueCounts::automatic:
        break;
    }
    return !lim.cpu;
}

ClLane::ClLane(ClRuntime& rt, const cl::Device& device, const cl::Program& program,
               const std::vector<size_t>& local, size_t zero_local,
               const std::vector<cl::Buffer>& shared, int paths, bool counted)
    : local_(local), zero_local_(zero_local), counted_(counted), args_(shared) {
    auto& ctx = rt.context();
    const uint64_t n = static_cast<uint64_t>(paths);
    queue_ = cl::CommandQueue(ctx, device, CL_QUEUE_PROFILING_ENABLE);
    for (int s = 0; s < etk::ETK_STAGE_COUNT; ++s)
        kernels_.emplace_back(program, stage_name(s));
    zero_ = cl::Kernel(program, "zero_words");
    next_bounce_ = cl::Kernel(program, "next_bounce");
    seconds_.assign(etk::ETK_STAGE_COUNT, 0.0);
#define ET_ALLOC(type, name)                                                                       \
    args_[etk::ETK_ARG_##name] = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(type) * n);
    ETK_PATH_FIELDS(ET_ALLOC)
#undef ET_ALLOC
#define ET_QUEUE(name)                                                                             \
    args_[etk::ETK_ARG_##name] = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_int) * n);
    ETK_FIXED_QUEUES(ET_QUEUE)
#undef ET_QUEUE
    queue_a_ = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_int) * n);
    queue_b_ = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_int) * n);
    args_[etk::ETK_ARG_counters] =
        cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_uint) * etk::ETK_Q_COUNT);
    for (auto& k : kernels_)
        for (int a = 0; a < etk::ETK_ARG_params; ++a)
            if (a != etk::ETK_ARG_ray_in && a != etk::ETK_ARG_ray_out)
                k.setArg(a, args_[a]);
    next_bounce_.setArg(0, args_[etk::ETK_ARG_counters]);
}

ClDevice::ClDevice(std::unique_ptr<ClRuntime> rt_ptr, const DeviceScene& scene, int paths,
                   ProgramBuildInfo* build, int lanes)
    : rt_(std::move(rt_ptr)), pixels_(scene.width() * scene.height()) {
    ClRuntime& rt = *rt_;
    const cl::Device& dev = rt.device().device;
    const DeviceLimits& lim = rt.limits();
    const int nl = std::max(1, lanes > 0 ? lanes : default_cl_lanes(rt));
    // Every buffer with its size, checked against the device before anything is allocated. The
    // fixed ones (scene, film) first; the lanes' paths in flight get a share of what is left.
    std::vector<BufferRequest> buffers;
#define ET_SCENE_SIZE(type, name)                                                                  \
    buffers.push_back({#name, std::max<uint64_t>(1, scene.name.size()) * sizeof(type)});
    ETK_SCENE_BUFFERS(ET_SCENE_SIZE)
#undef ET_SCENE_SIZE
#define ET_FILM_SIZE(type, name) buffers.push_back({#name, uint64_t(sizeof(type)) * pixels_});
    ETK_FILM_FIELDS(ET_FILM_SIZE)
#undef ET_FILM_SIZE
    guide_words_ = std::max<size_t>(1, scene.guide_sum_words());
    buffers.push_back({"guide_sums", uint64_t(sizeof(cl_uint)) * guide_words_});
    const uint64_t fixed_bytes = uint64_t(sizeof(FilmSums::Pixel)) * pixels_;
    fold_ = wants_film_sums_on_device(scene.settings, lim, fixed_bytes);
    const bool counted = wants_queue_counts_on_device(scene.settings, lim);
    if (fold_)
        buffers.push_back({"film sums (--film-sums device)", fixed_bytes});
    uint64_t fixed = 0;
    for (const BufferRequest& b : buffers)
        fixed += b.bytes;
    const uint64_t free_mem = lim.global_mem > fixed ? lim.global_mem - fixed : 0;
    const int cap = static_cast<int>(std::min<uint64_t>(
        {uint64_t(1) << 22, lim.max_alloc / 16,
         std::min(free_mem, lim.global_mem / 4) / (kBytesPerPath * uint64_t(nl))}));
    // The film shared out among the lanes in waves of equal size, as many per lane; on a CPU
    // device waves of at most kCpuWave paths (their path state stays in cache).
    const int waves_per_lane = lim.cpu ? std::max(1, ceil_div(ceil_div(pixels_, kCpuWave), nl)) : 1;
    const int share = ceil_div(pixels_, waves_per_lane * nl);
    paths_ = std::max(1, std::min(paths > 0 ? paths : share, std::min(cap, pixels_)));
    // No lane without a wave of its own (a film of fewer pixels than lanes, a --paths of half
    // the film or more).
    const int lanes_used = std::max(1, std::min(nl, ceil_div(pixels_, paths_)));
    const uint64_t n = static_cast<uint64_t>(paths_), px = static_cast<uint64_t>(pixels_);
    for (int l = 0; l < lanes_used; ++l) {
        const std::string lane = lanes_used > 1 ? " (lane " + std::to_string(l) + ")" : "";
#define ET_PATH_SIZE(type, name) buffers.push_back({#name + lane, sizeof(type) * n});
        ETK_PATH_FIELDS(ET_PATH_SIZE)
#undef ET_PATH_SIZE
#define ET_QUEUE_SIZE(name) buffers.push_back({#name + lane, sizeof(cl_int) * n});
        ETK_QUEUES(ET_QUEUE_SIZE)
#undef ET_QUEUE_SIZE
        buffers.push_back({"counters" + lane, uint64_t(sizeof(cl_uint)) * etk::ETK_Q_COUNT});
    }
    check_buffer_sizes(buffers, lim, rt.device().device_name);
    try {
        program_ = rt.build("wavefront.cl", "", build);
        for (int s = 0; s < etk::ETK_STAGE_COUNT; ++s)
            local_.push_back(choose_local_size(cl::Kernel(program_, stage_name(s)), dev, lim,
                                               kStageLocalTarget));
        const size_t zero_local =
            choose_local_size(cl::Kernel(program_, "zero_words"), dev, lim, kStageLocalTarget);
        auto& ctx = rt.context();
        args_.resize(etk::ETK_ARG_COUNT);
#define ET_UPLOAD(type, name)                                                                      \
    args_[etk::ETK_ARG_##name] = upload(ctx, scene.name, lim.host_unified);
        ETK_SCENE_BUFFERS(ET_UPLOAD)
#undef ET_UPLOAD
        // The visibility strategy rewrites its tables between passes: a copy of its own, never
        // the prepared scene's memory.
        args_[etk::ETK_ARG_guide_cells] = upload(ctx, scene.guide_cells, false);
        guide_floats_ = std::max<size_t>(1, scene.guide_cells.size());
        guide_in_place_ = lim.host_unified;
        args_[etk::ETK_ARG_guide_sums] =
            cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_uint) * guide_words_);
#define ET_FILM(type, name)                                                                        \
    args_[etk::ETK_ARG_##name] = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(type) * px);
        ETK_FILM_FIELDS(ET_FILM)
#undef ET_FILM
        if (fold_) {
            film_fixed_ = cl::Buffer(ctx, CL_MEM_READ_WRITE, fixed_bytes);
            fold_kernel_ = cl::Kernel(program_, "fold_film");
            fold_local_ = choose_local_size(fold_kernel_, dev, lim, kStageLocalTarget);
            fold_kernel_.setArg(0, args_[etk::ETK_ARG_film_sum]);
            fold_kernel_.setArg(1, args_[etk::ETK_ARG_film_sq]);
            fold_kernel_.setArg(2, film_fixed_);
            fold_kernel_.setArg(3, static_cast<cl_int>(pixels_));
        }
        if (lanes_used > 1)
            lane_devices_ = one_unit_sub_devices(rt);
        for (int l = 0; l < lanes_used; ++l)
            lanes_.push_back(std::make_unique<ClLane>(
                rt, lane_devices_.empty() ? dev : lane_devices_[l % lane_devices_.size()], program_,
                local_, zero_local, args_, paths_, counted));
        uint64_t widest = etk::ETK_Q_COUNT; // zero_words: the counters, the film's fields
#define ET_FILM_WORDS(type, name) widest = std::max<uint64_t>(widest, sizeof(type) / 4 * px);
        ETK_FILM_FIELDS(ET_FILM_WORDS)
#undef ET_FILM_WORDS
        if (fold_)
            widest = std::max<uint64_t>(widest, fixed_bytes / 4);
        for (auto& l : lanes_) // through every queue: whether the driver keeps the functions
            l->prime_kernels(paths_, widest); // per device or for all, each is made widest first
        clear_film(true);
        zero_guide_sums();
        if (fold_) {
            lanes_[0]->zero_words(film_fixed_, fixed_bytes / 4);
            lanes_[0]->finish();
        }
    } catch (const cl::Error& e) {
        throw Error(std::string("cannot set up the OpenCL renderer (") + e.what() +
                    "): " + cl_error_name(e.err()) + "; try a smaller film or --paths");
    }
}

// The lanes take waves on threads of their own (run_pass deals them out); each lane's launches
// and reads go to its own queue, on a compute unit of its own where the device has sub-devices
// (else the device runs one lane's kernels while another's host thread waits). Which lane renders
// a pixel changes nothing in it.
void ClDevice::run_lanes(const std::function<void(int)>& f) {
    try {
        run_on_threads(lanes(), f);
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL rendering failed (") + e.what() +
                    "): " + cl_error_name(e.err()));
    }
}

void ClLane::zero_words(const cl::Buffer& buffer, uint64_t words) {
    zero_.setArg(0, buffer);
    zero_.setArg(1, static_cast<cl_int>(words));
    queue_.enqueueNDRangeKernel(zero_, cl::NullRange,
                                cl::NDRange((words + zero_local_ - 1) / zero_local_ * zero_local_),
                                cl::NDRange(zero_local_));
}

// PoCL 5.0's CPU driver keeps a loaded work-group function per kernel, work-group size and
// grid width: a launch reuses the first one whose width is at least its own, else loads
// another. Its release looks the function up again by kernel and work-group size alone, so
// with two of them for one kernel and launches in flight from two queues (the lanes), a
// completed launch can release the other's and the next release fails an assertion
// (pocl_release_dlhandle_cache, lib/CL/devices/common.c): measured, 15 of 16 renders with two
// lanes aborted. One launch of each kernel at its widest range before any other makes that
// function the only one, found first by every later launch; every lane primes its own queue's
// device. On other devices: a few empty launches per lane.
void ClLane::prime_kernels(int paths, uint64_t words) {
    bind_queues(false);
    const etk::EtkParams params{};
    for (size_t s = 0; s < kernels_.size(); ++s) {
        kernels_[s].setArg(etk::ETK_ARG_params, sizeof(params), &params);
        kernels_[s].setArg(etk::ETK_ARG_n, 0); // no work-item does anything
        const size_t local = local_[s];
        queue_.enqueueNDRangeKernel(kernels_[s], cl::NullRange,
                                    cl::NDRange((paths + local - 1) / local * local),
                                    cl::NDRange(local));
    }
    zero_.setArg(0, args_[etk::ETK_ARG_counters]);
    zero_.setArg(1, 0);
    queue_.enqueueNDRangeKernel(zero_, cl::NullRange,
                                cl::NDRange((words + zero_local_ - 1) / zero_local_ * zero_local_),
                                cl::NDRange(zero_local_));
    queue_.finish();
}

void ClLane::finish() {
    queue_.finish();
    collect_events();
}

void ClDevice::finish() {
    for (auto& l : lanes_)
        l->finish();
}

size_t ClDevice::pending_events() const {
    size_t n = 0;
    for (const auto& l : lanes_)
        n += l->pending_events();
    return n;
}

void ClLane::collect_events() {
    // Profiling times of the finished launches; the events are released here, so a render holds
    // at most one bounce's worth of them. A blocking command after them on the in-order queue has
    // finished their work, but not necessarily marked their events complete: NVIDIA's driver
    // (the H200, tests/render/executor_cl_test.cpp) answered CL_PROFILING_INFO_NOT_AVAILABLE then.
    // So they are waited for first (at once when complete), and a time still not available is
    // left out of the stage's seconds rather than ending the render.
    std::vector<cl_event> events;
    for (auto& [stage, ev] : pending_)
        events.push_back(ev());
    if (!events.empty())
        clWaitForEvents(static_cast<cl_uint>(events.size()), events.data()); // errors: below
    for (auto& [stage, ev] : pending_) {
        cl_event e = ev();
        cl_ulong start = 0, end = 0;
        if (clGetEventProfilingInfo(e, CL_PROFILING_COMMAND_START, sizeof start, &start, nullptr) ==
                CL_SUCCESS &&
            clGetEventProfilingInfo(e, CL_PROFILING_COMMAND_END, sizeof end, &end, nullptr) ==
                CL_SUCCESS &&
            end >= start)
            seconds_[stage] += (end - start) * 1e-9;
    }
    pending_.clear();
}

void ClLane::bind_queues(bool swapped) {
    for (auto& k : kernels_) {
        k.setArg(etk::ETK_ARG_ray_in, swapped ? queue_b_ : queue_a_);
        k.setArg(etk::ETK_ARG_ray_out, swapped ? queue_a_ : queue_b_);
    }
}

void ClLane::reset_counters() {
    zero_words(args_[etk::ETK_ARG_counters], etk::ETK_Q_COUNT);
}

void ClLane::read_counters(uint32_t* out) {
    queue_.enqueueReadBuffer(args_[etk::ETK_ARG_counters], CL_TRUE, 0,
                             sizeof(cl_uint) * etk::ETK_Q_COUNT, out);
    // A blocking read on an in-order queue: every launch before it has finished.
    collect_events();
}

void ClLane::read_fields(int n, const std::vector<FieldRead>& reads) {
    // Path field k is kernel argument ETK_ARG_<first field> + k (path_state.h's argument order).
    constexpr int first = etk::ETK_ARG_ray_o;
    static_assert(etk::ETK_FIELD_ray_o == 0, "ray_o is the first path field");
    for (const FieldRead& r : reads)
        queue_.enqueueReadBuffer(args_[first + r.field], CL_FALSE, 0,
                                 path_field_bytes(r.field) * static_cast<size_t>(n), r.to);
    queue_.finish(); // the reads above are non-blocking
}

void ClDevice::with_mapped(int arg, size_t words, cl_map_flags flags,
                           const std::function<void(void*)>& f) {
    cl::CommandQueue& q = lanes_[0]->queue();
    void* p = q.enqueueMapBuffer(args_[arg], CL_TRUE, flags, 0, sizeof(cl_uint) * words);
    struct Unmap { // also when f throws
        cl::CommandQueue& q;
        cl::Buffer& b;
        void* p;
        ~Unmap() {
            try {
                q.enqueueUnmapMemObject(b, p);
                q.finish();
            } catch (const cl::Error&) {
            }
        }
    } unmap{q, args_[arg], p};
    f(p);
}

// Between passes (no lane is running), waited for, so every lane's later launches see it. Where
// the device shares the host's memory, the changed spans into the mapped buffer; elsewhere every
// float in one write: one transfer of tens of megabytes costs less than a write per changed
// cell's table.
void ClDevice::upload_guide(const std::vector<float>& cells,
                            const std::vector<FloatSpan>& changed) {
    // The learned tables are the buffer's first floats (the binned technique's may follow).
    if (cells.size() > guide_floats_)
        throw Error("visibility tables of " + std::to_string(cells.size()) + " floats, more than " +
                    std::to_string(guide_floats_));
    try {
        if (guide_in_place_) { // the floats the update rewrote, no more
            with_mapped(etk::ETK_ARG_guide_cells, guide_floats_, CL_MAP_WRITE, [&](void* p) {
                copy_spans(cells.data(), cells.size(), changed, static_cast<float*>(p));
            });
            return;
        }
        lanes_[0]->queue().enqueueWriteBuffer(args_[etk::ETK_ARG_guide_cells], CL_TRUE, 0,
                                              sizeof(cl_float) * cells.size(), cells.data());
    } catch (const cl::Error& e) {
        throw Error(std::string("cannot upload the visibility tables (") + e.what() +
                    "): " + cl_error_name(e.err()));
    }
}

// Zeroes written from the host, a few megabytes at a time, rather than by zero_words: tens of
// megabytes of work-items take minutes under Oclgrind, whose uninitialised-value check counts a
// host write (not a fill) as a definition. The writes are queued without waiting (their source
// is a static block of zeros, alive and unchanged throughout) and waited for once.
void ClDevice::zero_guide_sums() {
    static const std::vector<cl_uint> zeros(size_t(1) << 20, 0u);
    cl::CommandQueue& q = lanes_[0]->queue();
    for (size_t at = 0; at < guide_words_; at += zeros.size())
        q.enqueueWriteBuffer(args_[etk::ETK_ARG_guide_sums], CL_FALSE, sizeof(cl_uint) * at,
                             sizeof(cl_uint) * std::min(zeros.size(), guide_words_ - at),
                             zeros.data());
    q.finish();
}

// Between passes (no lane is running): the sums, then zeroes in their place.
void ClDevice::absorb_guide_sums(const GuideSumsAbsorb& absorb) {
    if (guide_in_place_) { // absorb leaves the words zero, as the passes to come need them
        try {
            with_mapped(etk::ETK_ARG_guide_sums, guide_words_, CL_MAP_READ | CL_MAP_WRITE,
                        [&](void* p) { absorb(static_cast<uint32_t*>(p), guide_words_); });
        } catch (const cl::Error& e) {
            throw Error(std::string("cannot map the visibility records (") + e.what() +
                        "): " + cl_error_name(e.err()));
        }
        return;
    }
    guide_sums_copy_.resize(guide_words_);
    try {
        ClLane& l = *lanes_[0];
        l.queue().enqueueReadBuffer(args_[etk::ETK_ARG_guide_sums], CL_TRUE, 0,
                                    sizeof(cl_uint) * guide_words_, guide_sums_copy_.data());
        zero_guide_sums();
    } catch (const cl::Error& e) {
        throw Error(std::string("cannot read the visibility records (") + e.what() +
                    "): " + cl_error_name(e.err()));
    }
    absorb(guide_sums_copy_.data(), guide_sums_copy_.size());
}

// `items` work-items (rounded up to whole work-groups) of a stage whose kernel argument n is
// `n` (< 0: the queue's counter says how many work).
void ClLane::enqueue_stage(int stage, int n, int items, const etk::EtkParams& params) {
    cl::Kernel& k = kernels_[stage];
    k.setArg(etk::ETK_ARG_params, sizeof(params), &params);
    k.setArg(etk::ETK_ARG_n, n);
    const size_t local = local_[stage];
    cl::Event ev;
    queue_.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((items + local - 1) / local * local),
                                cl::NDRange(local), nullptr, &ev);
    pending_.emplace_back(stage, ev);
}

void ClLane::launch(int stage, int n, const etk::EtkParams& params) {
    if (n > 0)
        enqueue_stage(stage, n, n, params);
}

// One work-item; not timed (a stage's share would hide it).
void ClLane::next_bounce(int first_rays) {
    next_bounce_.setArg(1, static_cast<cl_int>(first_rays));
    queue_.enqueueNDRangeKernel(next_bounce_, cl::NullRange, cl::NDRange(1), cl::NDRange(1));
}

// Every work-item past the queue's size returns at once (wavefront.cl, n < 0).
void ClLane::launch_counted(int stage, int most, const etk::EtkParams& params) {
    if (most > 0)
        enqueue_stage(stage, -1, most, params);
}

// Zeroed on the device rather than uploaded from the host's zeroed film: a 512x512 film is 16 MB
// each way per pass, 3-4% of a pass on PoCL. Zeroed by lane 0 and waited for, since
// every lane writes the film.
void ClDevice::clear_film(bool aovs) {
    ClLane& l = *lanes_[0];
#define ET_CLEAR(type, name)                                                                       \
    if (aovs || !film_field_is_aov(etk::ETK_ARG_##name))                                           \
        l.zero_words(args_[etk::ETK_ARG_##name], sizeof(type) * pixels_ / 4);
    ETK_FILM_FIELDS(ET_CLEAR)
#undef ET_CLEAR
    l.queue().finish();
}

// After finish(): lane 0's queue runs the fold after every lane's launches, and the next
// clear_film (on that queue, waited for) after the fold.
void ClDevice::fold_film() {
    try {
        lanes_[0]->queue().enqueueNDRangeKernel(
            fold_kernel_, cl::NullRange,
            cl::NDRange((pixels_ + fold_local_ - 1) / fold_local_ * fold_local_),
            cl::NDRange(fold_local_));
    } catch (const cl::Error& e) {
        throw Error(std::string("cannot add the pass to the film's sums on the device (") +
                    e.what() + "): " + cl_error_name(e.err()));
    }
}

void ClDevice::take_film_sums(FilmSums& sums) {
    if (sums.pixels() != static_cast<size_t>(pixels_))
        throw Error("the device's film sums are for another film size (a bug)");
    // In chunks: a second copy of the whole sums (112 bytes a pixel, 1.9 GB at 4096²) would
    // double what the renderer's memory check counted.
    constexpr size_t kChunk = size_t(1) << 16;
    std::vector<FilmSums::Pixel> chunk(std::min(kChunk, sums.pixels()));
    try {
        ClLane& l = *lanes_[0];
        for (size_t at = 0; at < sums.pixels(); at += kChunk) {
            const size_t n = std::min(kChunk, sums.pixels() - at);
            l.queue().enqueueReadBuffer(film_fixed_, CL_TRUE, sizeof(FilmSums::Pixel) * at,
                                        sizeof(FilmSums::Pixel) * n, chunk.data());
            FilmSums::add_pixels(sums.data() + at, chunk.data(), n);
        }
        l.zero_words(film_fixed_, sizeof(FilmSums::Pixel) / 4 * sums.pixels());
        l.finish();
    } catch (const cl::Error& e) {
        throw Error(std::string("cannot read the film's sums from the device (") + e.what() +
                    "): " + cl_error_name(e.err()));
    }
}

// After finish(): every lane's launches are done.
void ClDevice::download_film(Film& film, bool aovs) {
    cl::CommandQueue& q = lanes_[0]->queue();
#define ET_READ(type, name)                                                                        \
    if (aovs || !film_field_is_aov(etk::ETK_ARG_##name))                                           \
        q.enqueueReadBuffer(args_[etk::ETK_ARG_##name], CL_TRUE, 0, sizeof(type) * film.pixels(),  \
                            film.name.data());
    ETK_FILM_FIELDS(ET_READ)
#undef ET_READ
}

std::vector<std::pair<std::string, double>> ClDevice::stage_seconds() {
    std::vector<std::pair<std::string, double>> out;
    for (int s = 0; s < etk::ETK_STAGE_COUNT; ++s) {
        double t = 0.0;
        for (const auto& l : lanes_)
            t += l->seconds()[s];
        out.emplace_back(stage_name(s), t);
    }
    return out;
}

} // namespace et
