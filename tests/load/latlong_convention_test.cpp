// The lat-long conventions of other renderers (host/lib/load/environment_map.h,
// LatLongConvention): for each, a map with one bright texel at a known (column, row) must light
// the direction that renderer's own formula gives that texel, through envtrace's lookup, its
// importance sampling and an actual render on both back ends. The formulas below are written
// from the renderers' sources, in double, independently of envtrace's:
// - Mitsuba 3, envmap emitter (y-up local frame; to_world maps it to the world):
//     eval:   u = atan2(v.x, -v.z) / 2 pi (mod 1),  v = acos(v.y) / pi   (row 0 at the top)
//     sample: theta = pi v, phi = 2 pi u, local = (sin theta sin phi, cos theta, -sin theta cos
//     phi)
// - Blender Cycles, direction_to_equirectangular (z-up world b), image v measured from the
//   bottom row:
//     u = (atan2(b.y, b.x) - pi) / (-2 pi),  v = (acos(b.z) - pi) / (-pi)
//     inverse: phi = -2 pi u + pi, theta = -pi v + pi, b = (sin th cos ph, sin th sin ph, cos th)
//   with Blender's world brought to envtrace's y-up one by the proper rotation
//   (x, y, z)_blender -> (x, z, -y) (Blender's OBJ/glTF export with +Y up).
#include "load/environment_map.h"
#include "load/scene_environment.h"
#include "image/image_io.h"
#include "util/error.h"
#include "render_util.h"
#include "test_data.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <random>

