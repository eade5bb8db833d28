// Image textures on materials: bilinear lookup with repeat (wrap) addressing in one flat float
// buffer, texture coordinates interpolated at a hit, and a material's textured parameters.
// Plain buffers rather than OpenCL image objects, so that it stays OpenCL 1.2 with no optional
// image support and both back ends run the same arithmetic (bit-identical lookups).
//
// Texture k is two float4 in tex_info: (first texel's offset in tex_texels, width, height,
// channels), all as int bits, and (u scale, v scale, u offset, v offset) applied to the
// coordinates before wrapping. Texels are row-major from the top row, `channels` floats each
// (1: grey, replicated to RGB; 3: RGB). Texture coordinates follow OBJ: v = 0 is the image's
// bottom row. material_tex holds four ints per material: its albedo, specular and roughness
// textures (-1: none) and one unused slot.
#ifndef ETK_TEXTURE_LOOKUP_H
#define ETK_TEXTURE_LOOKUP_H
#include "bsdf.h"
#include "compat.h"
#include "path_state.h"

#define ETK_TEX_ALBEDO 0
#define ETK_TEX_SPECULAR 1
#define ETK_TEX_ROUGHNESS 2
#define ETK_TEX_SLOTS 4 // ints per material in material_tex

ETK_BEGIN

// x mod 1 in [0, 1); a non-finite or huge coordinate (whose fraction float cannot hold) maps to 0
// rather than to an index outside the texture.
ETK_FN float etk_tex_fract(float x) {
    float f = x - floor(x);
    return f >= 0.0f && f < 1.0f ? f : 0.0f;
}

// One texel as RGB (a grey texel replicated).
ETK_FN float3 etk_tex_texel(ETK_GLOBAL const float* texels, int offset, int width, int channels,
                            int x, int y) {
    ETK_GLOBAL const float* t = texels + offset + (y * width + x) * channels;
    return channels >= 3 ? make_float3(t[0], t[1], t[2]) : make_float3(t[0], t[0], t[0]);
}

// The texture's value at (u, v): bilinear between the four nearest texel centres, the texture
// repeated in both directions (so the texels of the left edge blend with the right edge's).
ETK_FN float3 etk_texture(ETK_GLOBAL const float4* info, ETK_GLOBAL const float* texels, int tex,
                          float2 uv) {
    float4 h = info[2 * tex], s = info[2 * tex + 1];
    int offset = (int)as_uint(h.x), w = (int)as_uint(h.y), ht = (int)as_uint(h.z);
    int ch = (int)as_uint(h.w);
    float u = etk_tex_fract(uv.x * s.x + s.z), v = etk_tex_fract(uv.y * s.y + s.w);
    // Continuous texel coordinates, texel centres at integers; row 0 is the top (v = 1).
    float x = u * (float)w - 0.5f, y = (1.0f - v) * (float)ht - 0.5f;
    float fx = floor(x), fy = floor(y);
    float ax = x - fx, ay = y - fy;
    // In [-1, size - 1]; min() guards a width so large that size - 0.5 rounds up to size.
    int x0 = min((int)fx, w - 1), y0 = min((int)fy, ht - 1);
    int x1 = x0 + 1 >= w ? 0 : x0 + 1, y1 = y0 + 1 >= ht ? 0 : y0 + 1;
    x0 = x0 < 0 ? w - 1 : x0;
    y0 = y0 < 0 ? ht - 1 : y0;
    float3 t00 = etk_tex_texel(texels, offset, w, ch, x0, y0);
    float3 t10 = etk_tex_texel(texels, offset, w, ch, x1, y0);
    float3 t01 = etk_tex_texel(texels, offset, w, ch, x0, y1);
    float3 t11 = etk_tex_texel(texels, offset, w, ch, x1, y1);
    return (t00 * (1.0f - ax) + t10 * ax) * (1.0f - ay) + (t01 * (1.0f - ax) + t11 * ax) * ay;
}

// Texture coordinates at barycentrics (b1, b2) of triangle prim: six floats per triangle in
// tri_uv, (u, v) of its three corners.
ETK_FN float2 etk_hit_uv(ETK_GLOBAL const float* tri_uv, int prim, float b1, float b2) {
    ETK_GLOBAL const float* t = tri_uv + 6 * prim;
    float b0 = 1.0f - b1 - b2;
    return make_float2(t[0] * b0 + t[2] * b1 + t[4] * b2, t[1] * b0 + t[3] * b1 + t[5] * b2);
}

// Material `mat` at barycentrics (b1, b2) of triangle prim: its textures replace the constant
// albedo, specular and roughness they stand for. Untextured materials cost one read.
ETK_FN EtkMaterial etk_material_textured(EtkScene S, EtkMaterial m, int mat, int prim, float b1,
                                         float b2) {
    ETK_GLOBAL const int* slots = S.material_tex + ETK_TEX_SLOTS * mat;
    int ta = slots[ETK_TEX_ALBEDO], ts = slots[ETK_TEX_SPECULAR], tr = slots[ETK_TEX_ROUGHNESS];
    if (ta < 0 && ts < 0 && tr < 0)
        return m;
    float2 uv = etk_hit_uv(S.tri_uv, prim, b1, b2);
    if (ta >= 0)
        m.albedo = etk_texture(S.tex_info, S.tex_texels, ta, uv);
    if (ts >= 0)
        m.specular = etk_texture(S.tex_info, S.tex_texels, ts, uv);
    if (tr >= 0)
        m.alpha = fmax(etk_texture(S.tex_info, S.tex_texels, tr, uv).x, 1e-3f);
    return m;
}

ETK_END

#endif
