// BVH traversal (kernels/bvh.h) against brute force: closest hit and any hit, on the host and in
// an OpenCL kernel (tests/kernels/cl/bvh_test.cl), for random triangle soups, soups of awkward
// triangles (tiny, huge, slivers, axis-aligned flat, coplanar grids with shared edges, duplicates)
// and the Stanford bunny.
//
// Brute force runs etk_triangle_hit over every triangle, so on the host the closest distance must
// be bit-identical; the triangle may differ only at a tie (two triangles at the same t within
// 1e-5 relative: shared edges, duplicates). On the device the arithmetic may round differently
// (contraction into FMA, other rounding of the built-ins), so t is compared within 1e-5 relative
// and a ray whose hit/miss verdict flips is accepted only if it passes within float rounding of a
// triangle's edge (either verdict is correct there). Closed meshes: a ray from inside hits them
// whichever edge or vertex it is aimed at (the test is watertight).
#include "prepare/bvh_build.h"
#include "kernels/bvh.h"
#include "bvh_trace.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <glm/gtc/random.hpp>

#include <cmath>
#include <functional>
#include <cstring>
#include <random>

namespace {

using etk::float4;

struct Ray {
    glm::vec3 o, d;
    float tmax;
};

struct Prepared {
    et::Bvh bvh;
    et::TriangleSoup soup;
    std::vector<float4> tris, packets;
};

Prepared prepare(const et::TriangleSoup& soup, int max_leaf = 4) {
    Prepared p;
    p.soup = soup;
    p.bvh = et::build_bvh(soup, max_leaf);
    p.tris = et::flatten_triangles(soup, p.bvh.order);
    p.packets = et::flatten_packets(soup, p.bvh);
    return p;
}

etk::float3 f3(glm::vec3 v) {
    return etk::make_float3(v.x, v.y, v.z);
}

// The kernels' triangle test (etk_packet_hit) on triangle `prim` alone, in lane `lane` of a
// packet whose other lanes are unused; returns whether it hit (updating h).
int triangle_hit(const Prepared& p, int prim, const Ray& r, etk::EtkHit* h, int lane = 0) {
    int lanes[4] = {-1, -1, -1, -1};
    lanes[lane] = prim;
    std::vector<float4> pk;
    pk.reserve(ETK_BVH_PACKET); // one allocation: brute force makes millions (slow under ASan)
    et::append_packet(p.soup, p.bvh.order, lanes, pk);
    return etk::etk_packet_hit(pk.data(), etk::etk_sheared_ray(f3(r.o), f3(r.d)), 1, h);
}

// Every triangle in turn, as the kernels' test sees it.
etk::EtkHit brute_force(const Prepared& p, const Ray& r, bool any) {
    etk::EtkHit h;
    h.t = r.tmax;
    h.prim = -1;
    h.b1 = h.b2 = 0.0f;
    for (int i = 0; i < static_cast<int>(p.tris.size() / 3); ++i)
        if (triangle_hit(p, i, r, &h, i % 4) && any)
            break;
    return h;
}

// Distance to one triangle (infinity when missed).
float single_t(const Prepared& p, int prim, const Ray& r) {
    etk::EtkHit h;
    h.t = 3e38f;
    h.prim = -1;
    return triangle_hit(p, prim, r, &h) ? h.t : INFINITY;
}

bool same_t(float a, float b) {
    return std::fabs(a - b) <= 1e-5f * std::max(std::fabs(a), std::fabs(b));
}

// Does the ray pass within a relative 1e-5 of an edge of some triangle (barycentrics of the
// supporting plane's crossing, in double)?
bool grazes_an_edge(const Prepared& p, const Ray& r) {
    for (size_t i = 0; i < p.tris.size() / 3; ++i) {
        const float4 a = p.tris[3 * i], b = p.tris[3 * i + 1], c = p.tris[3 * i + 2];
        const glm::dvec3 v0(a.x, a.y, a.z), e1(b.x, b.y, b.z), e2(c.x, c.y, c.z);
        const glm::dvec3 o(r.o), d(r.d);
        const glm::dvec3 pv = glm::cross(d, e2);
        const double det = glm::dot(e1, pv);
        if (det == 0.0)
            continue;
        const glm::dvec3 s = o - v0, q = glm::cross(s, e1);
        const double b1 = glm::dot(s, pv) / det, b2 = glm::dot(d, q) / det,
                     t = glm::dot(e2, q) / det;
        const double eps = 1e-5;
        if (t > -eps * std::fabs(t) && b1 > -eps && b2 > -eps && b1 + b2 < 1 + eps &&
            (std::fabs(b1) < eps || std::fabs(b2) < eps || std::fabs(b1 + b2 - 1) < eps))
            return true;
    }
    return false;
}

struct Outcome {
    int rays = 0, hits = 0, ties = 0, edge_flips = 0, unresolved = 0;
};

// A triangle thinner than the rounding of the ray's own coordinates (relative 1e-5 of |origin| +
// t, ~100 float ulps) is hit or missed by rounding: the triangle test computes vertex - origin and
// the slab test origin - box with errors larger than the triangle, so either verdict is right.
bool below_resolution(const Prepared& p, int prim, const Ray& r, float t) {
    if (prim < 0)
        return false;
    const float4 b = p.tris[3 * prim + 1], c = p.tris[3 * prim + 2];
    // Its smallest extent: the shortest altitude (a sliver is long but thinner than rounding).
    const glm::vec3 e1(b.x, b.y, b.z), e2(c.x, c.y, c.z);
    const float longest = std::max({glm::length(e1), glm::length(e2), glm::length(e2 - e1)});
    const float size = glm::length(glm::cross(e1, e2)) / longest;
    const float scale = std::max({std::fabs(r.o.x), std::fabs(r.o.y), std::fabs(r.o.z)}) + t;
    return size < 1e-5f * scale;
}

// Checks one traversal result against brute force; `exact`: host arithmetic (same code).
void check(const Prepared& p, const Ray& r, bool any, const etk::EtkHit& got, bool exact,
           Outcome& out, int ray_index) {
    ++out.rays;
    const etk::EtkHit ref = brute_force(p, r, false);
    SCOPED_TRACE(::testing::Message()
                 << (any ? "any hit" : "closest hit") << ", ray " << ray_index << " o (" << r.o.x
                 << ", " << r.o.y << ", " << r.o.z << ") d (" << r.d.x << ", " << r.d.y << ", "
                 << r.d.z << ") tmax " << r.tmax << ": got prim " << got.prim << " t " << got.t
                 << ", brute force prim " << ref.prim << " t " << ref.t);
    const bool differs =
        (got.prim >= 0) != (ref.prim >= 0) ||
        (got.prim >= 0 && got.prim != ref.prim && !any && !same_t(single_t(p, got.prim, r), ref.t));
    if (differs &&
        (below_resolution(p, ref.prim, r, ref.t) || below_resolution(p, got.prim, r, got.t))) {
        ++out.unresolved;
        return;
    }
    if ((got.prim >= 0) != (ref.prim >= 0)) {
        if (!exact && grazes_an_edge(p, r)) {
            ++out.edge_flips;
            return;
        }
        ADD_FAILURE() << "hit/miss differs";
        return;
    }
    if (ref.prim < 0)
        return;
    ++out.hits;
    ASSERT_LT(got.prim, static_cast<int>(p.tris.size() / 3));
    // Whatever was returned must be a real intersection within (0, tmax) at the reported t.
    const float t_own = single_t(p, got.prim, r);
    EXPECT_TRUE(exact ? t_own == got.t : same_t(t_own, got.t)) << "own t " << t_own;
    EXPECT_LT(got.t, r.tmax);
    // ... on the triangle's plane, measured on the soup's own vertices (in double), not on the
    // packets the traversal read nor on the edges the flatteners share (a packet holding another
    // triangle, swapped components or a wrong edge puts the point off it). Barycentrics would be
    // ill-conditioned on slivers; the plane is not.
    const glm::vec3* v = &p.soup.positions[3 * static_cast<size_t>(p.bvh.order[got.prim])];
    const glm::dvec3 v0(v[0]);
    const glm::dvec3 n = glm::cross(glm::dvec3(v[1]) - v0, glm::dvec3(v[2]) - v0);
    const glm::dvec3 along = glm::dvec3(r.o) + double(got.t) * glm::dvec3(r.d);
    const double scale = std::max({std::fabs(r.o.x), std::fabs(r.o.y), std::fabs(r.o.z)}) + got.t;
    if (!below_resolution(p, got.prim, r, got.t)) { // else the ray's rounding exceeds it
        EXPECT_LE(std::fabs(glm::dot(along - v0, n)), 1e-4 * scale * glm::length(n))
            << "hit point off its triangle's plane";
    }
    if (any)
        return;
    if (exact)
        EXPECT_EQ(got.t, ref.t);
    else
        EXPECT_TRUE(same_t(got.t, ref.t));
    if (got.prim != ref.prim) {
        EXPECT_TRUE(same_t(t_own, ref.t)) << "a different triangle, not at a tie";
        ++out.ties;
    }
}

glm::vec3 random_dir(std::mt19937& rng) {
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    const float z = 1 - 2 * U(rng), ph = 2 * float(M_PI) * U(rng), s = std::sqrt(1 - z * z);
    return {s * std::cos(ph), s * std::sin(ph), z};
}

// Rays of four kinds: random origin and direction; aimed at a random point of a random triangle
// (a tenth of them exactly at a vertex or on an edge); axis-aligned (zero direction components);
// and for any hit half of them with a finite tmax.
std::vector<Ray> make_rays(const et::TriangleSoup& soup, int n, uint32_t seed,
                           float max_radius = 1e30f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const auto& v : soup.positions)
        lo = glm::min(lo, v), hi = glm::max(hi, v);
    const glm::vec3 c = 0.5f * (lo + hi);
    const float radius = std::min(max_radius, 0.5f * glm::length(hi - lo));
    std::vector<Ray> rays;
    for (int i = 0; i < n; ++i) {
        Ray r;
        r.tmax = 3.0e38f;
        const int kind = i % 4;
        r.o = c + radius * 1.2f * (2.0f * glm::vec3(U(rng), U(rng), U(rng)) - 1.0f);
        if (kind == 0) {
            r.d = random_dir(rng);
        } else if (kind == 1 || kind == 3) {
            const size_t t = std::uniform_int_distribution<size_t>(0, soup.size() - 1)(rng);
            const glm::vec3* v = &soup.positions[3 * t];
            float b1 = U(rng), b2 = U(rng);
            if (b1 + b2 > 1)
                b1 = 1 - b1, b2 = 1 - b2;
            if (i % 40 == 1)
                b1 = 0.0f; // on the edge v0-v2
            if (i % 40 == 5)
                b1 = 1.0f, b2 = 0.0f; // at a vertex
            const glm::vec3 target = v[0] + b1 * (v[1] - v[0]) + b2 * (v[2] - v[0]);
            r.d = glm::normalize(target - r.o);
            if (kind == 3)
                r.tmax = glm::length(target - r.o) * (0.5f + U(rng));
        } else {
            r.d = glm::vec3(0.0f);
            r.d[i % 3] = U(rng) < 0.5f ? -1.0f : 1.0f;
            if (i % 8 == 2) // towards the scene along an axis
                r.d[i % 3] = c[i % 3] > r.o[i % 3] ? 1.0f : -1.0f;
        }
        if (!(glm::length(r.d) > 0.0f) || !std::isfinite(r.d.x))
            r.d = glm::vec3(0, 1, 0);
        rays.push_back(r);
    }
    return rays;
}

