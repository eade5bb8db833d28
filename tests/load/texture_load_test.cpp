// Material textures as the loaders read them (host/lib/load/texture.h): MTL map_Kd / map_Ks /
// map_Pr / map_Ns with their -s / -o options, OBJ texture coordinates, JSON texture objects and
// the generated checkerboard; colour decoded from sRGB, data as stored; hostile inputs (missing,
// non-regular, corrupt or oversized files, wrong JSON types) refused with the file and the key
// path named.
#include "image/image_io.h"
#include "kernels/texture_lookup.h"
#include "load/scene.h"
#include "util/error.h"
#include "test_data.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <random>

namespace {

void write_file(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}

// An 8-bit PNG of w x h grey or RGB values (k / 255 exactly).
void write_png(const std::string& path, int w, int h, const std::vector<int>& bytes) {
    std::vector<float> px;
    for (int b : bytes)
        px.push_back(b / 255.0f);
    et::write_image(path, w, h, static_cast<int>(bytes.size()) / (w * h), px);
}

// A textured quad: OBJ with texture coordinates and an MTL with the given body.
std::string textured_obj(const std::string& dir, const std::string& mtl_body) {
    write_file(dir + "/quad.mtl", "newmtl wood\n" + mtl_body);
    write_file(dir + "/quad.obj", "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                  "vt 0.1 0.2\nvt 0.9 0.2\nvt 0.9 0.8\nvt 0.1 0.8\n"
                                  "usemtl wood\nf 1/1 2/2 3/3 4/4\n");
    return dir + "/quad.obj";
}

std::string scene_with_material(const std::string& dir, const std::string& material) {
    const std::string path = dir + "/scene.json";
    write_file(path, R"({"environment": {"sky": {"resolution": [16, 8]}},
  "materials": {"m": )" + material +
                         R"(},
  "shapes": [{"type": "quad", "material": "m"}]})");
    return path;
}

using ett::error_of;

// The error (or "") of loading DIR/quad.obj with an MTL of the given body, textures read.
std::string textured_obj_error(const std::string& dir, const std::string& mtl_body) {
    return error_of([&] {
        std::vector<et::Material> mats;
        et::TriangleSoup soup;
        et::TextureSet textures;
        et::load_obj(textured_obj(dir, mtl_body), glm::mat4(1.0f), -1, mats, soup, &textures);
    });
}

TEST(TextureLoad, MtlMapsAndTextureCoordinates) {
    const std::string dir = ett::scratch_dir("texload-mtl");
    write_png(dir + "/wood.png", 2, 1, {0, 64, 128, 255, 200, 32});
    write_png(dir + "/rough.png", 2, 2, {128, 255, 0, 64});
    write_png(dir + "/spec.png", 1, 1, {10, 20, 30});
    const std::string obj = textured_obj(
        dir, "Kd 0.5 0.5 0.5\nmap_Kd -s 2 3 1 -o 0.25 0.5 0 wood.png\nmap_Ks spec.png\n"
             "map_Pr rough.png\nmap_Ns wood.png\n");
    std::vector<et::Material> mats;
    et::TriangleSoup soup;
    et::TextureSet textures;
    et::load_obj(obj, glm::mat4(1.0f), -1, mats, soup, &textures);
    ASSERT_EQ(mats.size(), 2u); // wood and the default
    const et::Material& m = mats[0];
    ASSERT_GE(m.albedo_tex, 0);
    ASSERT_GE(m.specular_tex, 0);
    ASSERT_GE(m.roughness_tex, 0);
    EXPECT_EQ(m.type, ETK_MAT_MICROFACET) << "a specular map makes the material glossy";
    const auto& T = textures.textures();
    ASSERT_EQ(T.size(), 3u);
    const et::Texture& kd = T[m.albedo_tex];
    EXPECT_EQ(kd.width, 2);
    EXPECT_EQ(kd.height, 1);
    EXPECT_EQ(kd.channels, 3);
    EXPECT_EQ(kd.uv_scale, glm::vec2(2.0f, 3.0f));
    EXPECT_EQ(kd.uv_offset, glm::vec2(0.25f, 0.5f));
    // Colour: decoded from sRGB.
    const int bytes[6] = {0, 64, 128, 255, 200, 32};
    for (int i = 0; i < 6; ++i)
        EXPECT_NEAR(kd.texels[i], et::srgb_to_linear(bytes[i] / 255.0f), 1e-6) << i;
    // Data (map_Pr wins over map_Ns): one channel, as stored.
    const et::Texture& pr = T[m.roughness_tex];
    EXPECT_EQ(pr.channels, 1);
    const int rough[4] = {128, 255, 0, 64};
    for (int i = 0; i < 4; ++i)
        EXPECT_NEAR(pr.texels[i], rough[i] / 255.0f, 1e-6) << i;
    // Texture coordinates of the two triangles of the face, corner by corner.
    ASSERT_EQ(soup.size(), 2u);
    ASSERT_EQ(soup.uvs.size(), 6u);
    for (size_t c = 0; c < 6; ++c) {
        const glm::vec3 p = soup.positions[c];
        EXPECT_NEAR(soup.uvs[c].x, 0.1f + 0.8f * p.x, 1e-6) << c;
        EXPECT_NEAR(soup.uvs[c].y, 0.2f + 0.6f * p.y, 1e-6) << c;
    }
}

