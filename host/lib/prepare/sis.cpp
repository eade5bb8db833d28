#include "prepare/sis.h"
#include "kernels/latlong.h"
#include "util/parallel.h"

#include "util/error.h"
#include "util/timer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <thread>

namespace et {

glm::dvec3 texel_direction(int row, int col, int w, int h) {
    const etk::float3 d = etk::etk_latlong_to_dir(
        etk::make_float2((static_cast<float>(col) + 0.5f) / static_cast<float>(w),
                         (static_cast<float>(row) + 0.5f) / static_cast<float>(h)));
    return glm::dvec3(d.x, d.y, d.z);
}

glm::dvec3 map_power(const EnvMap& env) {
    const RgbImage& im = env.image;
    glm::dvec3 sum(0.0);
    for (int y = 0; y < im.height; ++y) {
        glm::dvec3 row(0.0);
        for (int x = 0; x < im.width; ++x) {
            const float* t = im.at(x, y);
            row += glm::dvec3(t[0], t[1], t[2]);
        }
        sum += row * texel_solid_angle(y, im.width, im.height);
    }
    return sum * double(env.scale);
}

namespace {
template <typename F> void parallel_rows(int rows, int threads, F&& f) {
    threads = std::min(thread_count(threads), rows);
    std::atomic<int> next{0};
    run_on_threads(threads, [&](int) {
        for (int r; (r = next.fetch_add(1)) < rows;)
            f(r);
    });
}
} // namespace

VoronoiStrata voronoi_strata(const EnvMap& env, const std::vector<glm::dvec3>& points,
                             int threads) {
    if (points.empty())
        throw Error("Voronoi strata need at least one point");
    const RgbImage& im = env.image;
    const int w = im.width, h = im.height, n = static_cast<int>(points.size());
    VoronoiStrata v;
    v.width = w;
    v.height = h;
    v.points = points;
    v.cell.assign(static_cast<size_t>(w) * h, 0);
    std::vector<glm::vec3> pf(points.begin(), points.end());
    parallel_rows(h, threads, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const glm::vec3 d(texel_direction(y, x, w, h));
            int best = 0;
            float best_dot = -2.0f;
            for (int k = 0; k < n; ++k) {
                const float c = glm::dot(d, pf[k]);
                if (c > best_dot) {
                    best_dot = c;
                    best = k;
                }
            }
            v.cell[static_cast<size_t>(y) * w + x] = best;
        }
    });
    v.solid_angle.assign(n, 0.0);
    v.power.assign(n, glm::dvec3(0.0));
    std::vector<int> count(n, 0);
    for (int y = 0; y < h; ++y) {
        const double sa = texel_solid_angle(y, w, h);
        for (int x = 0; x < w; ++x) {
            const int k = v.cell[static_cast<size_t>(y) * w + x];
            const float* t = im.at(x, y);
            v.solid_angle[k] += sa;
            v.power[k] += glm::dvec3(t[0], t[1], t[2]) * (sa * env.scale);
            ++count[k];
        }
    }
    // Texels grouped by cell (counting sort), each cell's solid-angle CDF.
    v.begin.assign(n + 1, 0);
    for (int k = 0; k < n; ++k)
        v.begin[k + 1] = v.begin[k] + count[k];
    v.texels.resize(v.cell.size());
    std::vector<int> fill(v.begin.begin(), v.begin.end() - 1);
    for (size_t i = 0; i < v.cell.size(); ++i)
        v.texels[fill[v.cell[i]]++] = static_cast<int>(i);
    v.cdf.resize(v.texels.size());
    for (int k = 0; k < n; ++k) {
        double run = 0.0;
        for (int i = v.begin[k]; i < v.begin[k + 1]; ++i) {
            run += texel_solid_angle(v.texels[i] / w, w, h);
            v.cdf[i] = static_cast<float>(run / v.solid_angle[k]);
        }
        if (v.begin[k + 1] > v.begin[k])
            v.cdf[v.begin[k + 1] - 1] = 1.0f;
    }
    return v;
}