void add_random(et::TriangleSoup& soup, std::mt19937& rng, int n, float extent, float lo_size,
                float hi_size) {
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    for (int i = 0; i < n; ++i) {
        const glm::vec3 c = extent * (2.0f * glm::vec3(U(rng), U(rng), U(rng)) - 1.0f);
        const float s = lo_size * std::pow(hi_size / lo_size, U(rng));
        glm::vec3 p[3];
        for (auto& v : p)
            v = c + s * random_dir(rng);
        et::add_triangle(soup, p, nullptr, 0);
    }
}

et::TriangleSoup random_soup(uint32_t seed) {
    std::mt19937 rng(seed);
    et::TriangleSoup soup;
    add_random(soup, rng, 3000, 1.0f, 1e-3f, 0.5f);
    return soup;
}

et::TriangleSoup awkward_soup(uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    et::TriangleSoup soup;
    add_random(soup, rng, 300, 1.0f, 1e-6f, 1e-4f); // tiny
    add_random(soup, rng, 5, 1.0f, 1e3f, 1e4f);     // huge, spanning everything
    add_random(soup, rng, 500, 1.0f, 1e-2f, 0.3f);  // ordinary
    for (int i = 0; i < 300; ++i) {                 // slivers: third vertex just off an edge
        const glm::vec3 a = 2.0f * glm::vec3(U(rng), U(rng), U(rng)) - 1.0f;
        const glm::vec3 b = a + 0.5f * random_dir(rng);
        const glm::vec3 off = 1e-5f * random_dir(rng);
        glm::vec3 p[3] = {a, b, 0.5f * (a + b) + off};
        et::add_triangle(soup, p, nullptr, 0);
    }
    for (int i = 0; i < 200; ++i) { // axis-aligned, flat bounding boxes
        const int axis = i % 3;
        const glm::vec3 c = 2.0f * glm::vec3(U(rng), U(rng), U(rng)) - 1.0f;
        glm::vec3 p[3];
        for (auto& v : p) {
            v = c + 0.2f * (2.0f * glm::vec3(U(rng), U(rng), U(rng)) - 1.0f);
            v[axis] = c[axis];
        }
        et::add_triangle(soup, p, nullptr, 0);
    }
    // A coplanar grid (shared edges and vertices) in y = 0.25, and a copy of part of it (exact
    // duplicates: ties everywhere).
    const int g = 24;
    for (int rep = 0; rep < 2; ++rep)
        for (int i = 0; i < g; ++i)
            for (int j = 0; j < (rep ? g / 3 : g); ++j) {
                auto P = [&](int a, int b) {
                    return glm::vec3(-1.0f + 2.0f * a / g, 0.25f, -1.0f + 2.0f * b / g);
                };
                glm::vec3 t1[3] = {P(i, j), P(i + 1, j), P(i + 1, j + 1)};
                glm::vec3 t2[3] = {P(i, j), P(i + 1, j + 1), P(i, j + 1)};
                et::add_triangle(soup, t1, nullptr, 0);
                et::add_triangle(soup, t2, nullptr, 0);
            }
    return soup;
}

