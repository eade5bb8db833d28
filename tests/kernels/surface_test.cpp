// Where secondary rays start (kernels/surface.h, etk_surface_at): off the surface by a distance
// relative to the hit triangle's largest vertex coordinate, from a hit point rebuilt from the
// vertices, with no absolute floor, so that a scene renders the same image at any unit, wherever
// it sits in space and however far the camera is. A sphere
// resting on a ground square under a map with a sun (contact shadows, where an offset too large
// lets light leak under the sphere, and grazing ground, where one too small shadows the surface
// by itself) is rendered at unit scale and then scaled by 1e-4 and 1e4 and moved 1000 scene
// sizes away, and scaled by 1e10 (where a float cross product's squared length overflows: the
// loaders' and preparation's face normals are computed in double, load/scene.h). Same seed, same
// samples: the images differ only by float rounding, so the bounds are far below the estimator's
// noise. With the offset of before (2e-4 of the coordinates, and of 1 below coordinates of 1) the
// 1e-4 scene rendered 4.4% brighter, the moved one 2.7%.
#include "kernels/bvh.h"
#include "kernels/surface.h"
#include "render_util.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

et::Scene sphere_on_ground() {
    et::RgbImage map = ett::constant_image(64, 32, 0.5f);
    for (int c = 0; c < 3; ++c)
        map.at(40, 8)[c] = 2000.0f; // a sun 45 degrees up: a contact shadow beside the sphere
    et::Scene s = ett::base_scene(48, 32, et::make_envmap("sun", std::move(map), {}));
    s.camera.eye = {0.0f, 1.2f, 3.5f};
    s.camera.target = {0.0f, 0.35f, 0.0f};
    s.camera.fov_deg = 40.0f;
    s.materials.push_back(ett::diffuse(0.6f));
    s.materials.push_back(ett::diffuse(0.8f));
    ett::add_square(s.triangles, glm::vec3(0.0f), glm::vec3(0, 1, 0), 3.0f, 0);
    ett::add_sphere(s.triangles, glm::vec3(0.0f, 0.5f, 0.0f), 0.5f, 32, true, 1);
    s.settings.max_depth = 3;
    s.settings.sampler = et::SamplerKind::sobol;
    return s;
}

// The scene with every point p moved to k p + t (camera included).
et::Scene transformed(et::Scene s, float k, glm::vec3 t) {
    for (glm::vec3& p : s.triangles.positions)
        p = k * p + t;
    s.camera.eye = k * s.camera.eye + t;
    s.camera.target = k * s.camera.target + t;
    return s;
}

struct Difference {
    double mean_ratio = 0.0; // mean of b / mean of a
    double rms = 0.0;        // RMS of the pixel differences, relative to a's mean
};

Difference difference(const std::vector<float>& a, const std::vector<float>& b) {
    Difference d;
    double sq = 0.0;
    for (size_t i = 0; i < a.size(); ++i)
        sq += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    const double ma = ett::image_mean(a);
    d.mean_ratio = ett::image_mean(b) / ma;
    d.rms = std::sqrt(sq / a.size()) / ma;
    return d;
}

class SurfaceOffset : public ::testing::TestWithParam<std::string> {};

TEST_P(SurfaceOffset, ImageIndependentOfUnitAndPlace) {
    const int spp = 16;
    const et::Scene unit = sphere_on_ground();
    const ett::RenderResult ref = ett::render(unit, GetParam(), spp, false);
    ASSERT_GT(ett::image_mean(ref.mean), 0.0);
    // Bounds: a scaled scene renders the same image up to rounding (measured: mean ratio 1 and
    // rms below 1e-4 of the mean; the old absolute floor: 1.044 and 0.31 at 1e-4). A scene 1000
    // sizes from the origin keeps only ~1e-4 of relative precision in its vertices and hit points
    // (its offsets are ~170 ulps of 3000): measured 1.0017 and 0.046 (the old offset, 2e-4 of the
    // coordinates: 1.027 and 0.27).
    struct Case {
        const char* name;
        float k;
        glm::vec3 t;
        double mean_tol, rms_max;
    };
    for (const Case& c :
         {Case{"scaled by 1e-4", 1e-4f, glm::vec3(0.0f), 1e-3, 0.01},
          Case{"scaled by 1e4", 1e4f, glm::vec3(0.0f), 1e-3, 0.01},
          Case{"scaled by 1e10", 1e10f, glm::vec3(0.0f), 1e-3, 0.01},
          Case{"moved 1000 sizes away", 1.0f, glm::vec3(3000.0f, 0.0f, -2000.0f), 5e-3, 0.1}}) {
        SCOPED_TRACE(c.name);
        const ett::RenderResult r =
            ett::render(transformed(unit, c.k, c.t), GetParam(), spp, false);
        const Difference d = difference(ref.mean, r.mean);
        EXPECT_NEAR(d.mean_ratio, 1.0, c.mean_tol);
        EXPECT_LT(d.rms, c.rms_max);
    }
}

