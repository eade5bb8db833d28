// Ray traversal throughput: the same rays through envtrace's BVH (native, and the
// OpenCL back end through tests/kernels/cl/bvh_test.cl), through the BVH as it was before the SAH
// and 4-wide rewrite (bvh_baseline.*, native) and, when CMake found it, through Embree (an optional
// benchmark
// dependency, never one of the renderer). Also: the SAH cost of each tree (traversal 1, triangle
// 1, relative to the root's area) and, with Embree, the SAH cost of Embree's own builder
// (rtcBuildBVH, binary, leaves of <= 4) and that tree traced by envtrace's traversal.
//
// Rays: the scene's camera rays (one per sample, pixel jitter from the sampler at the scene's seed)
// and, at every camera hit on a non-delta surface, the shadow ray of the shade stage at depth 0
// (etk_env_sample of sample pair 1, from the offset surface origin; dropped when below the
// geometric or shading surface, as the shade stage does) and a diffuse bounce ray (cosine-
// distributed about the geometric normal on the camera's side, from a fixed-seed hash: incoherent
// rays that start on the surface, as a path's later segments do). Generated once, then each tracer
// runs over the same arrays; camera and bounce rays are closest-hit, shadow rays any-hit, all with
// tmax 3e38. Each run times every tracer once, interleaved, so the ratios of a run are side by
// side. --native-only leaves out the older BVH and the trees of Embree's builder (their builds
// take minutes on millions of triangles). --cpu-time times the process's CPU seconds (all
// threads) instead of wall time: Mrays per CPU-second, steadier on a machine whose cores other
// processes share (not for the OpenCL row: PoCL's idle workers may spin). --embree-config
// passes a configuration string to rtcNewDevice ("isa=avx2": Embree's AVX2 kernels on a host
// with AVX-512, whose 16-wide ones it picks by default; "verbose=1" prints its choice).
//
// Usage: bench_rays SCENE [--spp N] [--runs R] [--threads T] [--no-opencl] [--native-only]
//                   [--cpu-time] [--embree-config S] [--json F]
#include "bvh_baseline.h"
#include "kernels/integrator.h"
#include "load/scene.h"
#include "opencl/opencl_runtime.h"
#include "prepare/bvh_build.h"
#include "prepare/device_scene.h"
#include "util/json_file.h"
#include "util/parallel.h"
#include "util/timer.h"
#include "test_kernels.h"

#include <nlohmann/json.hpp>

#ifdef ENVTRACE_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

#include <algorithm>
#include <atomic>
#include <ctime>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

using etk::float4;
using nlohmann::json;

