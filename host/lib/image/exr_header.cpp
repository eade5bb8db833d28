#include "image/exr_header.h"

#include "util/checked_size.h"
#include "util/error.h"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <set>

// The layout (openexr.com, "OpenEXR File Layout"): magic 76 2f 31 01; a version field (version 2
// in the low byte; flags 0x200 single-part tiled, 0x400 long names, 0x800 deep, 0x1000
// multi-part); headers, each a list of attributes (name and type NUL-terminated, an int32 size,
// the value) ended by an empty name, a multi-part file's list of headers ended by an empty
// header; then one table of 64-bit chunk offsets per part; then the chunks.
//
// OpenEXR's Header::readFrom reads the value of a type it knows by its content, not by its size
// field, and goes on reading the next attribute where that content ended: a channel list whose
// entries end before its size says made the rest of F11's header be read out of step, until a
// string claimed 1 GB. So each known type is parsed here as OpenEXR parses it and must come out
// exactly as long as its size field; unknown types are read by size, as OpenEXR does.

namespace et {
namespace {

constexpr int kMaxName = 255; // OpenEXR reads names of up to 255 bytes, long-names flag or not

enum : int { kUint = 0, kHalf = 1, kFloat = 2 };

// Lines per chunk of each compression method, NO_COMPRESSION (0) to DWAB (9).
constexpr int kLinesPerChunk[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
constexpr int kCompressions = sizeof(kLinesPerChunk) / sizeof(kLinesPerChunk[0]);
constexpr const char* kCompressionNames[] = {
    "uncompressed storage", "RLE", "ZIPS", "ZIP", "PIZ", "PXR24", "B44", "B44A", "DWAA", "DWAB"};

// Fixed sizes of the types OpenEXR 3.1 knows (ImfHeader.cpp staticInitialize).
int fixed_size(const std::string& type) {
    static const std::map<std::string, int> sizes = {
        {"box2i", 16},      {"box2f", 16},    {"chromaticities", 32},
        {"compression", 1}, {"double", 8},    {"deepImageState", 1},
        {"envmap", 1},      {"float", 4},     {"int", 4},
        {"keycode", 28},    {"lineOrder", 1}, {"m33f", 36},
        {"m33d", 72},       {"m44f", 64},     {"m44d", 128},
        {"rational", 8},    {"tiledesc", 9},  {"timecode", 8},
        {"v2i", 8},         {"v2f", 8},       {"v2d", 16},
        {"v3i", 12},        {"v3f", 12},      {"v3d", 24}};
    const auto it = sizes.find(type);
    return it == sizes.end() ? -1 : it->second;
}

// A name for a message: printable, non-printable bytes as \xNN, at most 40 bytes.
std::string shown(const std::string& s) {
    std::string out;
    for (unsigned char c : s.substr(0, 40)) {
        if (c >= 0x20 && c < 0x7f) {
            out.push_back(static_cast<char>(c));
        } else {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", c);
            out += buf;
        }
    }
    return s.size() > 40 ? out + "..." : out;
}

struct Box {
    int32_t x0 = 0, y0 = 0, x1 = -1, y1 = -1;
    int64_t width() const { return int64_t(x1) - x0 + 1; }
    int64_t height() const { return int64_t(y1) - y0 + 1; }
};

struct Channel {
    std::string name;
    int32_t type = 0, xs = 1, ys = 1;
};

// One header's attributes as far as the checks need them.
struct Header {
    std::set<std::string> names;
    std::vector<Channel> channels;
    bool has_channels = false, has_compression = false, has_data = false, has_display = false,
         has_line_order = false, has_tiles = false, has_type = false, has_name = false,
         has_chunks = false;
    int compression = 0, line_order = 0;
    Box data, display;
    uint32_t tile_w = 0, tile_h = 0;
    int level_mode = 0, rounding = 0;
    std::string type;
    int32_t chunk_count = 0;
};

// Reads the file a value at a time; every read checks that the bytes are there.
class Walker {
  public:
    Walker(const std::string& path, uint64_t file_bytes)
        : path_(path), file_bytes_(file_bytes), file_(std::fopen(path.c_str(), "rb")) {
        if (!file_)
            throw Error(path + ": cannot open: " + std::strerror(errno));
    }
    [[noreturn]] void fail(const std::string& problem) const {
        throw Error(path_ + ": corrupt EXR header: " + problem);
    }
    [[noreturn]] void unsupported(const std::string& problem) const {
        throw Error(path_ + ": " + problem);
    }
    uint64_t pos() const { return pos_; }
    uint64_t left() const { return file_bytes_ > pos_ ? file_bytes_ - pos_ : 0; }
    void bytes(void* dst, size_t n, const char* what) {
        if (n > left() || std::fread(dst, 1, n, file_.get()) != n)
            fail(std::string("the file ends inside ") + what);
        pos_ += n;
    }
    uint32_t u32(const char* what) {
        unsigned char b[4];
        bytes(b, 4, what);
        return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
    }
    int32_t i32(const char* what) { return static_cast<int32_t>(u32(what)); }
    uint8_t u8(const char* what) {
        uint8_t b;
        bytes(&b, 1, what);
        return b;
    }
    // A NUL-terminated name of at most kMaxName bytes ("" for the terminating empty name).
    std::string name(const char* what) {
        std::string s;
        for (;;) {
            const char c = static_cast<char>(u8(what));
            if (c == 0)
                return s;
            if (s.size() >= kMaxName)
                fail(std::string(what) + " '" + shown(s) + "' is longer than 255 bytes");
            s.push_back(c);
        }
    }
    void skip(uint64_t n, const char* what) {
        if (n > left() || fseeko(file_.get(), static_cast<off_t>(pos_ + n), SEEK_SET) != 0)
            fail(std::string("the file ends inside ") + what);
        pos_ += n;
    }

  private:
    struct Closer {
        void operator()(std::FILE* f) const { std::fclose(f); }
    };
    std::string path_;
    uint64_t file_bytes_;
    std::unique_ptr<std::FILE, Closer> file_;
    uint64_t pos_ = 0;
};

Box read_box(Walker& in) {
    Box b;
    b.x0 = in.i32("a box2i");
    b.y0 = in.i32("a box2i");
    b.x1 = in.i32("a box2i");
    b.y1 = in.i32("a box2i");
    return b;
}

// The channel list, entry by entry as OpenEXR reads it; returns the bytes it took.
uint64_t read_channels(Walker& in, Header& h) {
    const uint64_t start = in.pos();
    std::set<std::string> seen;
    for (;;) {
        std::string name = in.name("channel name");
        if (name.empty())
            break;
        Channel c;
        c.name = name;
        c.type = in.i32("a channel");
        in.u8("a channel"); // pLinear
        in.skip(3, "a channel");
        c.xs = in.i32("a channel");
        c.ys = in.i32("a channel");
        if (c.type < kUint || c.type > kFloat)
            in.fail("channel '" + shown(name) + "' has pixel type " + std::to_string(c.type) +
                    " (0 UINT, 1 HALF, 2 FLOAT)");
        if (c.xs < 1 || c.ys < 1)
            in.fail("channel '" + shown(name) + "' has sampling " + std::to_string(c.xs) + "x" +
                    std::to_string(c.ys));
        if (!seen.insert(name).second)
            in.fail("channel '" + shown(name) + "' appears twice in the channel list");
        h.channels.push_back(c);
    }
    return in.pos() - start;
}

// The value of attribute `name` of type `type` and `size` bytes, read as OpenEXR reads it.
void read_value(Walker& in, Header& h, const std::string& name, const std::string& type,
                uint32_t size) {
    const std::string what =
        "attribute '" + shown(name) + "' (" + shown(type) + ", " + std::to_string(size) + " bytes)";
    const int fixed = fixed_size(type);
    if (fixed >= 0 && size != uint32_t(fixed))
        in.fail(what + ": a " + shown(type) + " has " + std::to_string(fixed) + " bytes");

    // The attributes the reader depends on must have their own types (OpenEXR refuses another
    // type for its predefined ones only when it reads them, after allocating the others).
    static const std::map<std::string, std::string> required_type = {
        {"channels", "chlist"},     {"compression", "compression"},
        {"dataWindow", "box2i"},    {"displayWindow", "box2i"},
        {"lineOrder", "lineOrder"}, {"tiles", "tiledesc"},
        {"type", "string"},         {"name", "string"},
        {"chunkCount", "int"}};
    const auto req = required_type.find(name);
    if (req != required_type.end() && req->second != type)
        in.fail(what + ": expected type " + req->second);

    if (type == "chlist") {
        const uint64_t used = read_channels(in, h);
        if (used != size)
            in.fail(what + ": its " + std::to_string(h.channels.size()) + " channels take " +
                    std::to_string(used) + " bytes");
        h.has_channels = true;
    } else if (type == "stringvector") {
        // Strings, each an int32 length and its bytes, filling the value exactly.
        uint64_t used = 0;
        while (used < size) {
            if (size - used < 4)
                in.fail(what + ": a string length is cut off at byte " + std::to_string(used));
            const int32_t n = in.i32("a string vector");
            used += 4;
            if (n < 0 || uint64_t(n) > size - used)
                in.fail(what + ": a string claims " + std::to_string(n) + " bytes, the value has " +
                        std::to_string(size - used) + " left");
            in.skip(uint64_t(n), "a string vector");
            used += uint64_t(n);
        }
    } else if (type == "floatvector") {
        if (size % 4 != 0)
            in.fail(what + ": not a whole number of floats");
        in.skip(size, "a float vector");
    } else if (type == "preview") {
        uint32_t pw = 0, ph = 0;
        if (size >= 8) {
            pw = in.u32("a preview");
            ph = in.u32("a preview");
        }
        if (size < 8 || 8 + 4 * uint64_t(pw) * ph != size)
            in.fail("preview of " + std::to_string(pw) + "x" + std::to_string(ph) +
                    " pixels in an attribute of " + std::to_string(size) + " bytes");
        in.skip(size - 8, "a preview");
    } else if (type == "idmanifest") {
        if (size < 4)
            in.fail(what + ": an ID manifest has at least 4 bytes");
        in.skip(size, "an ID manifest");
    } else if (name == "compression") {
        h.compression = in.u8("compression");
        if (h.compression >= kCompressions)
            in.fail("unknown compression method " + std::to_string(h.compression));
        h.has_compression = true;
    } else if (name == "lineOrder") {
        h.line_order = in.u8("lineOrder");
        if (h.line_order > 2)
            in.fail("unknown line order " + std::to_string(h.line_order));
        h.has_line_order = true;
    } else if (name == "dataWindow") {
        h.data = read_box(in);
        h.has_data = true;
    } else if (name == "displayWindow") {
        h.display = read_box(in);
        h.has_display = true;
    } else if (name == "tiles") {
        h.tile_w = in.u32("tiles");
        h.tile_h = in.u32("tiles");
        const uint8_t mode = in.u8("tiles");
        h.level_mode = mode & 0xf;
        h.rounding = mode >> 4;
        if (h.level_mode > 2 || h.rounding > 1)
            in.fail("tiles: unknown level mode " + std::to_string(h.level_mode) +
                    " or rounding mode " + std::to_string(h.rounding));
        h.has_tiles = true;
    } else if (name == "chunkCount") {
        h.chunk_count = in.i32("chunkCount");
        h.has_chunks = true;
    } else if (name == "type" || name == "name") {
        std::string value(std::min<uint32_t>(size, 64), '\0');
        in.bytes(value.data(), value.size(), "a string");
        in.skip(size - value.size(), "a string");
        if (name == "type") {
            h.type = value.substr(0, value.find('\0'));
            h.has_type = true;
        } else {
            h.has_name = true;
        }
    } else {
        in.skip(size, "an attribute value"); // fixed size checked above; others by size
    }
}

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

// Chunks (offset table entries) of a part: what OpenEXR sizes the table by.
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
