#include "prepare/device_scene.h"

#include "prepare/cosine_tables.h"
#include "prepare/env_black_mask.h"
#include "prepare/env_compensation.h"

#include "prepare/bvh_build.h"
#include "prepare/technique.h"
#include "prepare/visibility_tables.h"
#include "util/error.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace et {
namespace {

// Secondary rays start this far off the surface, relative to the largest coordinate of the hit
// triangle's vertices (kernels/surface.h): 1e-5 is ~170 float ulps. Measured on the shipped
// scenes (bunny_grace, ogre, the default scene at depth 1; glass, cornell_box, window_room at
// depth 5; same seeds): image means agree within 0.01% from 1e-5 down to 3e-7, surfaces shadow
// themselves from 1e-7 (1-5% darker; window_room 25% brighter through its walls). The earlier
// 2e-4 of the hit point's coordinates leaked light at contact (bunny_grace +0.08%) and, with its
// absolute floor below coordinates of 1, made small scenes up to 10% too bright.
constexpr float kRayEpsilon = 1e-5f;

// The cosine strategy's defensive share of the map's own distribution in every bin's table (as
// the visibility strategy's alpha: a light sample weighs at most 10x the map's own).
constexpr float kCosineAlpha = 0.1f;

// Geometry far from the origin against its size is moved next to it, with the camera: the ray
// offsets and the hit points' rounding are relative to the coordinates' magnitude, so a box 2
// wide at 1e4-1e5 leaked light along its inner edges (hit points rounded to ulps of 1e5, 0.008,
// landed past the neighbouring face) and at 2.5e5 was lit inside (offsets of 2.5). Per axis where
// every vertex lies farther from the origin than the geometry is wide, the shift is the middle
// rounded to a multiple of the farthest coordinate's ulp: every vertex is then within a factor
// of two of it and moves exactly, so the scene renders as it would at the origin. Geometry that
// straddles the origin, or lies near it, is left as it is (bit for bit).
void recentre(Scene& scene) {
    auto& pos = scene.triangles.positions;
    if (pos.empty())
        return;
    glm::vec3 lo = pos[0], hi = pos[0];
    for (const glm::vec3& v : pos) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
    }
    glm::vec3 shift(0.0f);
    for (int k = 0; k < 3; ++k) {
        const double a = lo[k], b = hi[k], width = b - a;
        if (!((a > 0.0 && a > width) || (b < 0.0 && -b > width)))
            continue;
        int e = 0;
        std::frexp(std::max(std::fabs(a), std::fabs(b)), &e);
        const double ulp = std::ldexp(1.0, e - 24); // of the farthest coordinate, as a float
        shift[k] = static_cast<float>(std::round(0.5 * (a + b) / ulp) * ulp);
    }
    if (shift == glm::vec3(0.0f))
        return;
    for (glm::vec3& v : pos)
        v -= shift;
    scene.camera.eye -= shift;
    scene.camera.target -= shift;
}

void set_camera(const Scene& scene, etk::EtkParams& p) {
    const Camera& c = scene.camera;
    glm::vec3 f = glm::normalize(c.target - c.eye);
    glm::vec3 r = glm::normalize(glm::cross(f, c.up));
    glm::vec3 u = glm::cross(r, f);
    const float th = std::tan(0.5f * glm::radians(c.fov_deg));
    const float aspect = static_cast<float>(scene.width) / scene.height;
    r *= th * aspect;
    u *= th;
    for (int k = 0; k < 3; ++k) {
        p.eye[k] = c.eye[k];
        p.forward[k] = f[k];
        p.right[k] = r[k];
        p.up[k] = u[k];
    }
}

bool uses_textures(const Scene& scene) {
    for (const Material& m : scene.materials)
        if (m.albedo_tex >= 0 || m.specular_tex >= 0 || m.roughness_tex >= 0)
            return true;
    return false;
}

