// The chunk offset table of an OpenEXR part: how many entries OpenEXR sizes it by, from the
// data window, the compression's lines per chunk and the tiling's levels.
#include "image/exr_header_parts.h"
#include "util/checked_size.h"

#include <algorithm>

namespace et::exr_detail {
namespace {

// OpenEXR's level arithmetic (ImfTiledMisc.cpp).
int round_log2(int64_t x, int rounding) {
    int y = 0, r = 0;
    while (x > 1) {
        r |= x & 1;
        ++y;
        x >>= 1;
    }
    return rounding == 1 ? y + r : y;
}
int64_t level_size(int64_t size, int level, int rounding) {
    int64_t s = size >> level;
    if (rounding == 1 && (s << level) < size)
        ++s;
    return std::max<int64_t>(s, 1);
}
// Tiles along one axis over `levels` levels.
std::vector<int64_t> tiles_per_level(int64_t size, int levels, uint32_t tile, int rounding) {
    std::vector<int64_t> n(static_cast<size_t>(levels));
    for (int l = 0; l < levels; ++l)
        n[l] = (level_size(size, l, rounding) + tile - 1) / tile;
    return n;
}

} // namespace

uint64_t chunk_count(const Header& h) {
    const int64_t w = h.data.width(), ht = h.data.height();
    if (h.type != "tiledimage")
        return static_cast<uint64_t>((ht + kLinesPerChunk[h.compression] - 1) /
                                     kLinesPerChunk[h.compression]);
    const int rx = h.level_mode == 0   ? 1
                   : h.level_mode == 1 ? round_log2(std::max(w, ht), h.rounding) + 1
                                       : round_log2(w, h.rounding) + 1;
    const int ry = h.level_mode == 0 ? 1 : h.level_mode == 1 ? rx : round_log2(ht, h.rounding) + 1;
    const auto nx = tiles_per_level(w, rx, h.tile_w, h.rounding);
    const auto ny = tiles_per_level(ht, ry, h.tile_h, h.rounding);
    uint64_t n = 0;
    if (h.level_mode == 2) {
        uint64_t sx = 0, sy = 0;
        for (int64_t v : nx)
            sx += uint64_t(v);
        for (int64_t v : ny)
            sy += uint64_t(v);
        n = checked_mul(sx, sy, "EXR tiles");
    } else {
        for (int l = 0; l < rx; ++l)
            n += checked_mul(uint64_t(nx[l]), uint64_t(ny[l]), "EXR tiles");
    }
    return n;
}

int pixel_bytes(const Channel& c) {
    return c.type == kHalf ? 2 : 4;
}

} // namespace et::exr_detail