TEST(TextureLoad, MapNsIsARoughnessMapAndFilesAreReadOnce) {
    const std::string dir = ett::scratch_dir("texload-ns");
    write_png(dir + "/g.png", 1, 1, {51});
    write_file(dir + "/two.mtl", "newmtl a\nmap_Kd g.png\nmap_Ns g.png\nnewmtl b\nmap_Kd g.png\n");
    write_file(dir + "/two.obj", "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n"
                                 "usemtl b\nf 1 3 2\n");
    std::vector<et::Material> mats;
    et::TriangleSoup soup;
    et::TextureSet textures;
    et::load_obj(dir + "/two.obj", glm::mat4(1.0f), -1, mats, soup, &textures);
    ASSERT_GE(mats.size(), 2u);
    EXPECT_EQ(mats[0].albedo_tex, mats[1].albedo_tex) << "one file, one texture";
    ASSERT_GE(mats[0].roughness_tex, 0);
    EXPECT_NEAR(textures.textures()[mats[0].roughness_tex].texels[0], 0.2f, 1e-6);
    EXPECT_EQ(textures.textures().size(), 2u); // g.png as colour and as data
    EXPECT_EQ(soup.uvs.size(), 6u);
    EXPECT_EQ(soup.uvs[0], glm::vec2(0.0f)) << "no vt: (0, 0)";
}

TEST(TextureLoad, BadMtlMapsAreErrorsNamingFileMaterialAndKey) {
    const std::string dir = ett::scratch_dir("texload-bad");
    auto load = [&](const std::string& body) { return textured_obj_error(dir, body); };
    std::string e = load("map_Kd missing.png\n");
    EXPECT_NE(e.find("quad.obj: material 'wood': map_Kd 'missing.png'"), std::string::npos) << e;
    EXPECT_NE(e.find("missing.png"), std::string::npos) << e;
    ASSERT_EQ(mkfifo((dir + "/fifo.png").c_str(), 0600), 0);
    e = load("map_Ks fifo.png\n");
    EXPECT_NE(e.find("map_Ks 'fifo.png'"), std::string::npos) << e;
    EXPECT_NE(e.find("regular"), std::string::npos) << e;
    e = load("map_Pr .\n");
    EXPECT_NE(e.find("map_Pr"), std::string::npos) << e;
    write_file(dir + "/corrupt.png", "\x89PNG\r\n\x1a\nthis is not a png");
    e = load("map_Kd corrupt.png\n");
    EXPECT_NE(e.find("map_Kd 'corrupt.png'"), std::string::npos) << e;
    // A 20-byte PFM that claims 100000 x 100000 texels: refused from its header.
    write_file(dir + "/huge.pfm", "PF\n100000 100000\n-1\n");
    e = load("map_Kd huge.pfm\n");
    EXPECT_NE(e.find("map_Kd 'huge.pfm'"), std::string::npos) << e;
    EXPECT_NE(e.find("100000x100000"), std::string::npos) << e;
    write_png(dir + "/ok.png", 1, 1, {1, 2, 3});
    e = load("map_Kd -s 1e30 1 1 ok.png\n");
    EXPECT_NE(e.find("-s / -o"), std::string::npos) << e;
    // Without a TextureSet (tools that want geometry only) maps are not read.
    std::vector<et::Material> mats;
    et::TriangleSoup soup;
    EXPECT_NO_THROW(
        et::load_obj(textured_obj(dir, "map_Kd missing.png\n"), glm::mat4(1.0f), -1, mats, soup));
}

