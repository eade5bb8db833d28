// spot1Lux.hdr (../shared/data): one tiny spot holding all the map's power (its README: the
// integral of L over the sphere is ~0.959, and a white Lambertian surface facing it reads
// ~0.305 = 0.959 / pi). A white (albedo 1) Lambertian square is turned to face the spot, found
// as the brightest texel through the lat-long convention of the data README, and filmed from
// the spot's side: every pixel must read the radiance (1 / pi) \int L cos dw.
//
// The expected value is computed here from the texels (double precision, exact texel solid
// angles 2 pi / W (cos theta0 - cos theta1)), independently of the renderer's tables; it must
// also agree with the README's 0.305. Tolerance: 5 sigma of the pixel mean (per-pass variance)
// plus 0.5% for the renderer's bilinear radiance lookup against the texel-constant sum (the spot
// covers a few texels; both integrate the same power to within that).
#include "render_util.h"

#include <gtest/gtest.h>

namespace {

struct Spot {
    glm::dvec3 dir;
    double expected[3];
};

// The direction of texel centre (col, row): u grows towards +X, v = 0 looks up, the centre
// looks along -Z.
glm::dvec3 texel_dir(int col, int row, int w, int h) {
    const double u = (col + 0.5) / w, v = (row + 0.5) / h;
    const double phi = M_PI * (2 * u - 1), theta = M_PI * v;
    return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

Spot find_spot(const et::RgbImage& img) {
    int best = 0;
    double best_l = -1.0;
    for (int i = 0; i < img.width * img.height; ++i) {
        const float* t = &img.rgb[3 * i];
        const double l = 0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2];
        if (l > best_l)
            best_l = l, best = i;
    }
    Spot s;
    s.dir = texel_dir(best % img.width, best / img.width, img.width, img.height);
    for (int c = 0; c < 3; ++c)
        s.expected[c] = 0.0;
    for (int row = 0; row < img.height; ++row) {
        const double d_omega =
            2 * M_PI / img.width *
            (std::cos(M_PI * row / img.height) - std::cos(M_PI * (row + 1) / img.height));
        for (int col = 0; col < img.width; ++col) {
            const double cosine = glm::dot(texel_dir(col, row, img.width, img.height), s.dir);
            if (cosine <= 0)
                continue;
            for (int c = 0; c < 3; ++c)
                s.expected[c] += img.at(col, row)[c] * cosine * d_omega / M_PI;
        }
    }
    return s;
}

class SpotTest : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(SpotTest, WhitePlaneFacingTheSpotReadsIrradianceOverPi) {
    ETT_DATA_FILE(path, "envmaps/spot1Lux.hdr");
    const auto& [backend, strategy] = GetParam();
    et::EnvMap env = et::load_envmap(path, {});
    const Spot spot = find_spot(env.image);
    std::printf("spot direction (%.4f, %.4f, %.4f); expected radiance %.5f %.5f %.5f\n", spot.dir.x,
                spot.dir.y, spot.dir.z, spot.expected[0], spot.expected[1], spot.expected[2]);
    for (double e : spot.expected)
        EXPECT_NEAR(e, 0.305, 0.005) << "the data README's figure";

    et::Scene s = ett::base_scene(16, 16, std::move(env));
    s.materials.push_back(ett::diffuse(1.0f));
    const glm::vec3 d(spot.dir);
    ett::add_square(s.triangles, glm::vec3(0.0f), d, 10.0f, 0);
    s.camera.eye = 2.0f * d;
    s.camera.target = glm::vec3(0.0f);
    s.camera.up = std::fabs(d.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
    s.camera.fov_deg = 30.0f; // the square fills the view
    s.settings.max_depth = 1;
    s.settings.strategy = et::parse_strategy(strategy, "test");
    s.settings.seed = 3;
    const ett::RenderResult r = ett::render(s, backend, 16);
    double sum = 0.0;
    for (size_t i = 0; i < r.mean.size(); ++i) {
        const double e = spot.expected[i % 3];
        EXPECT_NEAR(r.mean[i], e, 5 * std::sqrt(r.var_mean(i)) + 0.005 * e) << "pixel " << i / 3;
        sum += r.mean[i];
    }
    std::printf("%s %s: mean pixel %.5f (expected %.5f)\n", backend.c_str(), strategy.c_str(),
                sum / r.mean.size(), (spot.expected[0] + spot.expected[1] + spot.expected[2]) / 3);
}

INSTANTIATE_TEST_SUITE_P(
    All, SpotTest,
    ::testing::Values(std::make_tuple("opencl", "light"), std::make_tuple("opencl", "mis"),
                      std::make_tuple("cpu", "light"), std::make_tuple("cpu", "mis")),
    [](const auto& info) { return std::get<0>(info.param) + "_" + std::get<1>(info.param); });

} // namespace
