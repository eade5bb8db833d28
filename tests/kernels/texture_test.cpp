// Texture lookup (kernels/texture_lookup.h): bilinear between texel centres with repeat addressing,
// texture coordinates interpolated from barycentrics, textured material parameters; and the
// OpenCL kernels (texture_test.cl) agreeing with the host bit for bit.
#include "kernels/texture_lookup.h"
#include "test_data.h"
#include "test_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace {

using etk::float2;
using etk::float3;
using etk::float4;

// A texture of w x h texels and `ch` channels stored after `pad` guard floats (NaN, so that a
// read outside the texture shows in the result), with a uv transform.
struct Tex {
    std::vector<float4> info;
    std::vector<float> texels;
    int w, h, ch;
    Tex(int w_, int h_, int ch_, uint32_t seed, float su = 1, float sv = 1, float ou = 0,
        float ov = 0, int pad = 16)
        : w(w_), h(h_), ch(ch_) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        texels.assign(pad, std::numeric_limits<float>::quiet_NaN());
        for (int i = 0; i < w * h * ch; ++i)
            texels.push_back(u(rng));
        texels.insert(texels.end(), pad, std::numeric_limits<float>::quiet_NaN());
        info = {etk::make_float4(etk::as_float(uint32_t(pad)), etk::as_float(uint32_t(w)),
                                 etk::as_float(uint32_t(h)), etk::as_float(uint32_t(ch))),
                etk::make_float4(su, sv, ou, ov)};
    }
    float3 texel(int x, int y) const {
        const float* t = &texels[16 + (y * w + x) * ch];
        return ch == 3 ? float3{t[0], t[1], t[2]} : float3{t[0], t[0], t[0]};
    }
    float3 at(float u, float v) const {
        return etk::etk_texture(info.data(), texels.data(), 0, etk::make_float2(u, v));
    }
};

void expect_near3(float3 a, float3 b, float tol, const std::string& what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}
float3 avg(float3 a, float3 b) {
    return (a + b) * 0.5f;
}

// Texel (x, y) has its centre at u = (x + 1/2) / w, v = 1 - (y + 1/2) / h (row 0 at the top):
// there the lookup is the texel itself, exactly (powers of two keep the arithmetic exact).
TEST(Texture, TexelCentresGiveTheTexels) {
    for (int ch : {1, 3}) {
        const Tex t(8, 4, ch, 1);
        for (int y = 0; y < t.h; ++y)
            for (int x = 0; x < t.w; ++x) {
                const float3 got = t.at((x + 0.5f) / t.w, 1.0f - (y + 0.5f) / t.h);
                const float3 want = t.texel(x, y);
                EXPECT_EQ(got.x, want.x) << ch << " channels, texel " << x << "," << y;
                EXPECT_EQ(got.y, want.y);
                EXPECT_EQ(got.z, want.z);
            }
    }
}

// Half way between two centres, the mean of the two; at the texture's edges (u = 0, v = 0)
// the neighbour is across the edge: repeat addressing.
TEST(Texture, EdgesBlendNeighboursAndWrap) {
    const Tex t(8, 4, 3, 2);
    const float vc = 1.0f - 1.5f / t.h; // the centre of row 1
    for (int x = 1; x < t.w; ++x)
        expect_near3(t.at(float(x) / t.w, vc), avg(t.texel(x - 1, 1), t.texel(x, 1)), 1e-6f,
                     "between columns " + std::to_string(x - 1) + " and " + std::to_string(x));
    expect_near3(t.at(0.0f, vc), avg(t.texel(t.w - 1, 1), t.texel(0, 1)), 1e-6f,
                 "u = 0: last and first column");
    const float uc = 2.5f / t.w; // the centre of column 2
    expect_near3(t.at(uc, 0.0f), avg(t.texel(2, t.h - 1), t.texel(2, 0)), 1e-6f,
                 "v = 0: bottom and top row");
    // A corner: the four corner texels.
    const float3 c =
        (t.texel(0, 0) + t.texel(t.w - 1, 0) + t.texel(0, t.h - 1) + t.texel(t.w - 1, t.h - 1)) *
        0.25f;
    expect_near3(t.at(0.0f, 0.0f), c, 1e-6f, "corner");
    // A quarter of the way: bilinear weights 3/4 and 1/4.
    expect_near3(t.at(1.25f / t.w, vc), t.texel(0, 1) * 0.25f + t.texel(1, 1) * 0.75f, 1e-6f,
                 "quarter");
}