// The MTL format's -s / -o / -t take one to three numbers; tinyobjloader reads three, and
// took the file name for the missing ones (the texture vanished without a word). Short forms keep
// their map and take the defaults; a statement left without a file name is an error.
TEST(TextureLoad, MtlOptionsWithFewerNumbersKeepTheirMap) {
    const std::string dir = ett::scratch_dir("texload-short-options");
    write_png(dir + "/wood.png", 1, 1, {10, 20, 30});
    std::filesystem::create_directories(dir + "/tex");
    write_png(dir + "/tex/w.png", 1, 1, {1, 2, 3});
    struct Case {
        std::string body;
        glm::vec2 scale, offset;
    };
    const Case cases[] = {
        {"map_Kd -s 2 3 wood.png\n", {2, 3}, {0, 0}},
        {"map_Kd -s 2 wood.png\n", {2, 1}, {0, 0}},
        {"map_Kd -o 0.5 wood.png\n", {1, 1}, {0.5f, 0}},
        {"map_Kd -blendu on -o 0.25 0.5 -s 4 wood.png\r\n", {4, 1}, {0.25f, 0.5f}},
        {"  map_Kd -mm 0 1 -t 1 wood.png\n", {1, 1}, {0, 0}},
        {"map_Kd tex\\w.png\n", {1, 1}, {0, 0}}, // a Windows folder separator
    };
    for (const Case& c : cases) {
        std::vector<et::Material> mats;
        et::TriangleSoup soup;
        et::TextureSet textures;
        et::load_obj(textured_obj(dir, c.body), glm::mat4(1.0f), -1, mats, soup, &textures);
        ASSERT_GE(mats.size(), 1u);
        ASSERT_GE(mats[0].albedo_tex, 0) << c.body;
        const et::Texture& t = textures.textures()[mats[0].albedo_tex];
        EXPECT_EQ(t.uv_scale, c.scale) << c.body;
        EXPECT_EQ(t.uv_offset, c.offset) << c.body;
    }
    auto error = [&](const std::string& body) { return textured_obj_error(dir, body); };
    // The file is missing: an error (it passed silently when its name was taken for a number).
    std::string e = error("map_Kd -s 2 2 nothere.png\n");
    EXPECT_NE(e.find("nothere.png"), std::string::npos) << e;
    e = error("Kd 1 1 1\nmap_Kd -s 2 2\n");
    EXPECT_NE(e.find("quad.mtl: line 3: map_Kd names no file"), std::string::npos) << e;
    e = error("map_Kd -s nan 1 1 wood.png\n");
    EXPECT_NE(e.find("map_Kd -s: the numbers must be finite"), std::string::npos) << e;
    e = error("map_Kd -o wood.png\n");
    EXPECT_NE(e.find("map_Kd -o takes one to three numbers"), std::string::npos) << e;
    e = error("map_Ks\n");
    EXPECT_NE(e.find("line 2: map_Ks names no file"), std::string::npos) << e;
    // Statements envtrace ignores stay ignored, whatever they hold.
    EXPECT_EQ(error("map_Kd wood.png\nmap_Ka\nbump -bm\nmap_d -s nan 1 1 x.png\n"), "");
}

TEST(TextureLoad, JsonTexturesAndCheckers) {
    const std::string dir = ett::scratch_dir("texload-json");
    write_png(dir + "/a.png", 2, 2, {0, 0, 0, 255, 255, 255, 128, 128, 128, 64, 64, 64});
    const et::Scene s = et::load_scene(scene_with_material(
        dir, R"({"type": "plastic", "albedo": {"texture": "a.png", "uv_scale": [4, 2]},
                 "specular": {"checker": {"color0": [0.1, 0.2, 0.3], "color1": 0.5}},
                 "roughness": {"texture": "a.png", "uv_offset": [0.5, 0]}})"));
    ASSERT_EQ(s.materials.size(), 1u);
    const et::Material& m = s.materials[0];
    const auto& T = s.textures.textures();
    ASSERT_EQ(T.size(), 3u);
    EXPECT_EQ(T[m.albedo_tex].uv_scale, glm::vec2(4.0f, 2.0f));
    EXPECT_EQ(T[m.albedo_tex].channels, 3);
    EXPECT_EQ(T[m.roughness_tex].channels, 1);
    EXPECT_EQ(T[m.roughness_tex].uv_offset, glm::vec2(0.5f, 0.0f));
    EXPECT_NEAR(T[m.roughness_tex].texels[2], 128 / 255.0f, 1e-6);
    EXPECT_EQ(T[m.specular_tex].name, "checker");
    EXPECT_EQ(T[m.specular_tex].width, 64); // 2 squares x the default 32 texels
    // The quad's texture coordinates span [0, 1].
    ASSERT_EQ(s.triangles.uvs.size(), 6u);
    for (const glm::vec2& uv : s.triangles.uvs)
        EXPECT_TRUE((uv.x == 0.0f || uv.x == 1.0f) && (uv.y == 0.0f || uv.y == 1.0f));
}