// Texture coordinates in BVH order, only when a material is textured (nothing else reads them).
void add_texture_coordinates(const Scene& scene, const std::vector<int>& order, DeviceScene& d) {
    if (!uses_textures(scene))
        return;
    const auto& uvs = scene.triangles.uvs;
    d.tri_uv.assign(6 * std::max<size_t>(1, order.size()), 0.0f);
    for (size_t i = 0; i < order.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const size_t c = 3 * static_cast<size_t>(order[i]) + k;
            if (c < uvs.size()) {
                d.tri_uv[6 * i + 2 * k] = uvs[c].x;
                d.tri_uv[6 * i + 2 * k + 1] = uvs[c].y;
            }
        }
}

// Every texture into one flat buffer behind a two-float4 header each (kernels/texture_lookup.h),
// and each material's texture slots. TextureSet has kept the total within what the device indexes.
void add_textures(const Scene& scene, DeviceScene& d) {
    auto bits = [](uint32_t v) {
        float f;
        std::memcpy(&f, &v, 4);
        return f;
    };
    for (const Texture& t : scene.textures.textures()) {
        const uint32_t offset = static_cast<uint32_t>(d.tex_texels.size());
        d.tex_info.push_back(etk::make_float4(bits(offset), bits(uint32_t(t.width)),
                                              bits(uint32_t(t.height)),
                                              bits(uint32_t(t.channels))));
        d.tex_info.push_back(
            etk::make_float4(t.uv_scale.x, t.uv_scale.y, t.uv_offset.x, t.uv_offset.y));
        d.tex_texels.insert(d.tex_texels.end(), t.texels.begin(), t.texels.end());
    }
    for (const Material& m : scene.materials)
        d.material_tex.insert(d.material_tex.end(),
                              {m.albedo_tex, m.specular_tex, m.roughness_tex, -1});
    if (d.material_tex.empty())
        d.material_tex.assign(ETK_TEX_SLOTS, -1);
}

void add_triangles(const Scene& scene, DeviceScene& d) {
    Bvh bvh = build_bvh(scene.triangles);
    d.packets = flatten_packets(scene.triangles, bvh, &d.packet_slot);
    d.face_normals = face_normals(scene.triangles, bvh.order);
    const size_t n = bvh.order.size();
    d.normals.resize(3 * n);
    d.tri_material.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const int t = bvh.order[i];
        for (int k = 0; k < 3; ++k) {
            const glm::vec3& v = scene.triangles.normals[3 * t + k];
            d.normals[3 * i + k] = etk::make_float4(v.x, v.y, v.z, 0.0f);
        }
        d.tri_material[i] = scene.triangles.material[t];
    }
    add_texture_coordinates(scene, bvh.order, d);
    if (n == 0) // one all-zero triangle (face_normals, flatten_packets) that nothing hits
        d.normals.resize(3), d.tri_material.resize(1);
    d.bvh.nodes = bvh.node_count();
    d.bvh.depth = bvh.depth;
    d.bvh.sah_cost = bvh.sah_cost;
    d.bvh.build_seconds = bvh.build_seconds;
    d.nodes = std::move(bvh.nodes);
    d.triangle_count = n;
}

void add_materials(const Scene& scene, DeviceScene& d) {
    for (const auto& m : scene.materials) {
        // The type as a float value (bsdf.h: never an int's bits, a denormal in albedo's lane).
        const float type_value = static_cast<float>(m.type);
        // Conductors keep eta where the others keep the albedo and k where they keep F0;
        // dielectrics their ior in F0's first slot (bsdf.h).
        const bool metal = m.type == ETK_MAT_CONDUCTOR;
        const glm::vec3 a = metal ? m.eta : m.albedo, b = metal ? m.k : m.specular;
        d.materials.push_back(etk::make_float4(a.x, a.y, a.z, type_value));
        const bool glass = m.type == ETK_MAT_DIELECTRIC || m.type == ETK_MAT_SMOOTH_DIELECTRIC;
        d.materials.push_back(etk::make_float4(glass ? m.ior : b.x, b.y, b.z, m.roughness));
    }
    if (d.materials.empty())
        d.materials.resize(2);
    for (const auto& m : scene.materials)
        d.material_names.push_back(m.name);
}