namespace {

struct Rays {
    std::vector<float4> org, dir; // org.w = tmax
    size_t size() const { return org.size(); }
};

// A tracer writes, per ray, the soup index of the triangle hit (closest) or 1/0 (any hit), -1 for
// none. The result vectors let the tracers be checked against each other.
using Tracer = std::function<void(const Rays&, bool any, std::vector<int>&)>;

// Seconds of CPU time used by the whole process (all threads): with --cpu-time, what a tracer
// costs stays put when other processes share the cores (wall time counts their slices too).
double process_cpu_seconds() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

etk::float3 xyz(float4 v) {
    return etk::make_float3(v.x, v.y, v.z);
}

// Runs f(i) for i in [0, n) on `threads` threads, in chunks (as the native back end does).
template <typename F> void parallel_for(int threads, size_t n, F&& f) {
    std::atomic<size_t> next{0};
    et::run_on_threads(threads, [&](int) {
        for (size_t begin; (begin = next.fetch_add(1024)) < n;)
            for (size_t i = begin, end = std::min(n, begin + 1024); i < end; ++i)
                f(i);
    });
}

// A native tracer over any traversal function with etk_bvh_traverse's signature.
template <typename Traverse>
Tracer native_tracer(const float4* nodes, const float4* tris, const std::vector<int>& order,
                     int threads, Traverse traverse) {
    return [nodes, tris, &order, threads, traverse](const Rays& r, bool any,
                                                    std::vector<int>& out) {
        parallel_for(threads, r.size(), [&](size_t i) {
            etk::EtkHit h;
            const int hit =
                traverse(nodes, tris, xyz(r.org[i]), xyz(r.dir[i]), r.org[i].w, any ? 1 : 0, &h);
            out[i] = !hit ? -1 : any ? 1 : order[h.prim];
        });
    };
}
template <typename Traverse>
Tracer native_tracer(const std::vector<float4>& nodes, const std::vector<float4>& tris,
                     const std::vector<int>& order, int threads, Traverse traverse) {
    return native_tracer(nodes.data(), tris.data(), order, threads, traverse);
}

// The OpenCL back end: tests/kernels/cl/bvh_test.cl (etk_bvh_traverse, one ray per work-item).
class ClTracer {
  public:
    ClTracer(int device, const std::vector<float4>& nodes, const std::vector<float4>& tris,
             const std::vector<int>& order)
        : rt_(device), order_(order) {
        program_ = ett::build_test_kernel(rt_, "bvh_test.cl");
        k_ = cl::Kernel(program_, "bvh_trace");
        nodes_ = buffer(nodes);
        tris_ = buffer(tris);
        k_.setArg(0, nodes_);
        k_.setArg(1, tris_);
    }
    std::string name() const { return rt_.device().platform_name; }
    // Uploads once per ray set; time() then runs the kernel only.
    void load(const Rays& r, int slot) {
        org_[slot] = buffer(r.org);
        dir_[slot] = buffer(r.dir);
        n_[slot] = r.size();
        out_[slot] = cl::Buffer(rt_.context(), CL_MEM_WRITE_ONLY,
                                std::max<size_t>(1, r.size()) * sizeof(cl_float4));
    }
    void trace(int slot, bool any, std::vector<int>& out) {
        k_.setArg(2, org_[slot]);
        k_.setArg(3, dir_[slot]);
        k_.setArg(4, cl_int(any ? 1 : 0));
        k_.setArg(5, static_cast<cl_int>(n_[slot]));
        k_.setArg(6, out_[slot]);
        const size_t global = (n_[slot] + 63) / 64 * 64;
        rt_.queue().enqueueNDRangeKernel(k_, cl::NullRange, cl::NDRange(global), cl::NDRange(64));
        rt_.queue().finish();
        last_slot_ = slot;
        last_any_ = any;
        last_out_ = &out;
    }
    // Reads the last results back (outside the timed part).
    void read_back() {
        std::vector<float4> res(n_[last_slot_]);
        rt_.queue().enqueueReadBuffer(out_[last_slot_], CL_TRUE, 0, res.size() * sizeof(float4),
                                      res.data());
        for (size_t i = 0; i < res.size(); ++i) {
            const int prim = static_cast<int>(etk::as_uint(res[i].y));
            (*last_out_)[i] = prim < 0 ? -1 : last_any_ ? 1 : order_[prim];
        }
    }

  private:
    cl::Buffer buffer(const std::vector<float4>& v) {
        return cl::Buffer(rt_.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                          v.size() * sizeof(float4), const_cast<float4*>(v.data()));
    }
    et::ClRuntime rt_;
    const std::vector<int>& order_;
    cl::Program program_;
    cl::Kernel k_;
    cl::Buffer nodes_, tris_, org_[3], dir_[3], out_[3];
    size_t n_[3] = {0, 0, 0};
    int last_slot_ = 0;
    bool last_any_ = false;
    std::vector<int>* last_out_ = nullptr;
};

#ifdef ENVTRACE_HAVE_EMBREE
struct Embree {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    double build_seconds = 0;

