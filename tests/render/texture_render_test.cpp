// Textured surfaces rendered end to end on both back ends:
// - a diffuse quad under a constant environment of radiance 1, seen straight on, with BSDF
//   sampling at depth 1: every sample weighs albedo x 1, so a pixel is the mean of the albedo
//   texture over its footprint. The texture is 4 x 4 blocks of 2 x 2 equal texels, so over the
//   middle of each block bilinear lookup is exactly the block's colour: those pixels must equal
//   their texel (a flipped v, a shifted texel centre or a wrong channel order fails);
// - a scene with a checkerboard floor and an image-textured plastic sphere (albedo and
//   roughness maps), loaded from JSON: the OpenCL and native images are bit-identical.
#include "image/image_io.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <random>

namespace {

class TexturedQuad : public ::testing::TestWithParam<const char*> {};

TEST_P(TexturedQuad, PixelsEqualTheirTexels) {
    const int W = 32, blocks = 4;
    et::Scene s =
        ett::base_scene(W, W, et::make_envmap("one", ett::constant_image(64, 32, 1.0f), {}));
    s.settings.strategy = et::Strategy::bsdf;
    s.settings.max_depth = 1;
    // Looking down -Y at the quad [-1, 1]^2 (y = 0), image up = -Z, the quad filling the view.
    s.camera.eye = glm::vec3(0, 2, 0);
    s.camera.target = glm::vec3(0);
    s.camera.up = glm::vec3(0, 0, -1);
    s.camera.fov_deg = static_cast<float>(2.0 * std::atan(0.5) * 180.0 / M_PI);
    // 8 x 8 texels: block (i, j) (column i, row j from the top) is 2 x 2 texels of one colour.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.1f, 0.9f);
    std::vector<glm::vec3> colour(blocks * blocks);
    for (auto& c : colour)
        c = glm::vec3(u(rng), u(rng), u(rng));
    et::Texture t;
    t.name = "blocks";
    t.width = t.height = 2 * blocks;
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) {
            const glm::vec3 c = colour[(y / 2) * blocks + x / 2];
            t.texels.insert(t.texels.end(), {c.x, c.y, c.z});
        }
    et::Material m = ett::diffuse(0.5f);
    m.albedo_tex = s.textures.add(std::move(t), "test");
    s.materials.push_back(m);
    // Corners (x, z) with (u, v) = ((x + 1) / 2, (1 - z) / 2): v = 1 at the image's top (-Z).
    const glm::vec3 p[4] = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
    const glm::vec2 uv[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    const glm::vec3 a[3] = {p[0], p[2], p[1]}, b[3] = {p[0], p[3], p[2]};
    const glm::vec2 ua[3] = {uv[0], uv[2], uv[1]}, ub[3] = {uv[0], uv[3], uv[2]};
    ASSERT_TRUE(et::add_triangle(s.triangles, a, nullptr, 0, ua));
    ASSERT_TRUE(et::add_triangle(s.triangles, b, nullptr, 0, ub));

    const ett::RenderResult r = ett::render(s, GetParam(), 8, false);
    // Pixel (px, py) covers u in [px, px + 1] / 32: 8 pixels per block, of which 2..5 lie
    // between the block's texel centres, where the lookup is constant.
    int checked = 0;
    for (int py = 0; py < W; ++py)
        for (int px = 0; px < W; ++px) {
            if (px % 8 < 2 || px % 8 > 5 || py % 8 < 2 || py % 8 > 5)
                continue;
            const glm::vec3 want = colour[(py / 8) * blocks + px / 8];
            const float* got = &r.mean[3 * (static_cast<size_t>(py) * W + px)];
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(got[c], want[c], 2e-5f * want[c])
                    << GetParam() << " pixel " << px << "," << py << " channel " << c;
            ++checked;
        }
    EXPECT_EQ(checked, 16 * 16);
}

INSTANTIATE_TEST_SUITE_P(Backends, TexturedQuad, ::testing::Values("opencl", "cpu"),
                         [](const auto& info) { return std::string(info.param); });

TEST(TexturedScene, BackendsBitIdentical) {
    if (!et::have_image_library())
        GTEST_SKIP() << "its textures are 8-bit PNGs: a build without OpenImageIO reads PFM only";
    const std::string dir = ett::scratch_dir("texture-render");
    // A 16 x 8 colour image and an 8 x 8 roughness ramp, written as 8-bit PNGs.
    std::vector<float> img, rough;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x)
            img.insert(img.end(), {x / 15.0f, y / 7.0f, ((x + y) % 3) / 2.0f});
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            rough.insert(rough.end(), {0.05f + 0.1f * x, 0.0f, 0.0f});
    et::write_image(dir + "/colour.png", 16, 8, 3, img);
    et::write_image(dir + "/rough.png", 8, 8, 3, rough);
    std::ofstream(dir + "/scene.json") << R"({
  "camera": {"eye": [0, 1.2, 3.2], "target": [0, 0.5, 0], "fov": 40},
  "film": {"width": 40, "height": 30},
  "environment": {"sky": {"resolution": [64, 32]}},
  "materials": {
    "floor": {"albedo": {"checker": {"color0": 0.8, "color1": 0.1, "resolution": 8},
                         "uv_scale": 4}},
    "ball": {"type": "plastic", "albedo": {"texture": "colour.png", "uv_scale": [2, 1]},
             "roughness": {"texture": "rough.png"}}
  },
  "shapes": [
    {"type": "quad", "size": 6, "material": "floor"},
    {"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "segments": 32, "material": "ball"}
  ],
  "render": {"max_depth": 1, "sampler": "sobol"}
})";
    const et::Scene s = et::load_scene(dir + "/scene.json");
    ASSERT_EQ(s.textures.textures().size(), 3u);
    const ett::RenderResult cl = ett::render(s, "opencl", 4, false);
    const ett::RenderResult cpu = ett::render(s, "cpu", 4, false);
    ASSERT_EQ(cl.mean.size(), cpu.mean.size());
    EXPECT_GT(ett::image_mean(cpu.mean), 0.0);
    EXPECT_EQ(0, std::memcmp(cl.mean.data(), cpu.mean.data(), cl.mean.size() * sizeof(float)))
        << "the OpenCL and native images differ";
    // The textures show: the floor's squares differ by far more than noise in a pixel pair.
    float lo = 1e30f, hi = 0.0f;
    for (int x = 0; x < 40; ++x) {
        const float v = cpu.mean[3 * (29 * 40 + x)];
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    EXPECT_GT(hi, 3.0f * lo) << "the bottom row crosses light and dark squares";
}