void run_host(const Prepared& p, int n_rays, uint32_t seed, const char* name,
              float max_radius = 1e30f) {
    const et::TriangleSoup& soup = p.soup;
    const std::vector<Ray> rays = make_rays(soup, n_rays, seed, max_radius);
    Outcome closest, any;
    for (size_t i = 0; i < rays.size(); ++i) {
        const Ray& r = rays[i];
        for (int a = 0; a < 2; ++a) {
            etk::EtkHit h;
            etk::etk_bvh_traverse(p.bvh.nodes.data(), p.packets.data(), f3(r.o), f3(r.d), r.tmax, a,
                                  &h);
            check(p, r, a, h, true, a ? any : closest, static_cast<int>(i));
        }
        if (::testing::Test::HasFailure())
            return; // the first ray is enough to debug
    }
    std::printf("%s host: %zu triangles, BVH depth %d; %d rays, %d closest hits (%d ties), %d "
                "any hits; %d + %d verdicts below float resolution\n",
                name, soup.size(), p.bvh.depth, closest.rays, closest.hits, closest.ties, any.hits,
                closest.unresolved, any.unresolved);
    // The watertight test decides at the resolution of the ray's coordinates (it moves the
    // vertices to the ray's origin): a triangle smaller than that -- the awkward soups' 1e-6
    // triangles seen from the middle of the scene, ~1e-5 of the distance -- is hit or missed
    // within rounding, and the boxes may cull what the test alone takes. Still, at least 90% of
    // the rays must be resolved, so the comparison checks something.
    EXPECT_LE(closest.unresolved + any.unresolved, n_rays / 10);
    EXPECT_GT(closest.hits, n_rays / 4); // the rays do exercise the geometry
}