TEST(TextureLoad, BadJsonTexturesNameTheKeyPath) {
    const std::string dir = ett::scratch_dir("texload-json-bad");
    write_png(dir + "/a.png", 1, 1, {9});
    auto load = [&](const std::string& material) {
        return error_of([&] { et::load_scene(scene_with_material(dir, material)); });
    };
    const struct {
        const char* material;
        const char* expect;
    } cases[] = {
        {R"({"albedo": {"texture": 5}})", "materials.m.albedo.texture: expected an image file"},
        {R"({"albedo": {"texture": ""}})", "materials.m.albedo.texture: the file name is empty"},
        {R"({"albedo": {"texture": "nope.png"}})", "materials.m.albedo.texture"},
        {R"({"albedo": {}})", "materials.m.albedo: a texture needs exactly one"},
        {R"({"albedo": {"texture": "a.png", "checker": {}}})", "exactly one"},
        {R"({"type": "plastic", "specular": {"checker": 3}})", "materials.m.specular.checker"},
        {R"({"albedo": {"checker": {"color0": "red"}}})", "materials.m.albedo.checker.color0"},
        {R"({"albedo": {"checker": {"color1": [0.1, 2, 0.1]}}})",
         "materials.m.albedo.checker.color1[1]"},
        {R"({"albedo": {"checker": {"resolution": 0}}})", "materials.m.albedo.checker.resolution"},
        {R"({"albedo": {"checker": {"resolution": 1e9}}})", "resolution"},
        {R"({"type": "plastic", "roughness": {"texture": "a.png", "uv_scale": [1]}})",
         "materials.m.roughness.uv_scale: expected [u, v]"},
        {R"({"albedo": {"texture": "a.png", "uv_offset": [0, 1e300]}})",
         "materials.m.albedo.uv_offset[1]"},
        {R"({"albedo": {"texture": "a.png", "uv_scale": "big"}})", "uv_scale"},
    };
    for (const auto& c : cases) {
        const std::string e = load(c.material);
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.material << "\n  gave: " << e;
        EXPECT_NE(e.find("scene.json"), std::string::npos) << e;
    }
    // A folder named as a texture.
    std::filesystem::create_directory(dir + "/folder.png");
    const std::string e = load(R"({"albedo": {"texture": "folder.png"}})");
    EXPECT_NE(e.find("folder.png"), std::string::npos) << e;
    // Unknown keys are errors naming their path, with a suggestion when one is close.
    const std::string u = load(R"({"albedo": {"texture": "a.png", "filter": "nearest"}})");
    EXPECT_NE(u.find("materials.m.albedo.filter: unknown key (known here:"), std::string::npos)
        << u;
    const std::string v = load(R"({"albedo": {"checker": {"color0": 0.1, "colour1": 0.5}}})");
    EXPECT_NE(v.find("materials.m.albedo.checker.colour1: unknown key; did you mean \"color1\"?"),
              std::string::npos)
        << v;
}

// The generated checkerboard looked up through the kernels' lookup is Mitsuba 3's checkerboard:
// colour0 where the fractions of u and v are both below or both above 1/2 (away from the
// one-texel blend at the squares' edges).
TEST(TextureLoad, CheckerIsMitsubasCheckerboard) {
    const glm::vec3 c0(0.4f), c1(0.2f, 0.1f, 0.05f);
    const int res = 16;
    const et::Texture t = et::make_checker(c0, c1, res);
    const std::vector<etk::float4> info = {
        etk::make_float4(etk::as_float(0u), etk::as_float(uint32_t(t.width)),
                         etk::as_float(uint32_t(t.height)), etk::as_float(3u)),
        etk::make_float4(8, 8, 0, 0)};
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    int checked = 0;
    for (int i = 0; i < 20000; ++i) {
        const float a = u(rng), b = u(rng);
        const float fu = 8 * a - std::floor(8 * a), fv = 8 * b - std::floor(8 * b);
        const float margin = 1.0f / (2 * res); // one texel, in units of the period
        auto near_edge = [&](float f) {
            return std::fabs(f - 0.5f) < margin || f < margin || f > 1.0f - margin;
        };
        if (near_edge(fu) || near_edge(fv))
            continue;
        const glm::vec3 want = (fu > 0.5f) == (fv > 0.5f) ? c0 : c1;
        const etk::float3 got =
            etk::etk_texture(info.data(), t.texels.data(), 0, etk::make_float2(a, b));
        ASSERT_NEAR(got.x, want.x, 1e-6) << a << "," << b;
        ASSERT_NEAR(got.z, want.z, 1e-6) << a << "," << b;
        ++checked;
    }
    EXPECT_GT(checked, 10000);
}

} // namespace
