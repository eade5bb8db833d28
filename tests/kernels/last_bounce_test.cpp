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

// band: a band of sky too; w: the map's width (its height is half that).
et::Scene lamp_scene(int depth, et::Strategy strategy, bool band = true, int w = 128) {
    et::RgbImage img = ett::constant_image(w, w / 2, 0.0f);
    const int k = w / 128;
    for (int y = 10 * k; y < 10 * k + 3; ++y) // the lamp, high in the sky
        for (int x = 40 * k; x < 40 * k + 3; ++x)
            for (int c = 0; c < 3; ++c)
                img.at(x, y)[c] = 400.0f;
    for (int y = 26 * k; y < 30 * k && band; ++y) // a band of sky above the horizon, on one side
        for (int x = 80 * k; x < 110 * k; ++x)
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

// lit_sr > 0: the mask's lit solid angle replaced (the compensated strategy's last BSDF share).
MaskRun render(const et::Scene& scene, const std::string& backend, bool mask, float lit_sr = 0.0f) {
    et::RenderSettings st = scene.settings;
    st.backend = et::parse_backend(backend, "test");
    st.threads = 2;
    et::DeviceScene ds = et::prepare_device_scene(scene, st);
    EXPECT_GT(ds.params.env.black_w, 0) << "the lamp's map must have a black mask";
    if (!mask)
        ds.params.env.black_w = ds.params.env.black_h = 0;
    if (lit_sr > 0.0f)
        ds.params.env.lit_sr = lit_sr;
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

// The compensated strategy takes its last vertex's BSDF sample with probability q = the lit solid
// angle times the BSDF's density bound (integrator.h, etk_last_bsdf_share): under a lamp alone
// (lit: 0.1 sr, q = 0.03 on diffuse surfaces) most of those samples are never drawn, so fewer
// continuations are traced than with the rule off (a lit solid angle so large that q = 1); the
// image changes (an estimator with other weights), on both back ends. That it converges to the
// same image is Strategies.CompensatedWithFewLastBsdfSamplesConverges.
TEST(LastBounce, CompensatedDrawsFewBsdfSamplesUnderALamp) {
    // The cosine strategy is the compensated one with other light samples at the first vertex.
    for (et::Strategy strategy : {et::Strategy::compensated, et::Strategy::cosine})
        for (const char* backend : {"cpu", "opencl"})
            for (int depth : {1, 3}) {
                SCOPED_TRACE(std::string(et::name_of(strategy)) + " " + backend + " depth " +
                             std::to_string(depth));
                const et::Scene s = lamp_scene(depth, strategy, false, 256);
                const MaskRun few = render(s, backend, true), all = render(s, backend, true, 1e30f);
                size_t differ = 0;
                for (size_t i = 0; i < few.image.size(); ++i)
                    differ += few.image[i] != all.image[i];
                if (depth == 1) { // every vertex is the last
                    EXPECT_LT(few.continuations, all.continuations / 4);
                    EXPECT_GT(differ, few.image.size() / 4);
                } else { // only paths that reach a third surface
                    EXPECT_LT(few.continuations, all.continuations);
                    EXPECT_GT(differ, 0u);
                }
                EXPECT_NEAR(ett::image_mean(few.image), ett::image_mean(all.image),
                            0.1 * ett::image_mean(all.image));
            }
}

} // namespace