    Embree(const et::TriangleSoup& soup, const std::string& config) {
        device = rtcNewDevice(config.empty() ? nullptr : config.c_str());
        if (!device)
            throw std::runtime_error("Embree: rtcNewDevice failed");
        scene = rtcNewScene(device);
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        const size_t n = soup.size();
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * n));
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
        for (size_t i = 0; i < 3 * n; ++i) {
            v[3 * i] = soup.positions[i].x;
            v[3 * i + 1] = soup.positions[i].y;
            v[3 * i + 2] = soup.positions[i].z;
            idx[i] = static_cast<unsigned>(i);
        }
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
        et::Timer t;
        rtcCommitScene(scene);
        build_seconds = t.seconds();
    }
    ~Embree() {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
    }
    Tracer tracer(int threads) {
        return [this, threads](const Rays& r, bool any, std::vector<int>& out) {
            parallel_for(threads, r.size(), [&](size_t i) {
                RTCIntersectContext ctx;
                rtcInitIntersectContext(&ctx);
                RTCRayHit rh;
                const float4 o = r.org[i], d = r.dir[i];
                rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
                rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
                rh.ray.tnear = 0.0f;
                rh.ray.tfar = o.w;
                rh.ray.time = 0.0f;
                rh.ray.mask = ~0u;
                rh.ray.id = 0;
                rh.ray.flags = 0;
                if (any) {
                    rtcOccluded1(scene, &ctx, &rh.ray);
                    out[i] = rh.ray.tfar < 0.0f ? 1 : -1;
                } else {
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene, &ctx, &rh);
                    out[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID
                                 ? -1
                                 : static_cast<int>(rh.hit.primID);
                }
            });
        };
    }
};

// Embree's BVH builder (rtcBuildBVH) making a binary tree with leaves of <= 4 triangles and
// SAH constants 1 / 1, turned into et::BvhTreeNode so that flatten_bvh gives the kernels' layout
// and the SAH cost by the same formula as envtrace's tree. quality HIGH adds spatial splits
// (a triangle may then sit in several leaves: `order` repeats it).
struct EmbreeNode {
    bool leaf = false;
    RTCBounds bounds[2];
    EmbreeNode* child[2] = {nullptr, nullptr};
    std::vector<unsigned> prims;
};

