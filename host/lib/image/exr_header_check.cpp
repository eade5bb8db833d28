// Every header of an OpenEXR file checked before OpenEXR reads it (exr_header.h): the walk over
// the headers, each part's required attributes and values, and the chunk offset tables.
#include "image/exr_header.h"
#include "image/exr_header_parts.h"
#include "util/checked_size.h"

#include <algorithm>
#include <climits>

namespace et {
namespace {

using namespace exr_detail;

// A header's required attributes and their values, after the whole header has been read.
void check_part(const Walker& in, Header& h, int part, bool multipart, bool tiled_flag) {
    const std::string where = multipart ? "part " + std::to_string(part) + ": " : "";
    std::string missing;
    auto need = [&](bool has, const char* name) {
        if (!has)
            missing += std::string(missing.empty() ? "" : ", ") + name;
    };
    need(h.has_channels, "channels");
    need(h.has_compression, "compression");
    need(h.has_data, "dataWindow");
    need(h.has_display, "displayWindow");
    need(h.has_line_order, "lineOrder");
    if (multipart) {
        need(h.has_name, "name");
        need(h.has_type, "type");
        need(h.has_chunks, "chunkCount");
    }
    if (!h.has_type)
        h.type = tiled_flag ? "tiledimage" : "scanlineimage";
    const bool tiled = h.type == "tiledimage";
    if (tiled)
        need(h.has_tiles, "tiles");
    if (!missing.empty())
        in.fail(where + "no " + missing + " attribute");

    if (h.type == "deepscanline" || h.type == "deeptile")
        in.unsupported(where + "deep EXR images are not supported (no colour to read)");
    if (h.type != "scanlineimage" && h.type != "tiledimage")
        in.fail(where + "part type '" + shown(h.type) + "' is not an image");
    if (!multipart && tiled != tiled_flag)
        in.fail("the version field says " + std::string(tiled_flag ? "tiled" : "scanline") +
                " and the type attribute '" + h.type + "'");
    if (h.channels.empty())
        in.fail(where + "the channel list is empty");

    // Windows as OpenEXR's sanityCheck wants them: not empty, corners within +-2^30.
    auto check_box = [&](const Box& b, const char* name) {
        const int32_t lim = INT_MAX / 2;
        if (b.x0 > b.x1 || b.y0 > b.y1 || b.x0 <= -lim || b.y0 <= -lim || b.x1 >= lim ||
            b.y1 >= lim)
            in.fail(where + name + " (" + std::to_string(b.x0) + ", " + std::to_string(b.y0) +
                    ") - (" + std::to_string(b.x1) + ", " + std::to_string(b.y1) +
                    ") is empty or out of range");
    };
    check_box(h.data, "dataWindow");
    check_box(h.display, "displayWindow");
    if (!tiled && h.line_order > 1)
        in.fail(where + "a scanline image with random line order");

    for (const Channel& c : h.channels) {
        const bool fits = h.data.x0 % c.xs == 0 && h.data.y0 % c.ys == 0 &&
                          h.data.width() % c.xs == 0 && h.data.height() % c.ys == 0;
        if ((tiled && (c.xs != 1 || c.ys != 1)) || !fits)
            in.fail(where + "channel '" + shown(c.name) + "' has sampling " + std::to_string(c.xs) +
                    "x" + std::to_string(c.ys) +
                    (tiled ? " in a tiled image" : " that does not divide the data window"));
    }
    if (tiled) {
        // A tile may be larger than the image (a 16x8 map in 64x64 tiles), but OpenEXR and
        // OpenImageIO allocate, and fill, whole tiles: 16x6225936 tiles of a 37x21 image took
        // 1.27 GB. So a tile is at most the memory budget, and at most 256 MB unless the image
        // itself is larger.
        uint64_t pixel = 0, image = 0;
        for (const Channel& c : h.channels) {
            pixel += pixel_bytes(c);
            image +=
                uint64_t(pixel_bytes(c)) * uint64_t(h.data.width()) * uint64_t(h.data.height());
        }
        const uint64_t tile =
            h.tile_w < 1 || h.tile_h < 1
                ? 0
                : checked_mul(checked_mul(h.tile_w, h.tile_h, "EXR tiles"), pixel, "EXR tiles");
        if (tile == 0 || h.tile_w > INT_MAX || h.tile_h > INT_MAX || tile > kMaxBufferBytes ||
            tile > std::max<uint64_t>(image, uint64_t(256) << 20))
            in.fail(where + "tiles of " + std::to_string(h.tile_w) + "x" +
                    std::to_string(h.tile_h) + " pixels of " + std::to_string(pixel) +
                    " bytes are empty, larger than the memory budget, or larger than both the "
                    "image and 256 MB");
    }
}

} // namespace

ExrHeaderInfo check_exr_header(const std::string& path, uint64_t file_bytes) {
    Walker in(path, file_bytes);
    unsigned char head[8];
    in.bytes(head, 8, "the version field");
    const uint32_t flags =
        uint32_t(head[5]) << 8 | uint32_t(head[6]) << 16 | uint32_t(head[7]) << 24;
    if (head[4] != 2)
        in.fail("version " + std::to_string(head[4]) + " (OpenEXR files are version 2)");
    if (flags & ~uint32_t(0x1e00))
        in.fail("unknown flags in the version field (0x" + [&] {
            char buf[16];
            std::snprintf(buf, sizeof buf, "%x", flags);
            return std::string(buf);
        }() + ")");
    const bool tiled_flag = flags & 0x200, deep = flags & 0x800, multipart = flags & 0x1000;
    if (deep)
        in.unsupported("deep EXR images are not supported (no colour to read)");

    std::vector<Header> parts;
    for (;;) {
        Header h;
        int attributes = 0;
        for (;; ++attributes) {
            const std::string name = in.name("attribute name");
            if (name.empty())
                break;
            const std::string type = in.name("attribute type");
            if (type.empty())
                in.fail("attribute '" + shown(name) + "' has no type");
            const int32_t size = in.i32("an attribute size");
            if (size < 0 || uint64_t(size) > in.left())
                in.fail("attribute '" + shown(name) + "' claims " + std::to_string(size) +
                        " bytes, the file has " + std::to_string(in.left()) + " left");
            if (!h.names.insert(name).second)
                in.fail("attribute '" + shown(name) + "' appears twice");
            read_value(in, h, name, type, static_cast<uint32_t>(size));
        }
        if (attributes == 0) {
            if (multipart && !parts.empty())
                break; // the empty header that ends a multi-part file's list
            in.fail("the header has no attributes");
        }
        check_part(in, h, static_cast<int>(parts.size()), multipart, tiled_flag);
        parts.push_back(std::move(h));
        if (!multipart)
            break;
    }

    // The offset tables, and at least each chunk's own header (its y or tile coordinates and
    // data size, 8 bytes or more), must fit in what follows the headers.
    uint64_t chunks = 0;
    for (size_t p = 0; p < parts.size(); ++p) {
        const Header& h = parts[p];
        const uint64_t n = chunk_count(h);
        if (h.has_chunks && (h.chunk_count < 0 || uint64_t(h.chunk_count) != n))
            in.fail((multipart ? "part " + std::to_string(p) + ": " : std::string()) +
                    "chunkCount " + std::to_string(h.chunk_count) + ", but its data window, " +
                    "compression and tiles make " + std::to_string(n) + " chunks");
        chunks = checked_add(chunks, n, path);
    }
    const uint64_t need = checked_mul(chunks, 16, path);
    if (need > in.left())
        in.fail(std::to_string(chunks) + " chunks need at least " + std::to_string(need) +
                " bytes (their offsets and headers), the file has " + std::to_string(in.left()) +
                " after the header: truncated or corrupt");

    // The pixels themselves: every method but PIZ and DWA has a bounded compression ratio (a
    // chunk is stored raw when compressing does not shrink it), so the file must hold at least
    // the stored size over that ratio. An uncompressed 5439552x32 header in a 13 kB file was read
    // "successfully" by OpenEXR into 2 GB of texels otherwise.
    for (size_t p = 0; p < parts.size(); ++p) {
        const Header& h = parts[p];
        // NONE, RLE (runs of 128 bytes in 2), ZIPS, ZIP (deflate, 1032:1), PIZ, PXR24 (24-bit
        // floats, then deflate), B44 (32 bytes of half in 14), B44A (a flat block in 3), DWAA,
        // DWAB; 0: no bound here (check_declared_size's 100000:1 applies).
        constexpr double kMaxRatio[] = {1, 65, 1100, 1100, 0, 1400, 3, 11, 0, 0};
        const double ratio = kMaxRatio[h.compression];
        uint64_t stored = 0;
        for (const Channel& c : h.channels)
            stored += uint64_t(pixel_bytes(c)) * uint64_t(h.data.width() / c.xs) *
                      uint64_t(h.data.height() / c.ys);
        if (ratio > 0 && double(stored) / ratio > double(in.left()))
            in.fail((multipart ? "part " + std::to_string(p) + ": " : std::string()) +
                    std::to_string(h.data.width()) + "x" + std::to_string(h.data.height()) +
                    " pixels of " + std::to_string(h.channels.size()) + " channels are " +
                    std::to_string(stored) + " bytes, more than " +
                    kCompressionNames[h.compression] + " can fit in the " +
                    std::to_string(in.left()) + " bytes after the header: truncated or corrupt");
    }

    const Header& first = parts.front();
    ExrHeaderInfo info;
    info.width = first.data.width();
    info.height = first.data.height();
    info.channels = static_cast<int>(first.channels.size());
    info.tiled = first.type == "tiledimage";
    info.parts = static_cast<int>(parts.size());
    for (const Channel& c : first.channels)
        info.stored_bytes +=
            uint64_t(pixel_bytes(c)) * uint64_t(info.width / c.xs) * uint64_t(info.height / c.ys);
    return info;
}

} // namespace et