void run_host(const et::TriangleSoup& soup, int n_rays, uint32_t seed, const char* name,
              float max_radius = 1e30f, int max_leaf = 4) {
    run_host(prepare(soup, max_leaf), n_rays, seed, name, max_radius);
}

// The rays traced by tests/kernels/cl/bvh_test.cl on the OpenCL device: (t, prim bits, b1, b2)
// each.
std::vector<float4> trace_on_device(const Prepared& p, const std::vector<Ray>& rays, int any) {
    std::vector<float4> org, dir;
    for (const Ray& r : rays) {
        org.push_back(etk::make_float4(r.o.x, r.o.y, r.o.z, r.tmax));
        dir.push_back(etk::make_float4(r.d.x, r.d.y, r.d.z, 0.0f));
    }
    return ett::trace_bvh_kernel(ett::runtime(), p.bvh.nodes, p.packets, org, dir, any);
}

void run_device(const Prepared& p, int n_rays, uint32_t seed, const char* name,
                float max_radius = 1e30f) {
    const std::vector<Ray> rays = make_rays(p.soup, n_rays, seed, max_radius);
    const int n = static_cast<int>(rays.size());
    Outcome closest, any;
    for (int a = 0; a < 2; ++a) {
        const std::vector<float4> out = trace_on_device(p, rays, a);
        for (int i = 0; i < n; ++i) {
            etk::EtkHit h;
            h.t = out[i].x;
            h.prim = static_cast<int>(etk::as_uint(out[i].y));
            h.b1 = out[i].z;
            h.b2 = out[i].w;
            check(p, rays[i], a, h, false, a ? any : closest, i);
            if (::testing::Test::HasFailure())
                return;
        }
    }
    std::printf("%s device: %d rays, %d closest hits (%d ties, %d edge flips), %d any hits (%d "
                "edge flips); %d + %d verdicts below float resolution\n",
                name, closest.rays, closest.hits, closest.ties, closest.edge_flips, any.hits,
                any.edge_flips, closest.unresolved, any.unresolved);
    EXPECT_LE(closest.unresolved + any.unresolved, n_rays / 10); // as in run_host
    // An edge flip needs a ray within float rounding of an edge: rare even among rays aimed at
    // edges on purpose (1 in 40 of a quarter of the rays).
    EXPECT_LE(closest.edge_flips + any.edge_flips, n / 200);
}

