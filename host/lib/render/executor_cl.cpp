#include "render/executor_cl.h"

#include "util/error.h"

#include <algorithm>

namespace et {
namespace {

constexpr int kLocal = 64; // one fixed work-group size for every kernel

// Device bytes per path in flight: the path fields and the queues (ray_in and ray_out are two
// buffers that swap).
#define ET_FIELD_BYTES(type, name) +sizeof(type)
#define ET_QUEUE_BYTES(name) +sizeof(int)
constexpr size_t kBytesPerPath = 0 ETK_PATH_FIELDS(ET_FIELD_BYTES) ETK_QUEUES(ET_QUEUE_BYTES);
#undef ET_FIELD_BYTES
#undef ET_QUEUE_BYTES

// A read-only buffer over `v`, which the DeviceScene keeps alive for the renderer's lifetime:
// CL_MEM_USE_HOST_PTR lets a CPU device (PoCL) read the host vector in place instead of holding
// a second copy of a map that may be gigabytes; a GPU copies it as it would anyway. Device
// buffers cannot be empty: an empty vector gets one zero element.
template <typename T> cl::Buffer upload(cl::Context& ctx, const std::vector<T>& v) {
    static const T zero{};
    const void* data = v.empty() ? &zero : v.data();
    return cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR,
                      std::max<size_t>(1, v.size()) * sizeof(T), const_cast<void*>(data));
}

} // namespace

ClDevice::ClDevice(std::unique_ptr<ClRuntime> rt_ptr, const DeviceScene& scene, int paths,
                   ProgramBuildInfo* build)
    : rt_(std::move(rt_ptr)), pixels_(scene.width() * scene.height()) {
    ClRuntime& rt = *rt_;
    const cl::Device& dev = rt.device().device;
    const size_t max_alloc = dev.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
    const size_t global_mem = dev.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
    const int cap = static_cast<int>(
        std::min<size_t>({size_t(1) << 22, max_alloc / 16, global_mem / 4 / kBytesPerPath}));
    paths_ = std::max(1, std::min(paths > 0 ? paths : pixels_, std::min(cap, pixels_)));
    try {
        queue_ = cl::CommandQueue(rt.context(), dev, CL_QUEUE_PROFILING_ENABLE);
        program_ = rt.build("wavefront.cl", "", build);
        for (int s = 0; s < etk::ETK_STAGE_COUNT; ++s)
            kernels_.emplace_back(program_, stage_name(s));
        seconds_.assign(etk::ETK_STAGE_COUNT, 0.0);
        auto& ctx = rt.context();
        args_.resize(etk::ETK_ARG_COUNT);
        const size_t n = static_cast<size_t>(paths_), px = static_cast<size_t>(pixels_);
#define ET_UPLOAD(type, name) args_[etk::ETK_ARG_##name] = upload(ctx, scene.name);
        ETK_SCENE_BUFFERS(ET_UPLOAD)
#undef ET_UPLOAD
#define ET_ALLOC(type, name)                                                                       \
    args_[etk::ETK_ARG_##name] = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(type) * n);
        ETK_PATH_FIELDS(ET_ALLOC)
#undef ET_ALLOC
        for (int q : {etk::ETK_ARG_escaped, etk::ETK_ARG_shade, etk::ETK_ARG_shadow})
            args_[q] = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_int) * n);
        queue_a_ = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_int) * n);
        queue_b_ = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_int) * n);
#define ET_FILM(type, name)                                                                        \
    args_[etk::ETK_ARG_##name] = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(type) * px);            \
    queue_.enqueueFillBuffer(args_[etk::ETK_ARG_##name], 0.0f, 0, sizeof(type) * px);
        ETK_FILM_FIELDS(ET_FILM)
#undef ET_FILM
        args_[etk::ETK_ARG_counters] =
            cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_uint) * etk::ETK_Q_COUNT);
        for (auto& k : kernels_)
            for (int a = 0; a < etk::ETK_ARG_params; ++a)
                if (a != etk::ETK_ARG_ray_in && a != etk::ETK_ARG_ray_out)
                    k.setArg(a, args_[a]);
    } catch (const cl::Error& e) {
        throw Error(std::string("cannot set up the OpenCL renderer (") + e.what() +
                    "): " + cl_error_name(e.err()) + "; try a smaller film or --paths");
    }
}

void ClDevice::run_lanes(const std::function<void(int)>& f) {
    try {
        f(0);
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL rendering failed (") + e.what() +
                    "): " + cl_error_name(e.err()));
    }
}

void ClDevice::finish() {
    queue_.finish();
    // Profiling times of the finished launches, so that events are not kept for the whole render.
    for (auto& [stage, ev] : pending_)
        seconds_[stage] += (ev.getProfilingInfo<CL_PROFILING_COMMAND_END>() -
                            ev.getProfilingInfo<CL_PROFILING_COMMAND_START>()) *
                           1e-9;
    pending_.clear();
}

void ClDevice::bind_queues(bool swapped) {
    for (auto& k : kernels_) {
        k.setArg(etk::ETK_ARG_ray_in, swapped ? queue_b_ : queue_a_);
        k.setArg(etk::ETK_ARG_ray_out, swapped ? queue_a_ : queue_b_);
    }
}

void ClDevice::reset_counters() {
    queue_.enqueueFillBuffer(args_[etk::ETK_ARG_counters], cl_uint(0), 0,
                             sizeof(cl_uint) * etk::ETK_Q_COUNT);
}

void ClDevice::read_counters(uint32_t* out) {
    queue_.enqueueReadBuffer(args_[etk::ETK_ARG_counters], CL_TRUE, 0,
                             sizeof(cl_uint) * etk::ETK_Q_COUNT, out);
}

void ClDevice::read_learning(int n, int* bins) {
    queue_.enqueueReadBuffer(args_[etk::ETK_ARG_learn_bin], CL_TRUE, 0, sizeof(cl_int) * n, bins);
}

void ClDevice::launch(int stage, int n, const etk::EtkParams& params) {
    if (n <= 0)
        return;
    cl::Kernel& k = kernels_[stage];
    k.setArg(etk::ETK_ARG_params, sizeof(params), &params);
    k.setArg(etk::ETK_ARG_n, n);
    cl::Event ev;
    queue_.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((n + kLocal - 1) / kLocal * kLocal),
                                cl::NDRange(kLocal), nullptr, &ev);
    pending_.emplace_back(stage, ev);
}

void ClDevice::download_film(Film& film) {
#define ET_READ(type, name)                                                                        \
    queue_.enqueueReadBuffer(args_[etk::ETK_ARG_##name], CL_TRUE, 0, sizeof(type) * film.pixels(), \
                             film.name.data());
    ETK_FILM_FIELDS(ET_READ)
#undef ET_READ
}

void ClDevice::upload_film(const Film& film) {
#define ET_WRITE(type, name)                                                                       \
    queue_.enqueueWriteBuffer(args_[etk::ETK_ARG_##name], CL_TRUE, 0,                              \
                              sizeof(type) * film.pixels(), film.name.data());
    ETK_FILM_FIELDS(ET_WRITE)
#undef ET_WRITE
}

std::vector<std::pair<std::string, double>> ClDevice::stage_seconds() {
    std::vector<std::pair<std::string, double>> out;
    for (int s = 0; s < etk::ETK_STAGE_COUNT; ++s) {
        out.emplace_back(stage_name(s), seconds_[s]);
    }
    return out;
}

} // namespace et