et::Bvh embree_built_tree(RTCDevice device, const et::TriangleSoup& soup, RTCBuildQuality q,
                          double* seconds) {
    const size_t n = soup.size();
    std::vector<RTCBuildPrimitive> prims(q == RTC_BUILD_QUALITY_HIGH ? 2 * n : n);
    for (size_t i = 0; i < n; ++i) {
        glm::vec3 lo = soup.positions[3 * i], hi = lo;
        for (int k = 1; k < 3; ++k) {
            lo = glm::min(lo, soup.positions[3 * i + k]);
            hi = glm::max(hi, soup.positions[3 * i + k]);
        }
        prims[i] = {lo.x, lo.y, lo.z, 0u, hi.x, hi.y, hi.z, static_cast<unsigned>(i)};
    }
    std::vector<std::unique_ptr<EmbreeNode>> pool;
    std::mutex pool_mutex;
    struct User {
        std::vector<std::unique_ptr<EmbreeNode>>* pool;
        std::mutex* m;
        const et::TriangleSoup* soup;
        EmbreeNode* make() {
            std::lock_guard<std::mutex> l(*m);
            pool->push_back(std::make_unique<EmbreeNode>());
            return pool->back().get();
        }
    } user{&pool, &pool_mutex, &soup};
    RTCBVH bvh = rtcNewBVH(device);
    RTCBuildArguments a = rtcDefaultBuildArguments();
    a.byteSize = sizeof(a);
    a.buildFlags = RTC_BUILD_FLAG_NONE;
    a.buildQuality = q;
    a.maxBranchingFactor = 2;
    a.maxDepth = 60; // as envtrace's builder (kMaxDepth)
    a.sahBlockSize = 1;
    a.minLeafSize = 1;
    a.maxLeafSize = 4;
    a.traversalCost = 1.0f;
    a.intersectionCost = 1.0f;
    a.bvh = bvh;
    a.primitives = prims.data();
    a.primitiveCount = n;
    a.primitiveArrayCapacity = prims.size();
    a.userPtr = &user;
    a.createNode = [](RTCThreadLocalAllocator, unsigned, void* u) -> void* {
        return static_cast<User*>(u)->make();
    };
    a.setNodeChildren = [](void* node, void** children, unsigned count, void*) {
        for (unsigned k = 0; k < count; ++k)
            static_cast<EmbreeNode*>(node)->child[k] = static_cast<EmbreeNode*>(children[k]);
    };
    a.setNodeBounds = [](void* node, const RTCBounds** b, unsigned count, void*) {
        for (unsigned k = 0; k < count; ++k)
            static_cast<EmbreeNode*>(node)->bounds[k] = *b[k];
    };
    a.createLeaf = [](RTCThreadLocalAllocator, const RTCBuildPrimitive* p, size_t count,
                      void* u) -> void* {
        EmbreeNode* l = static_cast<User*>(u)->make();
        l->leaf = true;
        for (size_t k = 0; k < count; ++k)
            l->prims.push_back(p[k].primID);
        return l;
    };
    a.splitPrimitive = [](const RTCBuildPrimitive* p, unsigned dim, float pos, RTCBounds* lb,
                          RTCBounds* rb, void* u) {
        // Clip the triangle (not just its box) at pos along dim, as Embree's own SBVH does.
        const et::TriangleSoup& s = *static_cast<User*>(u)->soup;
        glm::vec3 llo(1e30f), lhi(-1e30f), rlo(1e30f), rhi(-1e30f);
        auto grow = [](glm::vec3& lo, glm::vec3& hi, glm::vec3 v) {
            lo = glm::min(lo, v);
            hi = glm::max(hi, v);
        };
        for (int k = 0; k < 3; ++k) {
            const glm::vec3 v0 = s.positions[3 * p->primID + k];
            const glm::vec3 v1 = s.positions[3 * p->primID + (k + 1) % 3];
            if (v0[dim] <= pos)
                grow(llo, lhi, v0);
            if (v0[dim] >= pos)
                grow(rlo, rhi, v0);
            if ((v0[dim] < pos && v1[dim] > pos) || (v0[dim] > pos && v1[dim] < pos)) {
                const glm::vec3 c = v0 + (v1 - v0) * ((pos - v0[dim]) / (v1[dim] - v0[dim]));
                grow(llo, lhi, c);
                grow(rlo, rhi, c);
            }
        }
        const glm::vec3 plo(p->lower_x, p->lower_y, p->lower_z);
        const glm::vec3 phi(p->upper_x, p->upper_y, p->upper_z);
        llo = glm::max(llo, plo), lhi = glm::min(lhi, phi);
        rlo = glm::max(rlo, plo), rhi = glm::min(rhi, phi);
        lhi[dim] = std::min(lhi[dim], pos);
        rlo[dim] = std::max(rlo[dim], pos);
        *lb = {llo.x, llo.y, llo.z, 0.0f, lhi.x, lhi.y, lhi.z, 0.0f};
        *rb = {rlo.x, rlo.y, rlo.z, 0.0f, rhi.x, rhi.y, rhi.z, 0.0f};
    };
    et::Timer t;
    auto* root = static_cast<EmbreeNode*>(rtcBuildBVH(&a));
    *seconds = t.seconds();
    // To et::BvhTreeNode: depth-first, leaves' triangles appended to `order`.
    std::vector<et::BvhTreeNode> tree;
    std::vector<int> order;
    std::function<int(EmbreeNode*, const RTCBounds&)> convert = [&](EmbreeNode* e,
                                                                    const RTCBounds& b) {
        const int index = static_cast<int>(tree.size());
        tree.emplace_back();
        tree[index].lo = glm::vec3(b.lower_x, b.lower_y, b.lower_z);
        tree[index].hi = glm::vec3(b.upper_x, b.upper_y, b.upper_z);
        if (e->leaf) {
            tree[index].first = static_cast<int>(order.size());
            tree[index].count = static_cast<int>(e->prims.size());
            for (unsigned p : e->prims)
                order.push_back(static_cast<int>(p));
            return index;
        }
        const int l = convert(e->child[0], e->bounds[0]);
        const int r = convert(e->child[1], e->bounds[1]);
        tree[index].left = l;
        tree[index].right = r;
        return index;
    };
    RTCBounds rb{1e30f, 1e30f, 1e30f, 0, -1e30f, -1e30f, -1e30f, 0};
    if (!root->leaf)
        for (const RTCBounds& c : root->bounds) {
            rb.lower_x = std::min(rb.lower_x, c.lower_x),
            rb.upper_x = std::max(rb.upper_x, c.upper_x);
            rb.lower_y = std::min(rb.lower_y, c.lower_y),
            rb.upper_y = std::max(rb.upper_y, c.upper_y);
            rb.lower_z = std::min(rb.lower_z, c.lower_z),
            rb.upper_z = std::max(rb.upper_z, c.upper_z);
        }
    convert(root, rb);
    rtcReleaseBVH(bvh);
    return et::flatten_bvh(std::move(tree), std::move(order));
}
#endif