void run_device(const et::TriangleSoup& soup, int n_rays, uint32_t seed, const char* name,
                float max_radius = 1e30f) {
    run_device(prepare(soup), n_rays, seed, name, max_radius);
}

TEST(Bvh, RandomSoupsHost) {
    for (uint32_t seed : {1u, 2u, 3u})
        run_host(random_soup(seed), 4000, seed, "random soup");
}

TEST(Bvh, LeavesOfSeveralPacketsHost) {
    // Leaves of up to 16 triangles: a leaf's packets are consecutive, its last one part-filled.
    const et::TriangleSoup soup = random_soup(4);
    const Prepared p = prepare(soup, 16);
    int largest = 0;
    for (const auto& leaf : p.bvh.leaves)
        largest = std::max(largest, leaf.second);
    EXPECT_GT(largest, 4);
    run_host(soup, 4000, 4, "random soup, leaves <= 16", 1e30f, 16);
}

TEST(Bvh, AwkwardSoupHost) {
    // Rays from the middle of the scene, where even the 1e-6 triangles are resolved...
    for (uint32_t seed : {11u, 12u})
        run_host(awkward_soup(seed), 4000, seed, "awkward soup (near)", 3.0f);
    // ... and from anywhere in the bounds of the 1e4 triangles, thousands of units away.
    run_host(awkward_soup(13), 4000, 13, "awkward soup (far)");
}

