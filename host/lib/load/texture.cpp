#include "load/texture.h"

#include "image/image_io.h"
#include "util/checked_size.h"
#include "util/data_path.h"
#include "util/error.h"
#include "util/json_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace et {
namespace {

// Texture values are reflectances and roughnesses: [0, 1], NaN (and -Inf) to 0.
float clamp01(float v) {
    return v > 0.0f ? std::min(v, 1.0f) : 0.0f;
}

std::string key_of(const std::string& path, TextureUse use, glm::vec2 s, glm::vec2 o) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "|%d|%a|%a|%a|%a", use == TextureUse::colour ? 0 : 1, s.x, s.y,
                  o.x, o.y);
    return path + buf;
}

// The budget every texture of a scene shares: one device buffer, indexed with 32-bit ints, no
// bigger than any other buffer built from input.
void check_budget(uint64_t have, uint64_t add, const std::string& what) {
    const uint64_t total = checked_add(have, add, what);
    const uint64_t limit = std::min<uint64_t>(kMaxDeviceIndex, kMaxBufferBytes / sizeof(float));
    if (total > limit)
        throw Error(what + ": the scene's textures would hold " + std::to_string(total) +
                    " floats, more than the budget of " + std::to_string(limit) + " (" +
                    std::to_string(kMaxBufferBytes >> 20) + " MiB)");
}

glm::vec2 read_vec2(const nlohmann::json& j, const char* key, glm::vec2 fallback,
                    const JsonReader& r, bool allow_scalar, double lo, double hi) {
    auto it = j.find(key);
    if (it == j.end())
        return fallback;
    const JsonReader rk = r.at(key);
    if (allow_scalar && it->is_number())
        return glm::vec2(static_cast<float>(rk.number(*it, lo, hi)));
    if (!it->is_array() || it->size() != 2)
        rk.fail(std::string("expected [u, v]") + (allow_scalar ? " or one number" : "") + ", got " +
                json_excerpt(*it));
    return glm::vec2(static_cast<float>(rk.at(size_t(0)).number((*it)[0], lo, hi)),
                     static_cast<float>(rk.at(size_t(1)).number((*it)[1], lo, hi)));
}

glm::vec3 read_colour(const nlohmann::json& j, const char* key, glm::vec3 fallback,
                      const JsonReader& r) {
    auto it = j.find(key);
    if (it == j.end())
        return fallback;
    const JsonReader rk = r.at(key);
    if (it->is_number())
        return glm::vec3(static_cast<float>(rk.number(*it, 0.0, 1.0)));
    if (!it->is_array() || it->size() != 3)
        rk.fail("expected [r, g, b] or one number in [0, 1], got " + json_excerpt(*it));
    glm::vec3 c;
    for (int k = 0; k < 3; ++k)
        c[k] = static_cast<float>(rk.at(size_t(k)).number((*it)[k], 0.0, 1.0));
    return c;
}

} // namespace

int TextureSet::add_file(const std::string& path, TextureUse use, glm::vec2 uv_scale,
                         glm::vec2 uv_offset, const std::string& where) {
    const std::string key = key_of(path, use, uv_scale, uv_offset);
    if (auto it = by_key_.find(key); it != by_key_.end())
        return it->second;
    Texture t;
    t.name = path;
    t.uv_scale = uv_scale;
    t.uv_offset = uv_offset;
    t.channels = use == TextureUse::colour ? 3 : 1;
    try {
        // The header first: its size against the budget the textures share, before any pixel
        // is read (the reader has checked it against the memory budget and the file's size).
        RgbImageReader reader(path, use == TextureUse::colour);
        t.width = reader.width();
        t.height = reader.height();
        const uint64_t texels = checked_mul(uint64_t(t.width), uint64_t(t.height), path);
        check_budget(floats_, checked_mul(texels, 3, path), path);
        std::vector<float> rgb(3 * texels);
        const size_t row = size_t(3) * t.width;
        for (int y = 0; y < t.height;) {
            const int got = reader.read_rows(reader.band_rows(), rgb.data() + row * y);
            if (got <= 0)
                throw Error(path + ": image ended early");
            y += got;
        }
        if (t.channels == 3) {
            for (float& v : rgb)
                v = clamp01(v);
            t.texels = std::move(rgb);
        } else {
            t.texels.resize(texels);
            for (uint64_t i = 0; i < texels; ++i)
                t.texels[i] = clamp01(rgb[3 * i]);
        }
    } catch (const Error& e) {
        throw Error(where + ": " + e.what());
    }
    const int index = add(std::move(t), where);
    by_key_[key] = index;
    return index;
}