Rays make_camera_rays(const et::DeviceScene& ds, int spp) {
    etk::EtkParams p = ds.params;
    const int pixels = ds.width() * ds.height();
    Rays r;
    r.org.resize(static_cast<size_t>(pixels) * spp);
    r.dir.resize(r.org.size());
    for (int s = 0; s < spp; ++s) {
        p.sample_index = static_cast<etk::uint>(s);
        for (int px = 0; px < pixels; ++px) {
            const size_t i = static_cast<size_t>(s) * pixels + px;
            const etk::float3 d = etk::etk_camera_dir(p, px);
            r.org[i] = etk::make_float4(p.eye[0], p.eye[1], p.eye[2], 3.0e38f);
            r.dir[i] = etk::make_float4(d.x, d.y, d.z, 0.0f);
        }
    }
    return r;
}

// A uniform float in [0, 1) from a ray index and a stream (a fixed hash: the same rays every run).
float hash01(uint32_t i, uint32_t stream) {
    uint32_t h = i * 0x9e3779b9u ^ (stream + 0x7f4a7c15u) * 0x85ebca6bu;
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

// The shadow and diffuse-bounce rays of the camera hits (see the header); traced with the
// current BVH.
void make_secondary_rays(const et::DeviceScene& ds, const Rays& cam, Rays& shadow, Rays& bounce) {
    const etk::EtkScene S = ds.view();
    etk::EtkParams p = ds.params;
    const size_t pixels = static_cast<size_t>(ds.width()) * ds.height();
    for (size_t i = 0; i < cam.size(); ++i) {
        p.sample_index = static_cast<etk::uint>(i / pixels);
        const int pixel = static_cast<int>(i % pixels);
        etk::EtkHit h;
        if (!etk::etk_bvh_traverse(ds.nodes.data(), ds.packets.data(), xyz(cam.org[i]),
                                   xyz(cam.dir[i]), 3.0e38f, 0, &h))
            continue;
        const etk::EtkSurface s = etk::etk_surface_at(S, p, xyz(cam.org[i]), xyz(cam.dir[i]), h);
        // Cosine about ng on the viewer's side (s.origin's side: ng faces the viewer).
        const float u1 = hash01(static_cast<uint32_t>(i), 1),
                    u2 = hash01(static_cast<uint32_t>(i), 2);
        const float r = std::sqrt(u1), phi = 6.2831853f * u2;
        const glm::vec3 n(s.ng.x, s.ng.y, s.ng.z);
        const glm::vec3 a = std::fabs(n.x) > 0.5f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
        const glm::vec3 t = glm::normalize(glm::cross(a, n)), b = glm::cross(n, t);
        const glm::vec3 w = glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b +
                                           std::sqrt(std::max(0.0f, 1.0f - u1)) * n);
        bounce.org.push_back(etk::make_float4(s.origin.x, s.origin.y, s.origin.z, 3.0e38f));
        bounce.dir.push_back(etk::make_float4(w.x, w.y, w.z, 0.0f));
        if (etk::etk_bsdf_is_delta(s.m))
            continue;
        const etk::EtkEnvSample ls =
            etk::etk_env_sample(ds.env_dist.data(), p.env, etk::etk_dims(p, pixel, 1u));
        const etk::float3 wi = etk::etk_to_local(ls.dir, s.t, s.b, s.ns);
        if (!(ls.pdf > 0.0f) || !(wi.z > 0.0f) || !(etk::dot(ls.dir, s.ng) > 0.0f))
            continue;
        shadow.org.push_back(etk::make_float4(s.origin.x, s.origin.y, s.origin.z, 3.0e38f));
        shadow.dir.push_back(etk::make_float4(ls.dir.x, ls.dir.y, ls.dir.z, 0.0f));
    }
}