// The texture buffer is checked against the device's limits like every scene buffer: a texture
// bigger than CL_DEVICE_MAX_MEM_ALLOC_SIZE (lowered through ENVTRACE_CL_MAX_ALLOC) is refused
// before anything is allocated, naming the buffer.
TEST(TexturedScene, TextureBufferCheckedAgainstDeviceLimits) {
    et::Scene s =
        ett::base_scene(4, 4, et::make_envmap("one", ett::constant_image(8, 4, 1.0f), {}));
    et::Material m = ett::diffuse(0.5f);
    m.albedo_tex = s.textures.add(et::make_checker(glm::vec3(1.0f), glm::vec3(0.0f), 256), "test");
    s.materials.push_back(m);
    ett::add_square(s.triangles, glm::vec3(0, 0, -3), glm::vec3(0, 0, 1), 1.0f, 0);
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::opencl;
    const et::DeviceScene ds = et::prepare_device_scene(s, st);
    const uint64_t bytes = ds.tex_texels.size() * sizeof(float);
    ASSERT_EQ(bytes, 512u * 512u * 3u * 4u);
    ASSERT_EQ(ds.tri_uv.size(), 12u);
    setenv("ENVTRACE_CL_MAX_ALLOC", std::to_string(bytes - 1).c_str(), 1);
    std::string msg;
    try {
        et::make_renderer(ds);
    } catch (const et::Error& e) {
        msg = e.what();
    }
    unsetenv("ENVTRACE_CL_MAX_ALLOC");
    EXPECT_NE(msg.find("buffer tex_texels needs " + std::to_string(bytes) + " bytes"),
              std::string::npos)
        << msg;
}

} // namespace