TEST(Bvh, RandomAndAwkwardSoupsDevice) {
    run_device(random_soup(1), 4000, 1, "random soup");
    run_device(awkward_soup(11), 4000, 11, "awkward soup (near)", 3.0f);
    run_device(awkward_soup(13), 4000, 13, "awkward soup (far)");
}

et::TriangleSoup bunny() {
    const std::string path = ett::data_file("meshes/stanford-bunny.obj");
    et::TriangleSoup soup;
    if (path.empty())
        return soup;
    std::vector<et::Material> mats;
    ett::WarningCapture quiet;
    et::load_obj(path, glm::mat4(1.0f), 0, mats, soup);
    return soup;
}

TEST(Bvh, StanfordBunnyHost) {
    const et::TriangleSoup soup = bunny();
    if (soup.size() == 0)
        GTEST_SKIP() << "meshes/stanford-bunny.obj not found: set ENVTRACE_DATA to ../shared/data";
    EXPECT_GT(soup.size(), 60000u);
    run_host(soup, 1200, 21, "stanford-bunny");
}

TEST(Bvh, StanfordBunnyDevice) {
    const et::TriangleSoup soup = bunny();
    if (soup.size() == 0)
        GTEST_SKIP() << "meshes/stanford-bunny.obj not found: set ENVTRACE_DATA to ../shared/data";
    run_device(soup, 1200, 22, "stanford-bunny");
}

// A closed latitude-longitude sphere whose triangles share their vertices' bits (as the scene's
// "sphere" shape makes them), slivers at the poles included.
et::TriangleSoup closed_sphere(glm::dvec3 c, double r, int segments) {
    const int rings = segments / 2;
    auto point = [&](int i, int j) {
        const double th = M_PI * i / rings, ph = 2.0 * M_PI * (j % segments) / segments;
        const glm::dvec3 u = i == 0 || i == rings
                                 ? glm::dvec3(0.0, i == 0 ? 1.0 : -1.0, 0.0)
                                 : glm::dvec3(std::sin(th) * std::cos(ph), std::cos(th),
                                              std::sin(th) * std::sin(ph));
        return glm::vec3(c + r * u);
    };
    et::TriangleSoup soup;
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const glm::vec3 a[3] = {point(i, j), point(i, j + 1), point(i + 1, j + 1)},
                            b[3] = {point(i, j), point(i + 1, j + 1), point(i + 1, j)};
            if (i > 0)
                et::add_triangle(soup, a, nullptr, 0);
            if (i < rings - 1)
                et::add_triangle(soup, b, nullptr, 0);
        }
    return soup;
}

