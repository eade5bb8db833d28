// The parts of an OpenEXR header as check_exr_header (exr_header.h) reads them, shared by the
// files that read attribute values (exr_attribute_read.cpp), size the chunk offset tables
// (exr_chunk_table.cpp) and check each part (exr_header_check.cpp).
//
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
#pragma once
#include "util/error.h"

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <set>
#include <sys/types.h>
#include <string>
#include <vector>

namespace et::exr_detail {

// OpenEXR reads names of up to 255 bytes, long-names flag or not.
inline constexpr int kMaxName = 255;

enum : int { kUint = 0, kHalf = 1, kFloat = 2 };

// Lines per chunk of each compression method, NO_COMPRESSION (0) to DWAB (9).
inline constexpr int kLinesPerChunk[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
inline constexpr int kCompressions = sizeof(kLinesPerChunk) / sizeof(kLinesPerChunk[0]);
inline constexpr const char* kCompressionNames[] = {
    "uncompressed storage", "RLE", "ZIPS", "ZIP", "PIZ", "PXR24", "B44", "B44A", "DWAA", "DWAB"};

// Fixed size in bytes of a type OpenEXR 3.1 knows (ImfHeader.cpp staticInitialize); -1 for others.
int fixed_size(const std::string& type);

// A name for a message: printable, non-printable bytes as \xNN, at most 40 bytes.
std::string shown(const std::string& s);

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

Box read_box(Walker& in);
// The channel list, entry by entry as OpenEXR reads it; returns the bytes it took.
uint64_t read_channels(Walker& in, Header& h);
// The value of attribute `name` of type `type` and `size` bytes, read as OpenEXR reads it.
void read_value(Walker& in, Header& h, const std::string& name, const std::string& type,
                uint32_t size);

// Chunks (offset table entries) of a part: what OpenEXR sizes the table by.
uint64_t chunk_count(const Header& h);
// Bytes of one sample of the channel.
int pixel_bytes(const Channel& c);

} // namespace et::exr_detail