constexpr int kSets = 3;
const char* const kSetNames[kSets] = {"camera", "shadow", "bounce"};
constexpr bool kSetAnyHit[kSets] = {false, true, false};

} // namespace

int main(int argc, char** argv) try {
    std::string scene_path, json_file, embree_config;
    int spp = 16, runs = 5, threads = 0;
    bool use_cl = true, native_only = false, cpu_time = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc)
                throw std::runtime_error(a + " needs a value");
            return argv[++i];
        };
        if (a == "--spp")
            spp = std::stoi(next());
        else if (a == "--runs")
            runs = std::stoi(next());
        else if (a == "--threads")
            threads = std::stoi(next());
        else if (a == "--no-opencl")
            use_cl = false;
        else if (a == "--embree-config")
            embree_config = next();
        else if (a == "--cpu-time")
            cpu_time = true;
        else if (a == "--native-only")
            native_only = true;
        else if (a == "--json")
            json_file = next();
        else
            scene_path = a;
    }
    if (scene_path.empty())
        throw std::runtime_error("usage: bench_rays SCENE [--spp N] [--runs R] [--threads T] "
                                 "[--no-opencl] [--native-only] [--cpu-time] [--embree-config S] "
                                 "[--json F]");
    threads = et::thread_count(threads);
    et::Scene scene = et::load_scene(scene_path);
    const et::TriangleSoup soup = scene.triangles;
    et::RenderSettings st = scene.settings;
    st.max_depth = 1;
    const et::DeviceScene ds = et::prepare_device_scene(std::move(scene), st);
    // The renderer's tree again, for its triangle order (the build is deterministic).
    const et::Bvh cur = et::build_bvh(soup);
    if (cur.nodes.size() != ds.nodes.size())
        throw std::runtime_error("the BVH build is not deterministic");

    Rays sets[kSets];
    sets[0] = make_camera_rays(ds, spp);
    make_secondary_rays(ds, sets[0], sets[1], sets[2]);

    struct Entry {
        std::string name;
        Tracer trace;
        double sah = 0, build = 0;
        int nodes_bytes = 0, tris_bytes = 0; // the tree; the triangle data traversal reads
    };
    std::vector<Entry> entries;
    entries.push_back(
        {"envtrace native",
         native_tracer(ds.nodes, ds.packets, cur.order, threads, &etk::etk_bvh_traverse),
         cur.sah_cost, cur.build_seconds, static_cast<int>(ds.nodes.size() * sizeof(float4)),
         static_cast<int>(ds.packets.size() * sizeof(float4))});
    baseline::Bvh base;
    std::vector<float4> base_tris;
    if (!native_only) {
        base = baseline::build_bvh(soup);
        base_tris = et::flatten_triangles(soup, base.order);
        entries.push_back(
            {"baseline native (main d2e3a75)",
             native_tracer(base.nodes, base_tris, base.order, threads, &baseline::bvh_traverse),
             base.sah_cost, base.build_seconds,
             static_cast<int>(base.nodes.size() * sizeof(float4)),
             static_cast<int>(base_tris.size() * sizeof(float4))});
    }
    std::unique_ptr<ClTracer> cl;
    if (use_cl) {
        cl = std::make_unique<ClTracer>(st.device, ds.nodes, ds.packets, cur.order);
        for (int k = 0; k < kSets; ++k)
            cl->load(sets[k], k);
    }
    int embree_row = -1;