// Watertightness: a ray from inside a closed mesh hits it, whichever edge or vertex it passes
// through. Rays are aimed at points on the triangles' edges and at their vertices, where
// Moller-Trumbore's rounding let about one in ten through (light leaked into closed spheres and
// rooms); the closest hit must exist, on the host and on the device.
TEST(Bvh, ClosedMeshesHaveNoCracks) {
    struct Case {
        glm::dvec3 c;
        double r;
        int segments;
    };
    // The last two far from the origin against their size (a coarse sphere, nearly a box): the
    // test itself has no cracks there (the light that leaked into such a box came from where
    // secondary rays start; prepare/device_scene.cpp's recentre).
    for (const Case& k : {Case{{0, 0, 0}, 1.0, 96}, Case{{3.7, -1.1, 0.3}, 1e-3, 256},
                          Case{{1e3, 20, -7}, 50.0, 512}, Case{{0, 0, 0}, 1e6, 64},
                          Case{{1e4, 1e4, 1e4}, 1.0, 8}, Case{{1e5, -1e5, 1e5}, 1.0, 8}}) {
        const et::TriangleSoup soup = closed_sphere(k.c, k.r, k.segments);
        const Prepared p = prepare(soup);
        std::mt19937 rng(static_cast<uint32_t>(k.segments));
        std::uniform_real_distribution<float> u01(0.0f, 1.0f);
        std::uniform_int_distribution<int> tri(0, static_cast<int>(soup.size()) - 1);
        std::vector<Ray> rays;
        int misses = 0;
        for (int n = 0; n < 40000; ++n) {
            // From the centre, or from a random point inside, towards a point of an edge (or a
            // vertex, one ray in eight).
            const glm::vec3 o =
                n % 4 == 0 ? glm::vec3(k.c)
                           : glm::vec3(k.c) + float(0.8 * k.r) * u01(rng) * random_dir(rng);
            const int t = tri(rng), e = n % 3;
            const glm::vec3 va = soup.positions[3 * t + e],
                            vb = soup.positions[3 * t + (e + 1) % 3];
            const glm::vec3 target = n % 8 == 1 ? va : va + u01(rng) * (vb - va);
            const glm::vec3 d = target - o;
            if (!(glm::length(d) > 0.0f))
                continue;
            rays.push_back({o, glm::normalize(d), 3e38f});
            etk::EtkHit h;
            if (!etk::etk_bvh_traverse(p.bvh.nodes.data(), p.packets.data(), f3(o),
                                       f3(rays.back().d), 3e38f, 0, &h))
                ++misses;
        }
        EXPECT_EQ(misses, 0) << rays.size() << " rays from inside a sphere of radius " << k.r
                             << ", " << k.segments << " segments, on the host";
        int device_misses = 0;
        for (const float4& h : trace_on_device(p, rays, 0))
            device_misses += static_cast<int>(etk::as_uint(h.y)) < 0;
        EXPECT_EQ(device_misses, 0) << rays.size() << " rays from inside a sphere of radius " << k.r
                                    << ", " << k.segments << " segments, on the device";
    }
}

// A binary tree as deep as the builder makes them (60 levels) whose every level offers the 8-wide
// collapse inner children to take: a spine S_d = (F_d, S_d+1) down to one triangle, where F_d is a
// fan of eight triangles (three binary levels) around the origin, each fan 0.8 the size of the
// one above, so that a fan's box is larger than the rest of the spine's and the collapse takes
// the fans' inner nodes first. Taken greedily, a path would hold 7 pushes per two spine levels,
// past the traversal's stack; the flattener keeps it within, and traversal stays exact.
TEST(Bvh, DeepTreeOfFansKeepsTheStackWithin) {
    et::TriangleSoup soup;
    std::vector<et::BvhTreeNode> tree(1);
    std::vector<int> order;
    auto leaf = [&](const glm::vec3 p[3]) {
        et::add_triangle(soup, p, nullptr, 0);
        et::BvhTreeNode n;
        n.lo = glm::min(p[0], glm::min(p[1], p[2]));
        n.hi = glm::max(p[0], glm::max(p[1], p[2]));
        n.first = static_cast<int>(order.size());
        n.count = 1;
        order.push_back(static_cast<int>(order.size()));
        tree.push_back(n);
        return static_cast<int>(tree.size()) - 1;
    };
    auto inner = [&](int node, int a, int b) {
        tree[static_cast<size_t>(node)].left = a;
        tree[static_cast<size_t>(node)].right = b;
        tree[static_cast<size_t>(node)].lo = glm::min(tree[a].lo, tree[b].lo);
        tree[static_cast<size_t>(node)].hi = glm::max(tree[a].hi, tree[b].hi);
    };
    auto new_node = [&]() {
        tree.emplace_back();
        return static_cast<int>(tree.size()) - 1;
    };
    // Fan of eight triangles at the corners of a cube of half-size r: a complete binary tree.
    std::function<int(float, int, int)> fan = [&](float r, int lo, int count) -> int {
        if (count == 1) {
            const glm::vec3 c(lo & 1 ? r : -r, lo & 2 ? r : -r, lo & 4 ? r : -r);
            const float s = 0.2f * r;
            const glm::vec3 p[3] = {c, c + glm::vec3(s, 0, 0), c + glm::vec3(0, s, s)};
            return leaf(p);
        }
        const int n = new_node();
        const int a = fan(r, lo, count / 2), b = fan(r, lo + count / 2, count / 2);
        inner(n, a, b);
        return n;
    };
    const int spine = 56; // the tree's height: spine + fan levels (3) + 1 <= 60
    std::function<int(int, float)> build = [&](int d, float r) -> int {
        if (d == spine) {
            const glm::vec3 p[3] = {glm::vec3(0), glm::vec3(r, 0, 0), glm::vec3(0, r, 0)};
            return leaf(p);
        }
        const int n = d == 0 ? 0 : new_node();
        const int f = fan(r, 0, 8);
        const int rest = build(d + 1, r * 0.8f);
        inner(n, f, rest);
        return n;
    };
    build(0, 1.0f);
    Prepared p;
    p.soup = soup;
    p.bvh = et::flatten_bvh(tree, order);
    p.tris = et::flatten_triangles(soup, p.bvh.order);
    p.packets = et::flatten_packets(soup, p.bvh);
    EXPECT_EQ(p.bvh.depth, spine + 3);
    EXPECT_LE(p.bvh.stack, ETK_BVH_STACK);
    EXPECT_GT(p.bvh.stack, 64); // the fans do fill the nodes' lanes (taken greedily: 133)
    run_host(p, 4000, 31, "deep tree of fans");
    run_device(p, 4000, 31, "deep tree of fans");
}

