// Radiance RGBE pixels decoded by envtrace once OpenImageIO has read the header (oiio_reader.cpp),
// bit for bit as OpenImageIO decodes them.
#pragma once
#include "image/oiio_file_proxy.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace et::image_detail {

// What a Radiance texel (m, m, m, e) is worth per unit of m: 2^(e - 136), 0 for e = 0, as
// OpenImageIO's decoder has it. Its table holds decimal literals, three of which (e = 40, 223, 226
// in 2.4) are not exact powers of two; the scales are read back from it once, through a 256-texel
// image in memory, so that texels decoded here are bit for bit those it would give.
const std::array<float, 256>& rgbe_scales();

// Radiance RGBE pixels decoded here, once OpenImageIO has read the header: its decoder makes a
// virtual read call per RLE run and takes several times as long. The rules are those of its
// RGBE_ReadPixels_RLE, scanline by scanline: widths below 8 or above 32767 are flat; a scanline
// that does not start with 2, 2, width is flat, its 4 bytes being the first pixel; runs of 0 or
// past the end of the scanline are errors. A texel is mantissa x 2^(exponent - 136), 0 for
// exponent 0, as there.
class RgbeDecoder {
  public:
    RgbeDecoder(const std::string& path, int64_t data_offset, int width)
        : w_(width), pos_(data_offset) {
        fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        // Room for the longest RLE scanline (a count byte per byte in every channel); flat ones
        // are read in pieces.
        if (rle())
            line_.resize(4 * static_cast<size_t>(w_));
        buf_.resize(std::max<size_t>(size_t(1) << 20, 2 * (8 * line_.size() / 4 + 4)));
        const std::array<float, 256>& scales = rgbe_scales();
        std::copy(scales.begin(), scales.end(), exponent_);
    }
    ~RgbeDecoder() {
        if (fd_ >= 0)
            ::close(fd_);
    }
    bool opened() const { return fd_ >= 0; }

    // Decodes scanlines [y0, y1) into dst; returns "" or what went wrong.
    std::string read_rows(int y0, int y1, float* dst) {
        for (int y = y0; y < y1; ++y, dst += 3 * static_cast<size_t>(w_)) {
            const std::string err = read_scanline(dst);
            if (!err.empty())
                return err + " on scanline " + std::to_string(y);
        }
        return "";
    }

  private:
    int w_, fd_ = -1;
    int64_t pos_;                     // file offset of buf_[at_]
    std::vector<unsigned char> buf_;  // file bytes [pos_ - at_, pos_ - at_ + len_)
    size_t at_ = 0, len_ = 0;         // next unread byte, bytes held
    std::vector<unsigned char> line_; // one RLE scanline, channel after channel
    float exponent_[256];

    // At least n unread bytes in the buffer (n <= buf_.size() / 2), fewer only at the file's end.
    size_t ensure(size_t n) {
        if (len_ - at_ >= n)
            return len_ - at_;
        std::memmove(buf_.data(), buf_.data() + at_, len_ - at_);
        len_ -= at_;
        at_ = 0;
        len_ += pread_full(fd_, buf_.data() + len_, buf_.size() - len_,
                           pos_ + static_cast<int64_t>(len_));
        return len_;
    }
    void advance(size_t n) {
        at_ += n;
        pos_ += static_cast<int64_t>(n);
    }
    void texel(const unsigned char* rgbe, float* out) const {
        const float f = exponent_[rgbe[3]];
        out[0] = rgbe[0] * f;
        out[1] = rgbe[1] * f;
        out[2] = rgbe[2] * f;
    }
    bool rle() const { return w_ >= 8 && w_ <= 0x7fff; }
    // n flat pixels into out.
    std::string read_flat(int n, float* out) {
        const int piece = static_cast<int>(buf_.size() / 8);
        for (int x0 = 0; x0 < n; x0 += piece) {
            const int m = std::min(piece, n - x0);
            const size_t bytes = 4 * static_cast<size_t>(m);
            if (ensure(bytes) < bytes)
                return "read error";
            const unsigned char* p = buf_.data() + at_;
            for (int x = 0; x < m; ++x)
                texel(p + 4 * x, out + 3 * (static_cast<size_t>(x0) + x));
            advance(bytes);
        }
        return "";
    }
    std::string read_scanline(float* out) {
        if (!rle())
            return read_flat(w_, out);
        if (ensure(8 * static_cast<size_t>(w_) + 4) < 4)
            return "read error";
        const unsigned char* p = buf_.data() + at_;
        if (p[0] != 2 || p[1] != 2 || (p[2] & 0x80)) {
            texel(p, out);
            advance(4);
            return read_flat(w_ - 1, out + 3);
        }
        if ((p[2] << 8 | p[3]) != w_)
            return "wrong scanline width";
        const unsigned char* end = buf_.data() + len_;
        p += 4;
        unsigned char* dst = line_.data();
        for (int c = 0; c < 4; ++c) {
            unsigned char* const dst_end = line_.data() + static_cast<size_t>(c + 1) * w_;
            while (dst < dst_end) {
                if (end - p < 2)
                    return "read error";
                const bool run = p[0] > 128;
                const ptrdiff_t count = run ? p[0] - 128 : p[0];
                if (count == 0 || count > dst_end - dst)
                    return "bad scanline data";
                if (run) {
                    std::memset(dst, p[1], static_cast<size_t>(count));
                    p += 2;
                } else {
                    if (end - p < 1 + count)
                        return "read error";
                    std::memcpy(dst, p + 1, static_cast<size_t>(count));
                    p += 1 + count;
                }
                dst += count;
            }
        }
        advance(static_cast<size_t>(p - (buf_.data() + at_)));
        const unsigned char *r = line_.data(), *g = r + w_, *b = g + w_, *e = b + w_;
        for (int x = 0; x < w_; ++x) {
            const float f = exponent_[e[x]];
            out[3 * x] = r[x] * f;
            out[3 * x + 1] = g[x] * f;
            out[3 * x + 2] = b[x] * f;
        }
        return "";
    }
};

} // namespace et::image_detail