// A closed box 2 wide, its inside seen from inside and its outside lit by a sun, moved far from
// the origin by exact amounts (its coordinates stay representable). Before preparation moved such
// geometry back next to the origin (prepare/device_scene.cpp, recentre), the inside leaked light
// along its edges from 1e3 away (hit points rounded to ulps of the coordinates landed past the
// neighbouring face) and was lit all over from 2.5e5 (offsets larger than the box); now the
// images are the same bits wherever the box is.
TEST_P(SurfaceOffset, FarFromTheOriginAsAtIt) {
    et::RgbImage map = ett::constant_image(64, 32, 0.5f);
    for (int c = 0; c < 3; ++c)
        map.at(40, 8)[c] = 2000.0f;
    et::Scene box = ett::base_scene(24, 16, et::make_envmap("sun", std::move(map), {}));
    box.materials.push_back(ett::diffuse(0.8f));
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.0f, 1.0f}) {
            glm::vec3 n(0.0f);
            n[axis] = side;
            ett::add_square(box.triangles, n, n, 1.0f, 0);
        }
    box.settings.max_depth = 2;
    for (const bool inside : {true, false}) {
        SCOPED_TRACE(inside ? "inside" : "outside");
        box.camera.eye = inside ? glm::vec3(0.5f, 0.25f, 0.25f) : glm::vec3(3.0f, 2.5f, 4.0f);
        box.camera.target = inside ? glm::vec3(-1.0f, -0.5f, -0.75f) : glm::vec3(0.0f);
        box.camera.fov_deg = inside ? 90.0f : 40.0f;
        const ett::RenderResult at_origin = ett::render(box, GetParam(), 8, false);
        if (inside)
            EXPECT_EQ(ett::image_mean(at_origin.mean), 0.0);
        else
            ASSERT_GT(ett::image_mean(at_origin.mean), 0.0);
        for (const float far : {1024.0f, 131072.0f, 1048576.0f}) {
            SCOPED_TRACE("moved by " + std::to_string(far));
            const ett::RenderResult r = ett::render(
                transformed(box, 1.0f, glm::vec3(far, -far, far)), GetParam(), 8, false);
            EXPECT_TRUE(r.mean == at_origin.mean) << "image mean " << ett::image_mean(r.mean)
                                                  << " against " << ett::image_mean(at_origin.mean);
        }
    }
}