// A light set is made from the map alone (envtrace lights MAP), in envtrace's convention, unturned
// and at intensity 1: the scene's environment turns and scales it as it turns and scales the map
// (rotation, convention, intensity were ignored, so --lights lit a turned scene from the wrong
// side).
void add_lights(const std::vector<DirectionalLight>& lights, DeviceScene& d) {
    const etk::EtkEnvMap& env = d.params.env;
    for (const auto& l : lights) {
        const etk::float3 w = etk::etk_env_to_world(
            env, etk::make_float3(l.direction.x, l.direction.y, l.direction.z));
        d.lights.push_back(etk::make_float4(w.x, w.y, w.z, 0.0f));
        d.lights.push_back(etk::make_float4(float(l.power.x * env.scale),
                                            float(l.power.y * env.scale),
                                            float(l.power.z * env.scale), 0.0f));
    }
    d.params.light_count = static_cast<int>(lights.size());
}

void add_strata(const VoronoiStrata& v, DeviceScene& d) {
    for (const auto& p : v.power) {
        d.lights.push_back(etk::make_float4(0.0f, 0.0f, 0.0f, 0.0f));
        d.lights.push_back(etk::make_float4(float(p.x), float(p.y), float(p.z), 0.0f));
    }
    d.strata_texels = v.texels;
    d.strata_begin = v.begin;
    d.strata_cdf = v.cdf;
    d.params.light_count = static_cast<int>(v.power.size());
    d.params.strata_width = v.width;
    d.params.strata_height = v.height;
}

// The binned technique's tables, one per bin of normals (kernels/normal_bins.h), after whatever
// guide_cells holds, from a table boundary (EtkParams::bin_cell_base): the cosine strategy's
// alone, or auto's alternative after the learned tables. Needs guide_regions.
void add_cosine_bins(DeviceScene& d) {
    const size_t cell = ETK_GUIDE_CELL_FLOATS;
    d.guide_cells.resize((d.guide_cells.size() + cell - 1) / cell * cell, 0.0f);
    d.params.bin_cell_base = static_cast<int>(d.guide_cells.size() / cell);
    const std::vector<float> bins =
        cosine_bin_tables(d.env_dist, d.guide_regions, d.params.env, kCosineAlpha);
    d.guide_cells.insert(d.guide_cells.end(), bins.begin(), bins.end());
}

// The visibility strategy: its hash grid over the scene's bounds, the map's region tables and
// the cells' initial tables (the map's own distribution; the continuation guide's, at depth > 1,
// uniform with a guided share of 0).
void add_visibility_guide(const Scene& scene, DeviceScene& d) {
    const int64_t pixels = static_cast<int64_t>(scene.width) * scene.height;
    d.guide_options.slots = guide_slots(d.guide_options, pixels);
    d.guide_options.learning_passes = guide_learning_passes(d.guide_options, pixels);
    const VisibilityOptions& opt = d.guide_options;
    glm::vec3 lo(0.0f), hi(0.0f);
    if (!scene.triangles.positions.empty()) {
        lo = hi = scene.triangles.positions[0];
        for (const glm::vec3& v : scene.triangles.positions) {
            lo = glm::min(lo, v);
            hi = glm::max(hi, v);
        }
    }
    const glm::vec3 ext = hi - lo;
    const float longest = std::max({ext.x, ext.y, ext.z, 1e-6f});
    etk::EtkParams& p = d.params;
    for (int k = 0; k < 3; ++k)
        p.guide_origin[k] = lo[k];
    p.guide_inv_cell = static_cast<float>(opt.resolution) / longest;
    d.guide_options.slots = guide_grid_slots(opt.slots, &ext[0], p.guide_inv_cell);
    p.guide_slots = opt.slots;
    // Shadow rays carry their record's key as a float value (integrator.h): exact below 2^24.
    if (static_cast<int64_t>(opt.slots) * ETK_GUIDE_REGIONS > (int64_t(1) << 24))
        throw Error("visibility options: " + std::to_string(opt.slots) +
                    " slots are more than the shadow rays' keys can name");
    // Depth 1 has no continuation to guide (the last bounce's is not guided: integrator.h).
    p.guide_continuation = opt.continuation && d.settings.max_depth > 1 ? 1 : 0;
    if (!d.settings.guide_verdict)
        d.guide_options.verdict_passes = 0;
    d.guide_regions = guide_region_tables(d.env_dist, p.env.dist_w, p.env.dist_h);
    d.guide_cells = guide_prior_cells(d.guide_regions, opt.slots, p.guide_continuation != 0,
                                      guide_portal_box(&lo[0], &hi[0]));
    d.guide_map_power = guide_map_power(d.env_texels, p.env.tex_w, p.env.tex_h);
    p.guide_inv_power = guide_inv_power(d.guide_map_power);
    if (screen_keeps_alternative(d.guide_options, p.guide_continuation != 0))
        add_cosine_bins(d);
}

} // namespace