SisResult build_sis(const EnvMap& env, const SisOptions& o) {
    if (o.samples < 1)
        throw Error("SIS needs at least one sample");
    if (o.levels < 1)
        throw Error("SIS needs at least one brightness level");
    Timer timer;
    const RgbImage& im = env.image;
    const int w = im.width, h = im.height;
    const size_t texels = static_cast<size_t>(w) * h;
    if (static_cast<size_t>(o.samples) > texels)
        throw Error((env.name.empty() ? std::string("the map") : env.name) + ": SIS asked for " +
                    std::to_string(o.samples) + " strata, but the map has only " +
                    std::to_string(texels) + (texels == 1 ? " texel (" : " texels (") +
                    std::to_string(w) + "x" + std::to_string(h) + "), one stratum at least each");
    SisResult r;

    // Luminance and its solid-angle weighted mean and standard deviation.
    std::vector<float> Y(texels);
    std::vector<double> row_sa(h);
    double sum = 0.0, sum2 = 0.0;
    for (int y = 0; y < h; ++y) {
        row_sa[y] = texel_solid_angle(y, w, h);
        for (int x = 0; x < w; ++x) {
            const float l = luminance(im.at(x, y)) * env.scale;
            Y[static_cast<size_t>(y) * w + x] = l;
            sum += l * row_sa[y];
            sum2 += double(l) * l * row_sa[y];
        }
    }
    const double mean = sum / (4.0 * M_PI);
    r.sigma = std::sqrt(std::max(0.0, sum2 / (4.0 * M_PI) - mean * mean));
    for (int i = 0; i < o.levels; ++i)
        r.thresholds.push_back(i * r.sigma);
    auto band_of = [&](float l) {
        if (!(r.sigma > 0.0))
            return 0;
        return std::min(o.levels - 1, static_cast<int>(std::floor(l / r.sigma)));
    };

    // Sample budget per band: Gamma_i = power (integral of Y) x solid angle^b.
    std::vector<double> band_sa(o.levels, 0.0), band_power(o.levels, 0.0), gamma(o.levels, 0.0);
    for (size_t i = 0; i < texels; ++i) {
        const int b = band_of(Y[i]);
        band_sa[b] += row_sa[i / w];
        band_power[b] += Y[i] * row_sa[i / w];
    }
    double gamma_sum = 0.0;
    for (int b = 0; b < o.levels; ++b) {
        if (band_sa[b] > 0.0)
            gamma[b] = band_power[b] * std::pow(band_sa[b], o.area_power);
        gamma_sum += gamma[b];
    }
    r.level_samples.assign(o.levels, 0);
    if (gamma_sum > 0.0) {
        std::vector<std::pair<double, int>> rem;
        int given = 0;
        for (int b = 0; b < o.levels; ++b) {
            const double share = o.samples * gamma[b] / gamma_sum;
            r.level_samples[b] = static_cast<int>(std::floor(share));
            given += r.level_samples[b];
            rem.emplace_back(-(share - r.level_samples[b]), -b); // ties: the brighter band
        }
        std::sort(rem.begin(), rem.end());
        for (int k = 0; given < o.samples; ++k, ++given)
            r.level_samples[-rem[k % o.levels].second] += 1;
    } else {
        r.level_samples[0] = o.samples; // black map: farthest points over the whole sphere
    }

    // Hochbaum-Shmoys farthest points, brightest level first. near[i]: cosine of the angle from
    // texel i to its nearest placed point (-2: none placed yet).
    std::vector<glm::vec3> dirs(texels);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            dirs[static_cast<size_t>(y) * w + x] = glm::vec3(texel_direction(y, x, w, h));
    std::vector<float> near(texels, -2.0f);
    std::vector<glm::dvec3> points;
    std::vector<char> used(texels, 0);
    for (int level = o.levels - 1; level >= 0; --level) {
        const float t = static_cast<float>(r.thresholds[level]);
        std::vector<int> region;
        for (size_t i = 0; i < texels; ++i)
            if (band_of(Y[i]) >= level || Y[i] >= t)
                region.push_back(static_cast<int>(i));
        for (int s = 0; s < r.level_samples[level]; ++s) {
            int pick = -1;
            if (points.empty()) { // the brightest texel of the region
                float best = -1.0f;
                for (int i : region)
                    if (Y[i] > best) {
                        best = Y[i];
                        pick = i;
                    }
            } else { // the texel farthest from every point so far
                float best = 3.0f;
                for (int i : region)
                    if (!used[i] && near[i] < best) {
                        best = near[i];
                        pick = i;
                    }
            }
            if (pick < 0) { // level exhausted (fewer free texels than samples): use any texel
                for (size_t i = 0; i < texels && pick < 0; ++i)
                    if (!used[i])
                        pick = static_cast<int>(i);
            }
            used[pick] = 1;
            points.push_back(glm::dvec3(dirs[pick]));
            r.point_level.push_back(level);
            const glm::vec3 p = dirs[pick];
            for (size_t i = 0; i < texels; ++i)
                near[i] = std::max(near[i], glm::dot(dirs[i], p));
        }
    }
    // Normalise the placed points exactly (the float texel directions are close to unit).
    for (auto& p : points)
        p = glm::normalize(p);
    r.strata = voronoi_strata(env, points, o.threads);
    r.seconds = timer.seconds();
    return r;
}

} // namespace et