#ifdef ENVTRACE_HAVE_EMBREE
    Embree embree(soup, embree_config);
    embree_row = static_cast<int>(entries.size());
    entries.push_back({"Embree rtcIntersect1/rtcOccluded1", embree.tracer(threads), -1,
                       embree.build_seconds, 0, 0});
    double ebuild_m = 0, ebuild_h = 0;
    et::Bvh emb_m, emb_h;
    std::vector<float4> emb_m_packets, emb_h_packets;
    if (!native_only) {
        emb_m = embree_built_tree(embree.device, soup, RTC_BUILD_QUALITY_MEDIUM, &ebuild_m);
        emb_h = embree_built_tree(embree.device, soup, RTC_BUILD_QUALITY_HIGH, &ebuild_h);
        emb_m_packets = et::flatten_packets(soup, emb_m);
        emb_h_packets = et::flatten_packets(soup, emb_h);
        entries.push_back({"envtrace traversal, Embree-built tree (binned SAH)",
                           native_tracer(emb_m.nodes, emb_m_packets, emb_m.order, threads,
                                         &etk::etk_bvh_traverse),
                           emb_m.sah_cost, ebuild_m,
                           static_cast<int>(emb_m.nodes.size() * sizeof(float4)),
                           static_cast<int>(emb_m_packets.size() * sizeof(float4))});
        entries.push_back({"envtrace traversal, Embree-built tree (spatial splits)",
                           native_tracer(emb_h.nodes, emb_h_packets, emb_h.order, threads,
                                         &etk::etk_bvh_traverse),
                           emb_h.sah_cost, ebuild_h,
                           static_cast<int>(emb_h.nodes.size() * sizeof(float4)),
                           static_cast<int>(emb_h_packets.size() * sizeof(float4))});
    }
