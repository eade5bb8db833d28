// The last bounce's shortcuts (kernels/integrator.h): its continuation is not traced towards a
// block of the map that is black for certain (host/lib/prepare/env_black_mask.h), and any ray
// from the last vertex is traced for any hit, not the closest. Neither may change the image: a
// map that is black but for a lamp and a band of sky, spheres (diffuse, glossy, mirror) on a
// ground, depth 1 and 3, the paper's MIS, BSDF sampling and the visibility strategy, on both back
// ends, renders the same bits with the mask and without it (the prepared scene's mask switched
// off), while the mask spares most of the last bounce's continuations.
#include "render/renderer.h"
#include "render_util.h"
#include "test_data.h"

#include <gtest/gtest.h>

namespace {

et::Scene lamp_scene(int depth, et::Strategy strategy) {
    et::RgbImage img = ett::constant_image(128, 64, 0.0f);
    for (int y = 10; y < 13; ++y) // the lamp, high in the sky
        for (int x = 40; x < 43; ++x)
            for (int c = 0; c < 3; ++c)
                img.at(x, y)[c] = 400.0f;
    for (int y = 26; y < 30; ++y) // a band of sky just above the horizon, on one side
        for (int x = 80; x < 110; ++x)
            img.at(x, y)[2] = 2.0f;
    et::Scene s = ett::base_scene(40, 24, et::make_envmap("lamp", img, {}));
    et::Material glossy;
    glossy.type = ETK_MAT_MICROFACET;
    glossy.specular = glm::vec3(0.8f);
    glossy.roughness = 0.2f;
    et::Material mirror;
    mirror.type = ETK_MAT_MIRROR;
    mirror.specular = glm::vec3(0.9f);
    s.materials = {ett::diffuse(0.6f), glossy, mirror};
    ett::add_square(s.triangles, glm::vec3(0, 0, 0), glm::vec3(0, 1, 0), 6.0f, 0);
    ett::add_sphere(s.triangles, glm::vec3(-1.1f, 0.5f, 0), 0.5f, 16, true, 0);
    ett::add_sphere(s.triangles, glm::vec3(0, 0.5f, 0), 0.5f, 16, true, 1);
    ett::add_sphere(s.triangles, glm::vec3(1.1f, 0.5f, 0), 0.5f, 16, true, 2);
    s.camera.eye = {0.0f, 1.2f, 4.0f};
    s.camera.target = {0.0f, 0.4f, 0.0f};
    s.camera.fov_deg = 40.0f;
    s.settings.max_depth = depth;
    s.settings.strategy = strategy;
    s.settings.sampler = et::SamplerKind::sobol;
    return s;
}

struct MaskRun {
    std::vector<float> image;
    uint64_t continuations = 0;
};

MaskRun render(const et::Scene& scene, const std::string& backend, bool mask) {
    et::RenderSettings st = scene.settings;
    st.backend = et::parse_backend(backend, "test");
    st.threads = 2;
    et::DeviceScene ds = et::prepare_device_scene(scene, st);
    EXPECT_GT(ds.params.env.black_w, 0) << "the lamp's map must have a black mask";
    if (!mask)
        ds.params.env.black_w = ds.params.env.black_h = 0;
    auto r = et::make_renderer(ds);
    for (uint32_t k = 0; k < 12; ++k)
        r->render_sample(k);
    MaskRun out;
    out.image = r->image();
    out.continuations = r->stats().continuation_rays;
    EXPECT_EQ(r->stats().nonfinite_samples, 0u);
    return out;
}

TEST(LastBounce, SkippingBlackContinuationsChangesNoBit) {
    for (const char* backend : {"cpu", "opencl"})
        for (int depth : {1, 3})
            for (et::Strategy strategy :
                 {et::Strategy::mis, et::Strategy::bsdf, et::Strategy::visibility}) {
                SCOPED_TRACE(std::string(backend) + " depth " + std::to_string(depth) + " " +
                             et::name_of(strategy));
                const et::Scene s = lamp_scene(depth, strategy);
                const MaskRun with = render(s, backend, true), without = render(s, backend, false);
                ASSERT_EQ(with.image.size(), without.image.size());
                size_t differ = 0;
                for (size_t i = 0; i < with.image.size(); ++i)
                    differ += with.image[i] != without.image[i];
                EXPECT_EQ(differ, 0u) << "values that the mask changed";
                EXPECT_GT(ett::image_mean(with.image), 0.0);
                if (depth == 1) // every continuation is the last bounce's: most look at black
                    EXPECT_LT(with.continuations, without.continuations / 2);
                else
                    EXPECT_LT(with.continuations, without.continuations);
            }
}

} // namespace