int TextureSet::add(Texture t, const std::string& where) {
    const uint64_t n =
        checked_mul(checked_mul(uint64_t(t.width), uint64_t(t.height), where), t.channels, where);
    if (t.width <= 0 || t.height <= 0 || (t.channels != 1 && t.channels != 3) ||
        t.texels.size() != n)
        throw Error(where + ": malformed texture");
    check_budget(floats_, n, where);
    if (textures_.size() >= static_cast<size_t>(std::numeric_limits<int>::max() / 2))
        throw Error(where + ": too many textures");
    floats_ += n;
    textures_.push_back(std::move(t));
    return static_cast<int>(textures_.size() - 1);
}

Texture make_checker(glm::vec3 colour0, glm::vec3 colour1, int resolution) {
    Texture t;
    t.name = "checker";
    t.width = t.height = 2 * resolution;
    t.channels = 3;
    t.texels.resize(size_t(3) * t.width * t.height);
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) {
            // The texel centre's (u, v); row 0 is the top, v = 1 (kernels/texture_lookup.h).
            const bool mu = (x + 0.5) / t.width > 0.5, mv = 1.0 - (y + 0.5) / t.height > 0.5;
            const glm::vec3 c = mu == mv ? colour0 : colour1;
            float* p = &t.texels[3 * (size_t(y) * t.width + x)];
            p[0] = c.x, p[1] = c.y, p[2] = c.z;
        }
    return t;
}

int read_texture_param(const nlohmann::json& j, const char* key, TextureUse use,
                       const std::string& dir, const JsonReader& r, TextureSet& set) {
    auto it = j.find(key);
    if (it == j.end() || !it->is_object())
        return -1;
    const nlohmann::json& t = *it;
    const JsonReader rt = r.at(key);
    rt.reject_unknown_keys(t, {"texture", "checker", "uv_scale", "uv_offset"});
    const bool file = t.contains("texture"), checker = t.contains("checker");
    if (file == checker)
        rt.fail("a texture needs exactly one of \"texture\" (an image file) and \"checker\"");
    const glm::vec2 scale = read_vec2(t, "uv_scale", glm::vec2(1.0f), rt, true, -1e6, 1e6);
    const glm::vec2 offset = read_vec2(t, "uv_offset", glm::vec2(0.0f), rt, false, -1e6, 1e6);
    if (file) {
        const JsonReader rf = rt.at("texture");
        if (!t["texture"].is_string())
            rf.fail("expected an image file name, got " + json_excerpt(t["texture"]));
        const std::string name = rf.string(t["texture"]);
        if (name.empty())
            rf.fail("the file name is empty");
        std::string path;
        try {
            path = resolve_data_file(name, dir);
        } catch (const Error& e) {
            rf.fail(e.what());
        }
        return set.add_file(path, use, scale, offset, rf.where());
    }
    const JsonReader rc = rt.at("checker");
    const nlohmann::json& c = t["checker"];
    rc.expect_object(c);
    rc.reject_unknown_keys(c, {"color0", "color1", "resolution"});
    const glm::vec3 c0 = read_colour(c, "color0", glm::vec3(0.4f), rc);
    const glm::vec3 c1 = read_colour(c, "color1", glm::vec3(0.2f), rc);
    const int res = static_cast<int>(rc.integer(c, "resolution", 32, 1, 2048));
    Texture tex = make_checker(c0, c1, res);
    if (use == TextureUse::data) { // one channel: the first
        std::vector<float> grey(tex.texels.size() / 3);
        for (size_t i = 0; i < grey.size(); ++i)
            grey[i] = tex.texels[3 * i];
        tex.texels = std::move(grey);
        tex.channels = 1;
    }
    tex.uv_scale = scale;
    tex.uv_offset = offset;
    return set.add(std::move(tex), rc.where());
}

} // namespace et