#endif
    const int n_native = static_cast<int>(entries.size());
    const int n_all = n_native + (cl ? 1 : 0);
    std::vector<std::string> names;
    for (const Entry& e : entries)
        names.push_back(e.name);
    if (cl)
        names.push_back("envtrace OpenCL (" + cl->name() + ")");

    // results[set][tracer] of the last run, checked against tracer 0; seconds[set][tracer] per run.
    std::vector<std::vector<std::vector<int>>> results(kSets, std::vector<std::vector<int>>(n_all));
    std::vector<std::vector<std::vector<double>>> seconds(kSets,
                                                          std::vector<std::vector<double>>(n_all));
    size_t all_rays = 0;
    for (const Rays& r : sets)
        all_rays += r.size();
    for (int run = 0; run < runs; ++run)
        for (int k = 0; k < kSets; ++k)
            for (int e = 0; e < n_all; ++e) {
                std::vector<int>& out = results[k][e];
                out.assign(sets[k].size(), -2);
                et::Timer t;
                const double cpu0 = process_cpu_seconds();
                if (e < n_native)
                    entries[e].trace(sets[k], kSetAnyHit[k], out);
                else
                    cl->trace(k, kSetAnyHit[k], out);
                seconds[k][e].push_back(cpu_time ? process_cpu_seconds() - cpu0 : t.seconds());
                if (e >= n_native)
                    cl->read_back();
            }
    // Medians over runs: Mrays/s per set and over all rays; ratios to tracer `ref` per run.
    auto mrays = [&](int k, int e) {
        std::vector<double> v;
        for (double s : seconds[k][e])
            v.push_back(sets[k].size() / s * 1e-6);
        return median(v);
    };
    auto secs_all = [&](int e, int run) {
        double s = 0;
        for (int k = 0; k < kSets; ++k)
            s += seconds[k][e][run];
        return s;
    };
    auto mrays_all = [&](int e) {
        std::vector<double> v;
        for (int r = 0; r < runs; ++r)
            v.push_back(all_rays / secs_all(e, r) * 1e-6);
        return median(v);
    };
    auto ratio = [&](int k, int e, int ref) { // throughput of e / throughput of ref
        std::vector<double> v;
        for (int r = 0; r < runs; ++r)
            v.push_back(k < 0 ? secs_all(ref, r) / secs_all(e, r)
                              : seconds[k][ref][r] / seconds[k][e][r]);
        return median(v);
    };

    std::printf("%s: %zu triangles, %dx%d, %d spp, %d threads; %zu camera + %zu shadow + %zu "
                "bounce rays; medians of %d runs%s\n",
                scene_path.c_str(), soup.size(), ds.width(), ds.height(), spp, threads,
                sets[0].size(), sets[1].size(), sets[2].size(), runs,
                cpu_time ? " (Mrays per CPU-second)" : "");
    std::printf("%-56s %8s %8s %8s %8s %8s %8s %9s %9s %9s\n", "tracer (Mrays/s)", "camera",
                "shadow", "bounce", "all", "/native", "SAH", "build ms", "nodes KB", "tris KB");
    json j;
    j["scene"] = scene_path;
    j["triangles"] = soup.size();
    for (int k = 0; k < kSets; ++k)
        j["rays"][kSetNames[k]] = sets[k].size();
    j["threads"] = threads;
    for (int e = 0; e < n_all; ++e) {
        const bool native = e < n_native;
        const Entry& own = entries[native ? e : 0];
        std::printf("%-56s %8.2f %8.2f %8.2f %8.2f %8.3f %8.2f %9.1f %9.0f %9.0f\n",
                    names[e].c_str(), mrays(0, e), mrays(1, e), mrays(2, e), mrays_all(e),
                    ratio(-1, e, 0), native ? entries[e].sah : cur.sah_cost,
                    (native ? entries[e].build : cur.build_seconds) * 1e3, own.nodes_bytes / 1024.0,
                    own.tris_bytes / 1024.0);
        // Agreement with tracer 0: closest-hit triangle (a different triangle is a tie or a
        // grazing ray) and any-hit verdicts.
        int diff[kSets] = {0, 0, 0};
        for (int k = 0; k < kSets; ++k)
            for (size_t i = 0; i < sets[k].size(); ++i)
                diff[k] += results[k][e][i] != results[k][0][i];
        if (e > 0)
            std::printf("    differs from envtrace native on %d camera rays (triangle), %d shadow "
                        "rays (verdict), %d bounce rays (triangle)\n",
                        diff[0], diff[1], diff[2]);
        json row = {{"name", names[e]}, {"ratio_to_native", ratio(-1, e, 0)}};
        for (int k = 0; k < kSets; ++k) {
            row[std::string("mrays_") + kSetNames[k]] = mrays(k, e);
            row[std::string("differs_") + kSetNames[k]] = diff[k];
        }
        j["tracers"].push_back(row);
    }
    // The goals' ratios, each the median of the runs' ratios (side by side within a run).
    if (embree_row >= 0) {
        std::printf("native / Embree:");
        for (int k = 0; k < kSets; ++k) {
            std::printf(" %s %.3f,", kSetNames[k], ratio(k, 0, embree_row));
            j["native_over_embree"][kSetNames[k]] = ratio(k, 0, embree_row);
        }
        std::printf(" all %.3f\n", ratio(-1, 0, embree_row));
        j["native_over_embree"]["all"] = ratio(-1, 0, embree_row);
    }
    if (cl) {
        std::printf("OpenCL / native:");
        for (int k = 0; k < kSets; ++k) {
            std::printf(" %s %.3f,", kSetNames[k], ratio(k, n_native, 0));
            j["opencl_over_native"][kSetNames[k]] = ratio(k, n_native, 0);
        }
        std::printf(" all %.3f\n", ratio(-1, n_native, 0));
        j["opencl_over_native"]["all"] = ratio(-1, n_native, 0);
    }
    std::printf("SAH: traversal 1, triangle 1 per unit of root area (envtrace's builder weighs "
                "a packet of four triangles as 1); tris KB: the triangle data traversal reads. "
                "Embree's own scene BVH is not exposed (the rows 'Embree-built tree' use its "
                "builder, rtcBuildBVH).\n");
    if (!json_file.empty())
        et::write_json_file(json_file, j, 2);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_rays: error: %s\n", e.what());
    return 1;
}