// A sphere on a ground quad seen from above, the ground 6 units wide and then 2e6 and 2e9 (an
// "infinite" ground, as scenes write it), under a map black below the horizon: nothing beyond 3
// units is seen or lights anything, so the images must agree. The 2e6 ground placed its hits to
// ulps of 1e6 and started shadow rays 5 units above it, above the sphere, and rendered 10%
// brighter without the sphere's shadow; the 2e9 one lost most of its hits to the triangle test's
// distance estimate (etk_packet_hit's terr) and showed the map through it.
TEST_P(SurfaceOffset, LargeGroundSeenFromNear) {
    et::RgbImage map = ett::constant_image(64, 32, 0.5f);
    for (int y = 16; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int c = 0; c < 3; ++c)
                map.at(x, y)[c] = 0.0f;
    for (int c = 0; c < 3; ++c)
        map.at(40, 8)[c] = 2000.0f;
    auto scene = [&](float half) {
        et::Scene s = ett::base_scene(48, 32, et::make_envmap("sun", map, {}));
        s.camera.eye = {0.0f, 3.0f, 1.5f};
        s.camera.target = {0.0f, 0.0f, 0.0f};
        s.camera.fov_deg = 40.0f;
        s.materials.push_back(ett::diffuse(0.6f));
        s.materials.push_back(ett::diffuse(0.8f));
        ett::add_square(s.triangles, glm::vec3(0.0f), glm::vec3(0, 1, 0), half, 0);
        ett::add_sphere(s.triangles, glm::vec3(0.0f, 0.5f, 0.0f), 0.5f, 32, true, 1);
        s.settings.max_depth = 1;
        s.settings.sampler = et::SamplerKind::sobol;
        // Not a learning strategy: its cells scale with the scene, so the 2e9 ground would
        // change its tables (and the noise of 16 spp) rather than the offsets tested here.
        s.settings.strategy = et::Strategy::compensated;
        return s;
    };
    const ett::RenderResult ref = ett::render(scene(3.0f), GetParam(), 16, false);
    for (const float half : {1e6f, 1e9f}) {
        SCOPED_TRACE("ground half-size " + std::to_string(half));
        const Difference d =
            difference(ref.mean, ett::render(scene(half), GetParam(), 16, false).mean);
        EXPECT_NEAR(d.mean_ratio, 1.0, 2e-3);
        EXPECT_LT(d.rms, 0.02);
    }
}

INSTANTIATE_TEST_SUITE_P(Backends, SurfaceOffset, ::testing::Values("cpu", "opencl"));

// The hit point is rebuilt from the triangle's vertices (etk_hit_point), so the secondary ray's
// origin lies off the triangle's plane by ray_epsilon x its vertices' magnitude, on the side the
// ray came from, however far the ray started: rays from 10 to 1e6 units away at a triangle of
// unit size. From o + d t the hit point is off the plane by ulps of the origin's distance (1e6:
// ~0.06 units, against an offset of 7e-6), which no offset relative to the triangle covers.
TEST(SurfaceOffset, OriginOffTheTriangleWhateverTheRayStart) {
    et::Scene s = sphere_on_ground();
    s.triangles = et::TriangleSoup{};
    // Straddling the origin on every axis, so that preparation keeps its coordinates (recentre).
    const glm::vec3 tri[3] = {{-0.3f, -0.05f, -0.4f}, {0.7f, 0.0f, -0.3f}, {0.1f, 0.05f, 0.6f}};
    et::add_triangle(s.triangles, tri, nullptr, 0);
    et::RenderSettings st = s.settings;
    st.backend = et::Backend::cpu;
    const et::DeviceScene ds = et::prepare_device_scene(s, st);
    const glm::vec3 n = et::unit_face_normal(tri);
    const glm::vec3 target(0.15f, 0.0f, 0.0f);           // inside the triangle
    const float expected = ds.params.ray_epsilon * 0.7f; // the largest vertex coordinate
    for (double dist : {10.0, 1e3, 1e5, 1e6}) {
        for (const glm::vec3 from : {glm::vec3(0.3f, 1.0f, 0.2f), glm::vec3(-0.8f, -0.2f, 0.5f)}) {
            SCOPED_TRACE("distance " + std::to_string(dist));
            const glm::vec3 dir = glm::normalize(from);
            const glm::vec3 o = target + float(dist) * dir;
            const etk::float3 eo = etk::make_float3(o.x, o.y, o.z);
            const etk::float3 ed = etk::make_float3(-dir.x, -dir.y, -dir.z);
            etk::EtkHit h;
            const etk::EtkScene S = ds.view();
            ASSERT_TRUE(etk::etk_bvh_traverse(S.nodes, S.packets, eo, ed, 3e38f, 0, &h));
            const etk::EtkSurface surf = etk::etk_surface_at(S, ds.params, eo, ed, h);
            // Signed distance of the origin from the plane, on the ray's side.
            const glm::vec3 org(surf.origin.x, surf.origin.y, surf.origin.z);
            const float side = glm::dot(dir, n) > 0.0f ? 1.0f : -1.0f;
            const float off = side * glm::dot(org - tri[0], n);
            EXPECT_GT(off, 0.5f * expected);
            EXPECT_LT(off, 2.0f * expected);
        }
    }
}

} // namespace
