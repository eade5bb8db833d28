#include "prepare/cosine_tables.h"

#include "kernels/latlong.h"
#include "kernels/normal_bins.h"
#include "kernels/piecewise_constant.h"
#include "kernels/visibility_guide.h"
#include "prepare/visibility_tables.h"

#include <algorithm>
#include <cmath>

namespace et {
namespace {

constexpr int K = ETK_GUIDE_REGIONS;
// Each region is cut into S x S parts, each summarised by its mass, its mass-weighted mean
// direction and how far its texels reach from that direction.
constexpr int S = 4;

struct Part {
    double mass = 0.0, x = 0.0, y = 0.0, z = 0.0; // (x, y, z): the mass-weighted direction sum,
                                                  // then its unit vector
    double reach = 0.0; // radians: the part's texels (their extent included) about (x, y, z)
};

double angle(const etk::float3& a, const etk::float3& b) {
    return std::acos(std::clamp(double(etk::dot(a, b)), -1.0, 1.0));
}

// How far the normals of bin k lie from its centre: the largest angle to points on a 5 x 5 grid
// over its square, 2% added for the curve between them.
double bin_radius(int k) {
    const etk::float3 c = etk::etk_normal_bin_centre(k);
    const int i = k % ETK_NORMAL_BIN_SIDE, j = k / ETK_NORMAL_BIN_SIDE;
    double r = 0.0;
    for (int a = 0; a <= 4; ++a)
        for (int b = 0; b <= 4; ++b) {
            const etk::float2 q = etk::make_float2((i + 0.25f * a) / ETK_NORMAL_BIN_SIDE,
                                                   (j + 0.25f * b) / ETK_NORMAL_BIN_SIDE);
            r = std::max(r, angle(c, etk::etk_octahedral_dir(q)));
        }
    return 1.02 * r;
}

} // namespace

std::vector<double> cosine_bin_weights(const std::vector<float>& dist, const etk::EtkEnvMap& env) {
    const int w = env.dist_w, h = env.dist_h;
    // Row densities from the marginal CDF's widths, as the kernels sample and evaluate them (the
    // stored densities differ where the CDF cannot hold a row's width: guide_region_tables).
    const float* mcdf = dist.data() + etk::etk_dist2d_marginal_cdf(h);
    const float* ccdf = dist.data() + etk::etk_dist2d_conditional_cdf(w, h);
    std::vector<Part> parts(static_cast<size_t>(K) * S * S);
    // Per column: its region column, part column and (sin, cos) of its longitude
    // (etk_latlong_dir's); per row the same for the colatitude: each texel's part and direction
    // without a division or a sine of its own.
    std::vector<int> col_part(w);
    std::vector<etk::float2> col_phi(w);
    for (int c = 0; c < w; ++c) {
        const int Rc = etk::etk_guide_region_col(c, w);
        const int c0 = etk::etk_guide_col_start(Rc, w),
                  nc = etk::etk_guide_col_start(Rc + 1, w) - c0;
        col_part[c] = Rc * S + (c - c0) * S / std::max(nc, 1);
        col_phi[c] = etk::etk_sincospi(2.0f * ((c + 0.5f) / w) - 1.0f);
    }
    // Each texel's part, its mass and direction (map space), in two passes: sums, then reach.
    auto each_texel = [&](auto&& visit) {
        for (int r = 0; r < h; ++r) {
            const int Rr = etk::etk_guide_region_row(r, h);
            const int r0 = etk::etk_guide_row_start(Rr, h),
                      nr = etk::etk_guide_row_start(Rr + 1, h) - r0;
            const int sr = (r - r0) * S / std::max(nr, 1);
            const float* row = ccdf + static_cast<size_t>(r) * (w + 1);
            const double pv = double(etk::etk_interval_density(mcdf, h, r)) / h;
            const etk::float2 theta = etk::etk_sincospi((r + 0.5f) / h);
            // Part index = ((Rr * COLS + Rc) * S + sr) * S + sc, with col_part = Rc * S + sc.
            const size_t base = static_cast<size_t>(Rr) * ETK_GUIDE_COLS * S * S;
            for (int c = 0; c < w; ++c) {
                const double m = pv * std::max(0.0, double(row[c + 1]) - double(row[c]));
                if (!(m > 0.0))
                    continue;
                const int rc = col_part[c] / S, sc = col_part[c] % S;
                const etk::float3 d =
                    etk::make_float3(theta.x * col_phi[c].x, theta.y, -theta.x * col_phi[c].y);
                visit(parts[base + (static_cast<size_t>(rc) * S + sr) * S + sc], m, d);
            }
        }
    };
    each_texel([](Part& p, double m, const etk::float3& d) {
        p.mass += m;
        p.x += m * d.x;
        p.y += m * d.y;
        p.z += m * d.z;
    });
    // The reach: the widest angle from the mean direction to a texel centre (its cosine, min_cos,
    // gathered first), plus half a texel's diagonal.
    for (Part& p : parts) {
        const double l = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
        if (l > 0.0) {
            p.x /= l;
            p.y /= l;
            p.z /= l;
        }
        p.reach = 1.0; // min_cos until the end of the pass
    }
    each_texel([](Part& p, double, const etk::float3& d) {
        p.reach = std::min(p.reach, p.x * d.x + p.y * d.y + p.z * d.z);
    });
    const double half_texel = 0.5 * std::hypot(M_PI / h, 2.0 * M_PI / w);
    for (Part& p : parts)
        p.reach = std::acos(std::clamp(p.reach, -1.0, 1.0)) + half_texel;
    // The parts as arrays of floats (unit mean direction, mass, cos and sin of the reach), so
    // that the loop over them below vectorises: 1024 bins x 8192 parts.
    const size_t np = parts.size();
    std::vector<float> ux(np), uy(np), uz(np), mass(np), cr(np), sr(np);
    for (size_t i = 0; i < np; ++i) {
        const Part& p = parts[i];
        ux[i] = float(p.x); // unit (or zero: a part of no mass) after the reach's pass
        uy[i] = float(p.y);
        uz[i] = float(p.z);
        mass[i] = float(p.mass);
        cr[i] = float(std::cos(std::min(p.reach, M_PI)));
        sr[i] = float(std::sin(std::min(p.reach, M_PI)));
    }
    std::vector<double> out(static_cast<size_t>(ETK_NORMAL_BINS) * K);
    std::vector<float> weight(np);
    for (int k = 0; k < ETK_NORMAL_BINS; ++k) {
        // Conservative: for any normal n of the bin and direction w of a part, the angle between
        // them is at least the part's mean direction's angle theta to the centre less the bin's
        // radius and the part's reach (together d), so the part's mass times cos(max(0, theta -
        // d)) (0 past 90 degrees) bounds its light times max(0, n . w) from above for every
        // normal of the bin: no direction a normal of the bin is lit from gets a density far
        // below its share of the light (no rare light samples of large weight). In closed form:
        // cos(theta - d) = cos theta cos d + sin theta sin d, 1 where theta < d.
        const etk::float3 c = etk::etk_world_to_env(env, etk::etk_normal_bin_centre(k));
        const double radius = bin_radius(k);
        const float crb = float(std::cos(radius)), srb = float(std::sin(radius));
        for (size_t i = 0; i < np; ++i) {
            const float x = c.x * ux[i] + c.y * uy[i] + c.z * uz[i];
            const float sx = std::sqrt(std::max(0.0f, 1.0f - x * x));
            const float cd = crb * cr[i] - srb * sr[i], sd = srb * cr[i] + crb * sr[i];
            weight[i] = mass[i] * (x >= cd ? 1.0f : std::max(0.0f, x * cd + sx * sd));
        }
        for (int R = 0; R < K; ++R) {
            double sum = 0.0;
            for (int q = 0; q < S * S; ++q)
                sum += weight[static_cast<size_t>(R) * S * S + q];
            out[static_cast<size_t>(k) * K + R] = sum;
        }
    }
    return out;
}

std::vector<float> cosine_bin_tables(const std::vector<float>& dist,
                                     const std::vector<float>& regions, const etk::EtkEnvMap& env,
                                     float alpha) {
    const std::vector<double> weights = cosine_bin_weights(dist, env);
    std::vector<float> out(static_cast<size_t>(ETK_NORMAL_BINS) * ETK_GUIDE_CELL_FLOATS);
    std::vector<double> prob(K);
    for (int k = 0; k < ETK_NORMAL_BINS; ++k) {
        const double* P = weights.data() + static_cast<size_t>(k) * K;
        double total = 0.0;
        for (int R = 0; R < K; ++R)
            total += P[R];
        for (int R = 0; R < K; ++R)
            prob[R] = alpha * double(regions[R]) +
                      (1.0 - alpha) * (total > 0.0 ? P[R] / total : double(regions[R]));
        float* cell = out.data() + static_cast<size_t>(k) * ETK_GUIDE_CELL_FLOATS;
        write_guide_cdf(prob, cell);
        cell[ETK_GUIDE_LIGHT_COUNT] = 1.0f;
    }
    return out;
}

} // namespace et
