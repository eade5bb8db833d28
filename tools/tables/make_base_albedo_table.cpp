// Writes kernels/base_albedo_table.h: the directional albedo of envtrace's GGX lobe with Schlick's
// Fresnel, E(mu, alpha, F0) = F0 A(mu, alpha) + B(mu, alpha), and its cosine-weighted mean over
// mu, Eavg(alpha, F0) = F0 Aavg(alpha) + Bavg(alpha), which couple the Lambertian base under the
// lobe to what the lobe reflects (kernels/bsdf.h, etk_base_coupling). Computed with the kernels'
// own functions (etk_sample_ggx_vndf, etk_smith_g1): a visible normal drawn from wo gives
// f cos / pdf = F(wo.h) G1(wi), so A and B are the means of (1 - (1 - wo.h)^5) G1(wi) and
// (1 - wo.h)^5 G1(wi) over stratified points of the sampler's square (wi below the horizon: 0).
//
//   make_base_albedo_table OUT.h          write the table
//   make_base_albedo_table --check FILE   exit 1 unless FILE is what this would write (ctest)
#include "kernels/ggx.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr int kMu = ETK_BASE_TABLE_MU, kAlpha = ETK_BASE_TABLE_ALPHA;

// A and B at one (mu, alpha), over n x n stratified points.
void lobe_albedo(double mu, double alpha, int n, double* a, double* b) {
    const float m = static_cast<float>(mu);
    const etk::float3 wo = etk::make_float3(std::sqrt(std::max(0.0f, 1.0f - m * m)), 0.0f, m);
    double sa = 0.0, sb = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const etk::float2 u = etk::make_float2((i + 0.5f) / static_cast<float>(n),
                                                   (j + 0.5f) / static_cast<float>(n));
            const etk::float3 h = etk::etk_sample_ggx_vndf(wo, static_cast<float>(alpha), u);
            const float c = etk::dot(wo, h);
            const etk::float3 wi = h * (2.0f * c) - wo;
            if (!(wi.z > 0.0f) || !(c > 0.0f))
                continue;
            const double g = etk::etk_smith_g1(wi.z, static_cast<float>(alpha));
            const double x = 1.0 - c, x5 = x * x * x * x * x;
            sa += (1.0 - x5) * g;
            sb += x5 * g;
        }
    *a = sa / (double(n) * n);
    *b = sb / (double(n) * n);
}

// The table's nodes: square roots of mu and alpha evenly spaced (finer at grazing angles and
// near-smooth lobes, where E changes fastest); alpha as the kernels clamp it.
double mu_node(int i) {
    const double s = double(i) / (kMu - 1);
    return std::max(s * s, 1e-4);
}
double alpha_node(int j) {
    const double s = double(j) / (kAlpha - 1);
    return std::max(s * s, 1e-3);
}

std::string table_text() {
    std::vector<double> a(kMu * kAlpha), b(kMu * kAlpha), aavg(kAlpha), bavg(kAlpha);
    for (int j = 0; j < kAlpha; ++j) {
        for (int i = 0; i < kMu; ++i)
            lobe_albedo(mu_node(i), alpha_node(j), 128, &a[j * kMu + i], &b[j * kMu + i]);
        // 2 int_0^1 E(mu) mu dmu, midpoint rule in mu.
        const int nm = 256;
        double sa = 0.0, sb = 0.0;
        for (int k = 0; k < nm; ++k) {
            const double mu = (k + 0.5) / nm;
            double ka, kb;
            lobe_albedo(mu, alpha_node(j), 48, &ka, &kb);
            sa += 2.0 * ka * mu / nm;
            sb += 2.0 * kb * mu / nm;
        }
        aavg[j] = sa;
        bavg[j] = sb;
    }
    std::ostringstream o;
    o << "// clang-format off\n"
         "// Written by tools/tables/make_base_albedo_table.cpp, which says what these are; do\n"
         "// not edit: ctest base_albedo_table_current checks that it is what the tool writes.\n"
         "#ifndef ETK_BASE_ALBEDO_TABLE_H\n#define ETK_BASE_ALBEDO_TABLE_H\n#include "
         "\"compat.h\"\n\nETK_BEGIN\n\n";
    auto array = [&](const char* name, const std::vector<double>& v) {
        o << "ETK_TABLE float " << name << "[" << v.size() << "] = {";
        for (size_t k = 0; k < v.size(); ++k) {
            char buf[32];
            std::snprintf(buf, sizeof buf, "%.6ef", v[k]);
            o << (k % 6 ? " " : "\n    ") << buf << (k + 1 < v.size() ? "," : "");
        }
        o << "};\n";
    };
    o << "// [alpha node][mu node]\n";
    array("etk_base_table_a", a);
    array("etk_base_table_b", b);
    o << "// [alpha node]\n";
    array("etk_base_table_avg_a", aavg);
    array("etk_base_table_avg_b", bavg);
    o << "// clang-format on\n\nETK_END\n\n#endif\n";
    return o.str();
}

} // namespace

int main(int argc, char** argv) {
    const bool check = argc == 3 && std::string(argv[1]) == "--check";
    if (argc != 2 && !check) {
        std::fprintf(stderr, "usage: %s OUT.h | --check FILE\n", argv[0]);
        return 2;
    }
    const std::string text = table_text();
    if (check) {
        std::ifstream in(argv[2], std::ios::binary);
        const std::string have{std::istreambuf_iterator<char>(in),
                               std::istreambuf_iterator<char>()};
        if (have != text) {
            std::fprintf(
                stderr,
                "%s is not what tools/tables/make_base_albedo_table.cpp writes from the "
                "kernels' GGX functions: regenerate it (build/tools/make_base_albedo_table "
                "%s)\n",
                argv[2], argv[2]);
            return 1;
        }
        return 0;
    }
    std::ofstream out(argv[1], std::ios::binary);
    out << text;
    out.close();
    if (!out) {
        std::fprintf(stderr, "%s: cannot write\n", argv[1]);
        return 1;
    }
    return 0;
}