etk::EtkScene DeviceScene::view() const {
#define ET_DATA(type, name) name.data(),
    return etk::EtkScene{ETK_SCENE_BUFFERS(ET_DATA)};
#undef ET_DATA
}

DeviceScene prepare_device_scene(Scene scene, const RenderSettings& st,
                                 const std::vector<DirectionalLight>* lights,
                                 const VoronoiStrata* sis) {
    DeviceScene d;
    d.settings = st;
    d.scene_path = scene.path;
    etk::EtkParams& p = d.params;
    p.env = scene.env.desc();
    recentre(scene);
    set_camera(scene, p);
    p.width = scene.width;
    p.height = scene.height;
    p.max_depth = st.max_depth;
    p.rr_depth = st.rr_depth;
    set_technique(p, st.strategy);
    p.heuristic = static_cast<int>(resolved_heuristic(st));
    p.sampler = static_cast<int>(st.sampler);
    p.seed = st.seed;
    p.bsdf_sampling = static_cast<int>(resolved_bsdf_sampling(st));
    p.ray_epsilon = kRayEpsilon;
    p.pixel_stride = 1;
    check_split(st);
    p.light_samples = st.light_samples;
    p.bsdf_samples = st.bsdf_samples;
    // Whether batches may be used; the renderer turns them off on devices that prefer single
    // samples (LightBatch::automatic).
    p.light_batch = st.light_batch != LightBatch::off && technique_batches_light_samples(p) ? 1 : 0;
    add_triangles(scene, d);
    add_materials(scene, d);
    add_textures(scene, d);
    if (st.strategy == Strategy::lights) {
        if (!lights)
            throw Error("the light-set strategy needs a light set");
        add_lights(*lights, d);
    }
    if (st.strategy == Strategy::sis) {
        if (!sis || sis->power.empty())
            throw Error("the SIS strategy needs its strata");
        add_strata(*sis, d);
    }
    d.map_name = scene.env.name;
    d.map_width = scene.env.image.width;
    d.map_height = scene.env.image.height;
    d.map_build_seconds = scene.env.build_seconds;
    if (p.light_first == ETK_LIGHT_COMPENSATED || p.light_deeper == ETK_LIGHT_COMPENSATED ||
        st.strategy == Strategy::automatic) // its fallback's
        d.env_dist_comp = compensate_distribution(scene.env.dist).table;
    d.env_dist = std::move(scene.env.dist.table);
    EnvBlackMask black = env_black_mask(scene.env.image);
    p.env.black_w = black.width;
    p.env.black_h = black.height;
    p.env.lit_sr = black.lit_solid_angle;
    d.env_black = std::move(black.bits);
    d.env_texels = std::move(scene.env.image.rgb);
    if (st.strategy == Strategy::automatic)
        d.guide_options = auto_visibility_options();
    if (st.strategy == Strategy::visibility || st.strategy == Strategy::automatic)
        add_visibility_guide(scene, d);
    if (st.strategy == Strategy::cosine) {
        // One table per bin of normals, in the visibility strategy's slots (kernels/normal_bins.h).
        d.guide_regions = guide_region_tables(d.env_dist, p.env.dist_w, p.env.dist_h);
        add_cosine_bins(d);
        p.guide_slots = ETK_NORMAL_BINS;
        p.guide_ready = 1; // prepared here, never learned
    }
    return d;
}

} // namespace et