TEST(Bvh, EmptySceneMissesEverything) {
    // Regression: the empty BVH used to be an inner node whose inverted box rays still "hit",
    // and traversal looped forever.
    const Prepared p = prepare(et::TriangleSoup{});
    ASSERT_EQ(p.tris.size(), 3u);
    std::mt19937 rng(5);
    for (int i = 0; i < 100; ++i)
        for (int any = 0; any < 2; ++any) {
            glm::vec3 d = i < 3 ? glm::vec3(i == 0, i == 1, i == 2) : random_dir(rng);
            etk::EtkHit h;
            EXPECT_FALSE(etk::etk_bvh_traverse(p.bvh.nodes.data(), p.packets.data(),
                                               etk::make_float3(0, 0, 0), f3(d), 3e38f, any, &h));
            EXPECT_EQ(h.prim, -1);
        }
}

} // namespace

namespace {

// Subtrees are built on several threads where a split has 2^14 triangles on each side: the tree
// must be the serial one, bit for bit (node layout, boxes, triangle order), whatever the count.
TEST(Bvh, SameTreeOnAnyThreadCount) {
    std::mt19937 rng(5);
    et::TriangleSoup big;
    add_random(big, rng, 40000, 1.0f, 1e-3f, 0.2f);
    std::vector<et::TriangleSoup> soups = {std::move(big)};
    if (bunny().size() > 0)
        soups.push_back(bunny());
    for (const et::TriangleSoup& soup : soups) {
        const et::Bvh one = et::build_bvh(soup, 4, 1);
        ASSERT_GT(one.node_count(), 1000);
        for (int threads : {2, 3, 8}) {
            const et::Bvh many = et::build_bvh(soup, 4, threads);
            ASSERT_EQ(one.nodes.size(), many.nodes.size()) << threads;
            EXPECT_EQ(0, std::memcmp(one.nodes.data(), many.nodes.data(),
                                     one.nodes.size() * sizeof(one.nodes[0])))
                << threads;
            EXPECT_EQ(one.order, many.order) << threads;
            EXPECT_EQ(one.sah_cost, many.sah_cost) << threads;
        }
    }
}

} // namespace