TEST(Texture, RepeatsAndTransformsCoordinates) {
    const Tex t(8, 4, 3, 3);
    for (float u : {0.0f, 0.3f, 0.0625f, 0.9f})
        for (float v : {0.0f, 0.2f, 0.5f, 0.99f}) {
            const float3 a = t.at(u, v);
            expect_near3(t.at(u + 3.0f, v - 2.0f), a, 1e-5f, "shifted by whole periods");
            expect_near3(t.at(u - 1.0f, v + 1.0f), a, 1e-5f, "negative coordinates");
        }
    // Scale 2 and offset 0.25: (u, v) reads (2u + 0.25, 2v + 0.25).
    const Tex s(8, 4, 3, 3, 2.0f, 2.0f, 0.25f, 0.25f);
    for (float u : {0.1f, 0.4f, 0.7f})
        for (float v : {0.05f, 0.6f})
            expect_near3(s.at(u, v), t.at(2 * u + 0.25f, 2 * v + 0.25f), 1e-5f, "uv transform");
}

// No coordinate reads outside the texture: the guard floats around it are NaN.
TEST(Texture, HostileCoordinatesStayInside) {
    const float inf = std::numeric_limits<float>::infinity(),
                nan = std::numeric_limits<float>::quiet_NaN();
    for (int w : {1, 2, 5}) {
        const Tex t(w, 3, 3, 4);
        for (float u :
             {nan, inf, -inf, 1e30f, -1e30f, 16777215.0f, -0.0f, 0.99999994f, -1e-30f, 1.0f})
            for (float v : {nan, 0.5f, -1e-30f, 0.99999994f, 1e20f}) {
                const float3 c = t.at(u, v);
                EXPECT_TRUE(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z))
                    << "w " << w << " uv " << u << "," << v;
            }
    }
}

TEST(Texture, HitUvInterpolatesCorners) {
    const float tri[12] = {9, 9, 9, 9, 9, 9, 0.1f, 0.2f, 0.9f, 0.3f, 0.4f, 1.7f}; // triangle 1
    auto uv = [&](float b1, float b2) { return etk::etk_hit_uv(tri, 1, b1, b2); };
    EXPECT_EQ(uv(0, 0).x, 0.1f);
    EXPECT_EQ(uv(0, 0).y, 0.2f);
    EXPECT_EQ(uv(1, 0).x, 0.9f);
    EXPECT_EQ(uv(1, 0).y, 0.3f);
    EXPECT_EQ(uv(0, 1).x, 0.4f);
    EXPECT_EQ(uv(0, 1).y, 1.7f);
    EXPECT_NEAR(uv(1.0f / 3, 1.0f / 3).x, (0.1 + 0.9 + 0.4) / 3, 1e-6);
    EXPECT_NEAR(uv(1.0f / 3, 1.0f / 3).y, (0.2 + 0.3 + 1.7) / 3, 1e-6);
    EXPECT_NEAR(uv(0.25f, 0.5f).x, 0.25 * 0.1 + 0.25 * 0.9 + 0.5 * 0.4, 1e-6);
}

// Textures replace the constants they stand for; an untextured material is left as it is.
TEST(Texture, MaterialParametersComeFromTheirTextures) {
    const Tex colour(8, 4, 3, 5), grey(8, 4, 1, 6);
    // Texture 0: colour, texture 1: grey (data), both in one buffer as the host packs them.
    std::vector<float> texels(colour.texels);
    const uint32_t grey_offset = static_cast<uint32_t>(texels.size() + 16);
    texels.insert(texels.end(), grey.texels.begin(), grey.texels.end());
    std::vector<float4> info = colour.info;
    info.push_back(etk::make_float4(etk::as_float(grey_offset), etk::as_float(8u),
                                    etk::as_float(4u), etk::as_float(1u)));
    info.push_back(etk::make_float4(1, 1, 0, 0));
    const std::vector<int> slots = {-1, -1, -1, -1, 0, 0, 1, -1};
    const std::vector<float> tri_uv = {0.3f, 0.6f, 0.3f, 0.6f, 0.3f, 0.6f};
    etk::EtkScene S{};
    S.material_tex = slots.data();
    S.tri_uv = tri_uv.data();
    S.tex_info = info.data();
    S.tex_texels = texels.data();
    etk::EtkMaterial m{};
    m.albedo = float3{0.1f, 0.2f, 0.3f};
    m.specular = float3{0.4f, 0.5f, 0.6f};
    m.alpha = 0.7f;
    const etk::EtkMaterial same = etk::etk_material_textured(S, m, 0, 0, 0.2f, 0.3f);
    EXPECT_EQ(same.albedo.x, 0.1f);
    EXPECT_EQ(same.specular.z, 0.6f);
    EXPECT_EQ(same.alpha, 0.7f);
    const etk::EtkMaterial t = etk::etk_material_textured(S, m, 1, 0, 0.2f, 0.3f);
    const float3 want = colour.at(0.3f, 0.6f);
    EXPECT_EQ(t.albedo.x, want.x);
    EXPECT_EQ(t.albedo.z, want.z);
    EXPECT_EQ(t.specular.y, want.y);
    EXPECT_EQ(t.alpha, std::max(grey.at(0.3f, 0.6f).x, 1e-3f));
}

