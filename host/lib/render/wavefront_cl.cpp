#include "render/wavefront_cl.h"

#include "util/error.h"
#include "util/timer.h"

#include <algorithm>

namespace et {
namespace {

const char* kStages[] = {"generate",   "intersect",     "escaped_rays",
                         "shade_hits", "trace_shadows", "accumulate"};
enum { GENERATE, INTERSECT, ESCAPED, SHADE, SHADOW, ACCUMULATE, STAGES };
constexpr int kLocal = 64; // one fixed work-group size for every kernel
// Argument positions in ETK_KERNEL_ARGS.
constexpr int kArgRayIn = 16, kArgRayOut = 17, kArgParams = 23, kArgN = 24;
constexpr size_t kBytesPerPath = 8 * 16 + 4 + 5 * 4;

template <typename T> cl::Buffer upload(cl::Context& ctx, const std::vector<T>& v) {
    std::vector<T> copy = v;
    if (copy.empty())
        copy.resize(1);
    return cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, copy.size() * sizeof(T),
                      copy.data());
}

} // namespace

WavefrontCL::WavefrontCL(std::unique_ptr<ClRuntime> rt_ptr, const SceneArrays& a,
                         const etk::EtkParams& params, int paths, ProgramBuildInfo* build)
    : rt_(std::move(rt_ptr)), params_(params), pixels_(params.width * params.height) {
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
        for (const char* name : kStages)
            kernels_.emplace_back(program_, name);
        events_.resize(STAGES);
        auto& ctx = rt.context();
        nodes_ = upload(ctx, a.bvh.nodes);
        tris_ = upload(ctx, a.tris);
        normals_ = upload(ctx, a.normals);
        tri_material_ = upload(ctx, a.tri_material);
        materials_ = upload(ctx, a.materials);
        env_dist_ = upload(ctx, a.env->dist.table);
        env_texels_ = upload(ctx, a.env->image.rgb);
        const size_t f4 = sizeof(cl_float4) * paths_, i4 = sizeof(cl_int) * paths_;
        for (cl::Buffer* b :
             {&ray_o_, &ray_d_, &beta_, &radiance_, &hit_, &shadow_o_, &shadow_d_, &shadow_L_})
            *b = cl::Buffer(ctx, CL_MEM_READ_WRITE, f4);
        for (cl::Buffer* b : {&pixel_, &queue_a_, &queue_b_, &escaped_, &shade_, &shadow_})
            *b = cl::Buffer(ctx, CL_MEM_READ_WRITE, i4);
        counters_ = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_uint) * ETK_Q_COUNT);
        film_ = cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_float4) * pixels_);
        queue_.enqueueFillBuffer(film_, 0.0f, 0, sizeof(cl_float4) * pixels_);
        const cl::Buffer* args[] = {
            &nodes_,      &tris_,     &normals_,  &tri_material_, &materials_, &env_dist_,
            &env_texels_, &ray_o_,    &ray_d_,    &beta_,         &radiance_,  &hit_,
            &shadow_o_,   &shadow_d_, &shadow_L_, &pixel_,        &queue_a_,   &queue_b_,
            &escaped_,    &shade_,    &shadow_,   &counters_,     &film_};
        for (auto& k : kernels_)
            for (int i = 0; i < 23; ++i)
                k.setArg(i, *args[i]);
    } catch (const cl::Error& e) {
        throw Error(std::string("cannot set up the OpenCL renderer (") + e.what() +
                    "): " + cl_error_name(e.err()) + "; try a smaller film or --paths");
    }
}

void WavefrontCL::set_queue_args(const cl::Buffer& in, const cl::Buffer& out) {
    for (auto& k : kernels_) {
        k.setArg(kArgRayIn, in);
        k.setArg(kArgRayOut, out);
    }
}

void WavefrontCL::launch(int stage, int n) {
    if (n <= 0)
        return;
    cl::Kernel& k = kernels_[stage];
    k.setArg(kArgParams, sizeof(params_), &params_);
    k.setArg(kArgN, n);
    cl::Event ev;
    queue_.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((n + kLocal - 1) / kLocal * kLocal),
                                cl::NDRange(kLocal), nullptr, &ev);
    events_[stage].push_back(ev);
}

void WavefrontCL::zero_counters() {
    queue_.enqueueFillBuffer(counters_, cl_uint(0), 0, sizeof(cl_uint) * ETK_Q_COUNT);
}

void WavefrontCL::read_counters(uint32_t* out) {
    queue_.enqueueReadBuffer(counters_, CL_TRUE, 0, sizeof(cl_uint) * ETK_Q_COUNT, out);
}

void WavefrontCL::render_sample(uint32_t sample_index) {
    Timer timer;
    try {
        params_.sample_index = sample_index;
        for (int first = 0; first < pixels_; first += paths_) {
            const int n = std::min(paths_, pixels_ - first);
            params_.first_pixel = first;
            set_queue_args(queue_b_, queue_a_); // generate fills queue A
            launch(GENERATE, n);
            stats_.camera_rays += n;
            int rays = n;
            bool swap = false;
            for (int bounce = 0; rays > 0; ++bounce) {
                if (bounce > 0)
                    stats_.continuation_rays += rays;
                swap ? set_queue_args(queue_b_, queue_a_) : set_queue_args(queue_a_, queue_b_);
                zero_counters();
                launch(INTERSECT, rays);
                uint32_t c[ETK_Q_COUNT];
                read_counters(c);
                launch(ESCAPED, static_cast<int>(c[ETK_Q_ESCAPED]));
                launch(SHADE, static_cast<int>(c[ETK_Q_SHADE]));
                read_counters(c);
                launch(SHADOW, static_cast<int>(c[ETK_Q_SHADOW]));
                stats_.shadow_rays += c[ETK_Q_SHADOW];
                rays = static_cast<int>(c[ETK_Q_RAY_OUT]);
                swap = !swap;
            }
            launch(ACCUMULATE, n);
            uint32_t c[ETK_Q_COUNT]; // the last bounce zeroed them: this is accumulate's count
            read_counters(c);
            stats_.nonfinite_samples += c[ETK_Q_NONFINITE];
        }
        queue_.finish();
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL rendering failed (") + e.what() +
                    "): " + cl_error_name(e.err()));
    }
    stats_.samples_per_pixel += 1;
    stats_.seconds += timer.seconds();
}

std::vector<float> WavefrontCL::image() {
    std::vector<cl_float4> film(pixels_);
    queue_.enqueueReadBuffer(film_, CL_TRUE, 0, sizeof(cl_float4) * pixels_, film.data());
    std::vector<float> rgb(3 * static_cast<size_t>(pixels_));
    for (int p = 0; p < pixels_; ++p) {
        const float inv = film[p].s[3] > 0.0f ? 1.0f / film[p].s[3] : 0.0f;
        for (int c = 0; c < 3; ++c)
            rgb[3 * p + c] = film[p].s[c] * inv;
    }
    return rgb;
}

const RenderStats& WavefrontCL::stats() {
    // Stage times from the profiling events collected so far.
    stats_.stage_seconds.clear();
    for (int s = 0; s < STAGES; ++s) {
        double t = 0.0;
        for (auto& ev : events_[s])
            t += (ev.getProfilingInfo<CL_PROFILING_COMMAND_END>() -
                  ev.getProfilingInfo<CL_PROFILING_COMMAND_START>()) *
                 1e-9;
        stats_.stage_seconds.emplace_back(kStages[s], t);
    }
    return stats_;
}

} // namespace et
