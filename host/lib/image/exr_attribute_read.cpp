// Attribute values read as OpenEXR reads them: a known type by its content, which must come out
// exactly as long as its size field; unknown types by size.
#include "image/exr_header_parts.h"

#include <map>

namespace et::exr_detail {

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

} // namespace et::exr_detail