// The OpenCL program computes the same bits as the host for every coordinate, wild ones
// included, and for the barycentric interpolation.
TEST(Texture, OpenClMatchesHostBitForBit) {
    et::ClRuntime& rt = ett::runtime();
    cl::Program program = ett::build_test_kernel(rt, "texture_test.cl");
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-3.0f, 3.0f);
    const int n = 4096;
    std::vector<float2> uv(n);
    for (auto& c : uv)
        c = etk::make_float2(u(rng), u(rng));
    uv[0] = etk::make_float2(0.0f, 0.0f);
    uv[1] = etk::make_float2(std::numeric_limits<float>::quiet_NaN(), 1e30f);
    uv[2] = etk::make_float2(-std::numeric_limits<float>::infinity(), 0.5f);
    for (const Tex& t : {Tex(8, 4, 3, 8), Tex(5, 3, 1, 9, 3.0f, -2.0f, 0.1f, 0.7f)}) {
        cl::Buffer info(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                        t.info.size() * sizeof(float4), const_cast<float4*>(t.info.data()));
        cl::Buffer texels(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                          t.texels.size() * sizeof(float), const_cast<float*>(t.texels.data()));
        cl::Buffer in(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(float2),
                      uv.data());
        cl::Buffer out(rt.context(), CL_MEM_WRITE_ONLY, n * sizeof(float4));
        cl::Kernel k(program, "texture_lookup");
        k.setArg(0, info);
        k.setArg(1, texels);
        k.setArg(2, 0);
        k.setArg(3, in);
        k.setArg(4, n);
        k.setArg(5, out);
        rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(n), cl::NDRange(64));
        std::vector<float4> got(n);
        rt.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(float4), got.data());
        for (int i = 0; i < n; ++i) {
            const float3 h = t.at(uv[i].x, uv[i].y);
            ASSERT_EQ(etk::as_uint(got[i].x), etk::as_uint(h.x))
                << "uv " << uv[i].x << "," << uv[i].y;
            ASSERT_EQ(etk::as_uint(got[i].y), etk::as_uint(h.y));
            ASSERT_EQ(etk::as_uint(got[i].z), etk::as_uint(h.z));
        }
    }
    // Barycentric interpolation of triangle 2's corners.
    std::vector<float> tri_uv(18);
    for (auto& v : tri_uv)
        v = u(rng);
    std::vector<float2> bary(n);
    std::uniform_real_distribution<float> b(0.0f, 1.0f);
    for (auto& c : bary) {
        float b1 = b(rng), b2 = b(rng);
        if (b1 + b2 > 1.0f)
            b1 = 1.0f - b1, b2 = 1.0f - b2;
        c = etk::make_float2(b1, b2);
    }
    cl::Buffer tb(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                  tri_uv.size() * sizeof(float), tri_uv.data());
    cl::Buffer bb(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(float2),
                  bary.data());
    cl::Buffer out(rt.context(), CL_MEM_WRITE_ONLY, n * sizeof(float2));
    cl::Kernel k(program, "hit_uv");
    k.setArg(0, tb);
    k.setArg(1, bb);
    k.setArg(2, 2);
    k.setArg(3, n);
    k.setArg(4, out);
    rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(n), cl::NDRange(64));
    std::vector<float2> got(n);
    rt.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(float2), got.data());
    for (int i = 0; i < n; ++i) {
        const float2 h = etk::etk_hit_uv(tri_uv.data(), 2, bary[i].x, bary[i].y);
        ASSERT_EQ(etk::as_uint(got[i].x), etk::as_uint(h.x));
        ASSERT_EQ(etk::as_uint(got[i].y), etk::as_uint(h.y));
    }
}

} // namespace
