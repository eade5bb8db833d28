// Environment maps for the benchmarks: real maps from the shared data directory, the procedural
// sky, and an 8192x4096 map made in memory by upsampling a real 1k map (never written to disk).
#pragma once
#include "util/data_path.h"
#include "image/image_io.h"
#include "kernels/envmap.h"
#include "load/sky.h"

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

namespace et::bench {

// A real map by file name (e.g. "royal_esplanade_1k.hdr"), resolved like scene inputs
// (ENVTRACE_DATA, then ../shared/data beside the source tree), cached for the process.
inline const RgbImage& real_map(const std::string& name) {
    static std::map<std::string, RgbImage> cache;
    auto it = cache.find(name);
    if (it == cache.end()) {
        std::string path;
        try {
            path = resolve_data_file("envmaps/" + name);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "%s\n", e.what());
            std::exit(1);
        }
        it = cache.emplace(name, read_rgb_image(path)).first;
    }
    return it->second;
}

// The procedural sun-and-sky at w x h.
inline const RgbImage& sky_map(int w, int h) {
    static std::map<std::pair<int, int>, RgbImage> cache;
    auto key = std::make_pair(w, h);
    auto it = cache.find(key);
    if (it == cache.end()) {
        SkyParams p;
        p.width = w;
        p.height = h;
        it = cache.emplace(key, make_sky(p)).first;
    }
    return it->second;
}

// A real map bilinearly upsampled (wrapping in phi, clamped at the poles) to w x h.
inline const RgbImage& upsampled_map(const std::string& name, int w, int h) {
    static std::map<std::string, RgbImage> cache;
    const std::string key = name + "@" + std::to_string(w) + "x" + std::to_string(h);
    auto it = cache.find(key);
    if (it == cache.end()) {
        const RgbImage& src = real_map(name);
        RgbImage out;
        out.width = w;
        out.height = h;
        out.rgb.resize(3 * static_cast<size_t>(w) * h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                etk::float3 c =
                    etk::etk_env_lookup_uv(src.rgb.data(), src.width, src.height,
                                           etk::make_float2((x + 0.5f) / w, (y + 0.5f) / h));
                float* t = out.at(x, y);
                t[0] = c.x;
                t[1] = c.y;
                t[2] = c.z;
            }
        it = cache.emplace(key, std::move(out)).first;
    }
    return it->second;
}

} // namespace et::bench
