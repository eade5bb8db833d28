#include "render/light_render.h"
#include "util/parallel.h"

#include "kernels/directional_lights.h"
#include "util/timer.h"

#include <algorithm>
#include <atomic>
#include <thread>

namespace et {
namespace {
etk::float3 f3(glm::dvec3 v) {
    return etk::make_float3(float(v.x), float(v.y), float(v.z));
}
} // namespace

LightSetRenderer::LightSetRenderer(const SceneArrays& arrays, const etk::EtkParams& params,
                                   const std::vector<DirectionalLight>& lights, int threads)
    : arrays_(arrays), params_(params), threads_(threads) {
    for (const auto& l : lights) {
        dirs_.push_back(etk::make_float3(l.direction.x, l.direction.y, l.direction.z));
        power_.push_back(f3(l.power));
    }
    film_.assign(3 * static_cast<size_t>(params.width) * params.height, 0.0);
}

LightSetRenderer::LightSetRenderer(const SceneArrays& arrays, const etk::EtkParams& params,
                                   const VoronoiStrata& strata, int threads)
    : arrays_(arrays), params_(params), threads_(threads), strata_(&strata) {
    for (const auto& p : strata.power)
        power_.push_back(f3(p));
    film_.assign(3 * static_cast<size_t>(params.width) * params.height, 0.0);
}

void LightSetRenderer::render_sample(uint32_t sample_index) {
    Timer timer;
    etk::EtkParams p = params_;
    p.sample_index = sample_index;
    const SceneArrays& a = arrays_;
    const etk::EtkScene S = scene_view(a);
    const int width = p.width, height = p.height;
    const int n_strata = strata_ ? static_cast<int>(power_.size()) : 0;
    const int stratum = strata_ ? static_cast<int>(sample_index % uint32_t(n_strata)) : -1;
    std::atomic<int> next_row{0};
    std::atomic<uint64_t> shadow_rays{0};
    auto work = [&] {
        uint64_t shadows = 0;
        for (int y; (y = next_row.fetch_add(1)) < height;) {
            for (int x = 0; x < width; ++x) {
                const int pixel = y * width + x;
                const etk::float3 o = etk::etk_p3(p.eye);
                const etk::float3 d = etk::etk_camera_dir(p, pixel);
                etk::EtkHit h;
                etk::float3 L = etk::make_float3(0, 0, 0);
                if (!etk::etk_bvh_traverse(S.nodes, S.tris, o, d, 3.0e38f, 0, &h)) {
                    L = etk::etk_env_radiance(S.env_texels, p.env, d);
                } else {
                    const etk::EtkSurface s = etk::etk_surface_at(S, p, o, d, h);
                    if (!strata_) {
                        for (size_t k = 0; k < dirs_.size(); ++k) {
                            const etk::float3 c = etk::etk_dl_unshadowed(s, dirs_[k], power_[k]);
                            if (!(etk::etk_max3(c) > 0.0f))
                                continue;
                            ++shadows;
                            etk::EtkHit sh;
                            if (!etk::etk_bvh_traverse(S.nodes, S.tris, s.origin, dirs_[k], 3.0e38f,
                                                       1, &sh))
                                L += c;
                        }
                    } else {
                        const VoronoiStrata& v = *strata_;
                        const etk::float2 u = etk::etk_dims(p, pixel, 1u);
                        const etk::float3 md = etk::etk_dl_stratum_direction(
                            v.texels.data(), v.cdf.data(), v.begin[stratum], v.begin[stratum + 1],
                            v.width, v.height, u);
                        const etk::float3 wi = normalize(etk::etk_env_to_world(p.env, md));
                        const etk::float3 E = power_[stratum] * float(n_strata);
                        const etk::float3 c = etk::etk_dl_unshadowed(s, wi, E);
                        if (etk::etk_max3(c) > 0.0f) {
                            ++shadows;
                            etk::EtkHit sh;
                            if (!etk::etk_bvh_traverse(S.nodes, S.tris, s.origin, wi, 3.0e38f, 1,
                                                       &sh))
                                L = c;
                        }
                    }
                }
                if (!(etk::isfinite(L.x) && etk::isfinite(L.y) && etk::isfinite(L.z)))
                    L = etk::make_float3(0, 0, 0);
                film_[3 * size_t(pixel)] += L.x;
                film_[3 * size_t(pixel) + 1] += L.y;
                film_[3 * size_t(pixel) + 2] += L.z;
            }
        }
        shadow_rays += shadows;
    };
    run_on_threads(thread_count(threads_), [&](int) { work(); });
    ++samples_;
    stats_.samples_per_pixel = samples_;
    stats_.camera_rays += uint64_t(width) * height;
    stats_.shadow_rays += shadow_rays.load();
    stats_.seconds += timer.seconds();
}

std::vector<float> LightSetRenderer::image() {
    std::vector<float> out(film_.size());
    const double inv = samples_ > 0 ? 1.0 / samples_ : 0.0;
    for (size_t i = 0; i < film_.size(); ++i)
        out[i] = static_cast<float>(film_[i] * inv);
    return out;
}

} // namespace et