namespace {

using et::LatLongConvention;
using etk::float2;
using etk::float3;

struct D3 {
    double x, y, z;
};
struct UV {
    double u, v; // v measured from the top row, as envtrace's
};

// Mitsuba 3: the local (map-frame) direction of map coordinates and back.
D3 mitsuba_dir(UV t) {
    const double th = M_PI * t.v, ph = 2 * M_PI * t.u;
    return {std::sin(th) * std::sin(ph), std::cos(th), -std::sin(th) * std::cos(ph)};
}
UV mitsuba_uv(D3 d) {
    double u = std::atan2(d.x, -d.z) / (2 * M_PI);
    u -= std::floor(u);
    return {u, std::acos(std::clamp(d.y, -1.0, 1.0)) / M_PI};
}

// Blender Cycles, in envtrace's y-up world.
D3 blender_dir(UV t) {
    const double vb = 1.0 - t.v; // Blender's v counts from the bottom row
    const double ph = -2 * M_PI * t.u + M_PI, th = -M_PI * vb + M_PI;
    const D3 b = {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
    return {b.x, b.z, -b.y};
}
UV blender_uv(D3 d) {
    const D3 b = {d.x, -d.z, d.y}; // y-up -> Blender's z-up
    double u = (std::atan2(b.y, b.x) - M_PI) / (-2 * M_PI);
    u -= std::floor(u);
    const double vb = (std::acos(std::clamp(b.z, -1.0, 1.0)) - M_PI) / (-M_PI);
    return {u, 1.0 - vb};
}

// envtrace's own (kernels/latlong.h, docs/conventions.md), for the control cases.
D3 envtrace_dir(UV t) {
    const double th = M_PI * t.v, ph = M_PI * (2 * t.u - 1);
    return {std::sin(th) * std::sin(ph), std::cos(th), -std::sin(th) * std::cos(ph)};
}
UV envtrace_uv(D3 d) {
    double u = 0.5 * (1 + std::atan2(d.x, -d.z) / M_PI);
    u -= std::floor(u);
    return {u, std::acos(std::clamp(d.y, -1.0, 1.0)) / M_PI};
}

D3 dir_of(LatLongConvention c, UV t) {
    return c == LatLongConvention::mitsuba   ? mitsuba_dir(t)
           : c == LatLongConvention::blender ? blender_dir(t)
                                             : envtrace_dir(t);
}
UV uv_of(LatLongConvention c, D3 d) {
    return c == LatLongConvention::mitsuba   ? mitsuba_uv(d)
           : c == LatLongConvention::blender ? blender_uv(d)
                                             : envtrace_uv(d);
}

// Right-handed rotation by `deg` about +Y (Mitsuba's <rotate y="1" angle="deg"/>).
D3 rotate_y(D3 d, double deg) {
    const double a = deg * M_PI / 180, c = std::cos(a), s = std::sin(a);
    return {c * d.x + s * d.z, d.y, -s * d.x + c * d.z};
}

float3 to_f(D3 d) {
    return etk::make_float3(float(d.x), float(d.y), float(d.z));
}
D3 to_d(float3 d) {
    return {d.x, d.y, d.z};
}

// u difference on the circle, in (-0.5, 0.5].
double du(double a, double b) {
    return a - b - std::round(a - b);
}

const LatLongConvention kAll[] = {LatLongConvention::envtrace, LatLongConvention::mitsuba,
                                  LatLongConvention::blender};

TEST(LatLongConvention, NamesAndTurns) {
    for (LatLongConvention c : kAll) {
        LatLongConvention back = LatLongConvention::envtrace;
        ASSERT_TRUE(et::parse_convention(et::name_of(c), back));
        EXPECT_EQ(back, c);
    }
    LatLongConvention c;
    EXPECT_FALSE(et::parse_convention("luxcore", c));
    EXPECT_FALSE(et::parse_convention("Mitsuba", c));
    EXPECT_EQ(et::convention_rotation_degrees(LatLongConvention::envtrace), 0.0);
    EXPECT_EQ(et::convention_rotation_degrees(LatLongConvention::mitsuba), 180.0);
    EXPECT_EQ(et::convention_rotation_degrees(LatLongConvention::blender), 90.0);
}

// The relations of docs/conventions.md: u_mitsuba = u - 1/2, u_blender = u - 1/4, v the same; both
// proper rotations (checked over the sphere, so a mirrored convention would fail).
TEST(LatLongConvention, OtherRenderersAreTurnsOfEnvtraces) {
    std::mt19937 rng(14);
    std::normal_distribution<double> g;
    for (int i = 0; i < 20000; ++i) {
        D3 d = {g(rng), g(rng), g(rng)};
        const double n = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
        d = {d.x / n, d.y / n, d.z / n};
        const UV e = envtrace_uv(d), m = mitsuba_uv(d), b = blender_uv(d);
        if (std::hypot(d.x, d.z) < 1e-6)
            continue;
        ASSERT_NEAR(du(m.u, e.u - 0.5), 0.0, 1e-9);
        ASSERT_NEAR(du(b.u, e.u - 0.25), 0.0, 1e-9);
        ASSERT_NEAR(m.v, e.v, 1e-9);
        ASSERT_NEAR(b.v, e.v, 1e-9);
        // The inverses are inverses.
        for (LatLongConvention c : kAll) {
            const D3 r = dir_of(c, uv_of(c, d));
            ASSERT_NEAR(r.x, d.x, 1e-9);
            ASSERT_NEAR(r.y, d.y, 1e-9);
            ASSERT_NEAR(r.z, d.z, 1e-9);
        }
    }
    // Landmarks: Mitsuba's left edge and Blender's centre.
    const D3 ml = mitsuba_dir({0.0, 0.5}), bc = blender_dir({0.5, 0.5}), bt = blender_dir({0.3, 0});
    EXPECT_NEAR(ml.z, -1.0, 1e-12);
    EXPECT_NEAR(bc.x, 1.0, 1e-12);
    EXPECT_NEAR(bt.y, 1.0, 1e-12); // row 0 looks up in Blender too: no vertical flip
}

// envtrace's lookup coordinates of a world direction, with convention and rotation, against the
// other renderer's formula; for Mitsuba with to_world = <rotate y="1" angle="a"/> too, which is
// envtrace's "rotation": -a.
TEST(LatLongConvention, LookupCoordinatesMatchTheOtherRenderer) {
    et::EnvMap env;
    env.image = ett::constant_image(8, 4, 1.0f);
    std::mt19937 rng(7);
    std::normal_distribution<double> g;
    for (LatLongConvention c : kAll)
        for (double to_world_deg : {0.0, 30.0, -77.0, 103.0, 270.0}) {
            SCOPED_TRACE(std::string(et::name_of(c)) + " " + std::to_string(to_world_deg));
            env.convention = c;
            env.rotation_degrees = float(-to_world_deg);
            const etk::EtkEnvMap desc = env.desc();
            for (int i = 0; i < 2000; ++i) {
                D3 d = {g(rng), g(rng), g(rng)};
                const double n = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
                d = {d.x / n, d.y / n, d.z / n};
                if (std::hypot(d.x, d.z) < 1e-3)
                    continue;
                const float2 uv = etk::etk_env_uv(desc, to_f(d));
                const UV want = uv_of(c, rotate_y(d, -to_world_deg)); // to_world^-1 d
                ASSERT_NEAR(du(uv.x, want.u), 0.0, 2e-6) << d.x << " " << d.y << " " << d.z;
                ASSERT_NEAR(uv.y, want.v, 2e-6);
            }
        }
}

// Which way "rotation" turns the map (docs/conventions.md): positive turns it clockwise seen from
// above, what the map shows towards -Z moving towards +X; the texel at u lands where u + rotation /
// 360 was.
TEST(LatLongConvention, PositiveRotationTurnsMinusZTowardsPlusX) {
    et::EnvMap env;
    env.image = ett::constant_image(8, 4, 1.0f);
    env.rotation_degrees = 90.0f;
    const float3 w = etk::etk_env_to_world(env.desc(), etk::make_float3(0, 0, -1));
    EXPECT_NEAR(w.x, 1.0f, 1e-6f);
    EXPECT_NEAR(w.z, 0.0f, 1e-6f);
    env.rotation_degrees = 30.0f;
    const UV t = {0.4, 0.3};
    const float3 landed = etk::etk_env_to_world(env.desc(), to_f(envtrace_dir(t)));
    EXPECT_NEAR(du(envtrace_uv(to_d(landed)).u, t.u + 30.0 / 360), 0.0, 1e-6);
}

// One bright texel at (col, row), a map made for convention c.
et::EnvMap one_texel_map(int w, int h, int col, int row, LatLongConvention c) {
    et::RgbImage img = ett::constant_image(w, h, 0.0f);
    for (int k = 0; k < 3; ++k)
        img.at(col, row)[k] = 100.0f;
    et::DistributionOptions o;
    o.blur_sigma = 0.0f; // the distribution's support is the bilinear footprint of the texel
    o.threads = 1;
    et::EnvMap env = et::make_envmap("one texel", img, o);
    env.convention = c;
    return env;
}

struct Texel {
    int col, row;
};
const Texel kTexels[] = {{5, 9}, {40, 20}, {63, 15}, {0, 3}, {21, 27}, {48, 16}};

// The direction the other renderer gives the texel's centre: envtrace looks up the full value
// there (bilinear at a texel centre), and nothing where envtrace's own convention would put it.
TEST(LatLongConvention, OneBrightTexelLightsTheOtherRenderersDirection) {
    const int w = 64, h = 32;
    for (LatLongConvention c : kAll)
        for (const Texel& t : kTexels) {
            SCOPED_TRACE(std::string(et::name_of(c)) + " texel " + std::to_string(t.col) + "," +
                         std::to_string(t.row));
            const et::EnvMap env = one_texel_map(w, h, t.col, t.row, c);
            const etk::EtkEnvMap desc = env.desc();
            const UV centre = {(t.col + 0.5) / w, (t.row + 0.5) / h};
            const float3 want = to_f(dir_of(c, centre));
            EXPECT_NEAR(etk::etk_env_radiance(env.image.rgb.data(), desc, want).x, 100.0f, 0.05f);
            EXPECT_GT(etk::etk_env_pdf(env.dist.table.data(), desc, want), 0.0f);
            if (c != LatLongConvention::envtrace) {
                // The map read in envtrace's convention lights another direction: the test can
                // tell the conventions apart.
                const float3 own = to_f(envtrace_dir(centre));
                EXPECT_EQ(etk::etk_env_radiance(env.image.rgb.data(), desc, own).x, 0.0f);
            }
        }
}

// Importance sampling under the convention: every sample lies within the distribution cells that
// the texel's bilinear footprint (one texel either side of its centre) touches, i.e. within 1.5
// texels of its centre in the other renderer's coordinates, and its density is the pdf of its
// direction.
TEST(LatLongConvention, SamplesLandOnTheOtherRenderersTexel) {
    const int w = 64, h = 32;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> xi(0.0f, 1.0f);
    for (LatLongConvention c : kAll)
        for (const Texel& t : kTexels) {
            SCOPED_TRACE(std::string(et::name_of(c)) + " texel " + std::to_string(t.col) + "," +
                         std::to_string(t.row));
            et::EnvMap env = one_texel_map(w, h, t.col, t.row, c);
            env.rotation_degrees = 0.0f;
            const etk::EtkEnvMap desc = env.desc();
            double su = 0, sv = 0, sw = 0;
            int pdf_off = 0;
            for (int i = 0; i < 2000; ++i) {
                const float x0 = std::min(xi(rng), 0.99999994f),
                            x1 = std::min(xi(rng), 0.99999994f);
                const etk::EtkEnvSample s =
                    etk::etk_env_sample(env.dist.table.data(), desc, etk::make_float2(x0, x1));
                ASSERT_GT(s.pdf, 0.0f);
                const UV got = uv_of(c, to_d(s.dir));
                const double dcol = du(got.u, (t.col + 0.5) / w) * w;
                const double drow = (got.v - (t.row + 0.5) / h) * h;
                ASSERT_LT(std::fabs(dcol), 1.5 + 1e-3);
                ASSERT_LT(std::fabs(drow), 1.5 + 1e-3);
                // The density of the direction; a sample within rounding of a cell edge may read
                // the neighbouring cell's.
                const float pdf = etk::etk_env_pdf(env.dist.table.data(), desc, s.dir);
                pdf_off += std::fabs(pdf - s.pdf) > 2e-3f * s.pdf;
                su += dcol, sv += drow, sw += 1;
            }
            EXPECT_LE(pdf_off, 10);
            // Centred on the texel (the tent is symmetric; sin theta tilts v slightly).
            EXPECT_NEAR(su / sw, 0.0, 0.1);
            EXPECT_NEAR(sv / sw, 0.0, 0.15);
        }
}

// The scene key: "convention" sets it, the default is envtrace's, anything else is an error
// naming the file and key path.
TEST(LatLongConvention, SceneKey) {
    const std::string dir = ett::scratch_dir("latlong-convention-key");
    et::write_image(dir + "/map.exr", 8, 4, 3, std::vector<float>(8 * 4 * 3, 1.0f));
    auto load = [&](const std::string& text) {
        return et::load_scene_environment(nlohmann::json::parse(text), dir, dir + "/s.json", {});
    };
    EXPECT_EQ(load(R"({"map": "map.exr"})").convention, LatLongConvention::envtrace);
    EXPECT_EQ(load(R"({"map": "map.exr", "convention": "mitsuba"})").convention,
              LatLongConvention::mitsuba);
    const et::EnvMap b = load(R"({"map": "map.exr", "convention": "blender", "rotation": 10})");
    EXPECT_EQ(b.convention, LatLongConvention::blender);
    EXPECT_EQ(b.rotation_degrees, 10.0f);
    // Convention and rotation add: blender + 10 degrees is envtrace + 100.
    et::EnvMap e = b;
    e.convention = LatLongConvention::envtrace;
    e.rotation_degrees = 100.0f;
    EXPECT_NEAR(b.desc().rot_cos, e.desc().rot_cos, 1e-7f);
    EXPECT_NEAR(b.desc().rot_sin, e.desc().rot_sin, 1e-7f);
    for (const char* bad : {R"("luxcore")", R"(5)", R"("")", R"(["mitsuba"])"}) {
        SCOPED_TRACE(bad);
        try {
            load(std::string(R"({"map": "map.exr", "convention": )") + bad + "}");
            ADD_FAILURE() << "accepted";
        } catch (const et::Error& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find("s.json: environment.convention"), std::string::npos) << m;
        }
    }
    try {
        load(R"({"map": "map.exr", "convention": "luxcore"})");
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("\"mitsuba\""), std::string::npos) << m;
        EXPECT_NE(m.find("luxcore"), std::string::npos) << m;
    }
}

// End to end: a scene file naming the convention, with one bright texel and no geometry, seen by
// a camera aimed where the other renderer puts the texel: the spot is at the image centre on both
// back ends; aimed where envtrace's own convention would put it, the image is black.
TEST(LatLongConvention, RenderShowsTheTexelWhereTheOtherRendererDoes) {
    const int w = 64, h = 32, film = 24;
    const std::string dir = ett::scratch_dir("latlong-convention-render");
    struct Case {
        LatLongConvention c;
        Texel t;
        double rotation; // envtrace's; the expected direction turns with it
    };
    int n = 0;
    for (const Case& k : {Case{LatLongConvention::mitsuba, {5, 9}, 0.0},
                          Case{LatLongConvention::blender, {40, 20}, 0.0},
                          Case{LatLongConvention::mitsuba, {21, 12}, -77.0},
                          Case{LatLongConvention::blender, {50, 14}, 35.0}}) {
        SCOPED_TRACE(std::string(et::name_of(k.c)) + " texel " + std::to_string(k.t.col) + "," +
                     std::to_string(k.t.row));
        std::vector<float> px(size_t(w) * h * 3, 0.0f);
        for (int ch = 0; ch < 3; ++ch)
            px[3 * (size_t(k.t.row) * w + k.t.col) + ch] = 100.0f;
        // A new name each time: a file read as an input may not be written again in this process.
        const std::string map = "map" + std::to_string(n++) + ".exr";
        et::write_image(dir + "/" + map, w, h, 3, px);
        const UV centre = {(k.t.col + 0.5) / w, (k.t.row + 0.5) / h};
        // envtrace's rotation r is a right-handed turn by -r about +Y.
        const D3 want = rotate_y(dir_of(k.c, centre), -k.rotation);
        const D3 wrong = rotate_y(envtrace_dir(centre), -k.rotation);
        for (const bool right : {true, false}) {
            const D3 aim = right ? want : wrong;
            std::ofstream(dir + "/s.json")
                << R"({"camera": {"eye": [0, 0, 0], "target": [)" << aim.x << ", " << aim.y << ", "
                << aim.z << R"(], "up": [0, 1, 0], "fov": 30},
  "film": {"width": )"
                << film << R"(, "height": )" << film << R"(},
  "environment": {"map": ")"
                << map << R"(", "convention": ")" << et::name_of(k.c) << R"(", "rotation": )"
                << k.rotation << R"(,
                  "blur": 0},
  "shapes": [], "render": {"max_depth": 1}})";
            const et::Scene scene = et::load_scene(dir + "/s.json");
            for (const char* backend : {"cpu", "opencl"}) {
                SCOPED_TRACE(backend);
                const ett::RenderResult r = ett::render(scene, backend, 4, false);
                double sum = 0, cx = 0, cy = 0;
                for (int y = 0; y < film; ++y)
                    for (int x = 0; x < film; ++x) {
                        const double v = r.mean[3 * (size_t(y) * film + x)];
                        sum += v, cx += v * (x + 0.5), cy += v * (y + 0.5);
                    }
                if (!right) {
                    EXPECT_EQ(sum, 0.0);
                    continue;
                }
                ASSERT_GT(sum, 0.0);
                // Pixels are 1.25 degrees, the texel 5.6: the spot's centroid within a pixel of
                // the centre, and the centre pixels near the texel's value.
                EXPECT_NEAR(cx / sum, film / 2.0, 1.0);
                EXPECT_NEAR(cy / sum, film / 2.0, 1.0);
                const size_t mid = 3 * (size_t(film / 2) * film + film / 2);
                EXPECT_GT(r.mean[mid], 50.0f);
            }
        }
    }
}

} // namespace
