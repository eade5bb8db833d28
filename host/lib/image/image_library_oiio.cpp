// Images through OpenImageIO: every format it reads and writes (image_library.h).
#include "image/exr_header.h"
#include "image/image_io.h"
#include "image/image_library.h"
#include "util/file_check.h"

#include "util/error.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

OIIO_NAMESPACE_USING

namespace et::image_detail {
namespace {

// Up to `size` bytes at `offset`, retrying short reads and EINTR; fewer only at the end of the
// file or on an error.
size_t pread_full(int fd, void* buf, size_t size, int64_t offset) {
    size_t done = 0;
    while (fd >= 0 && offset >= 0 && done < size) {
        const ssize_t n = ::pread(fd, static_cast<char*>(buf) + done, size - done,
                                  static_cast<off_t>(offset + static_cast<int64_t>(done)));
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        done += static_cast<size_t>(n);
    }
    return done;
}

// A read-only IOProxy over a file, with a buffer of its own. OpenImageIO's Radiance HDR reader
// asks for 2 bytes per RLE run; through its default proxy each request is an fread, and those
// cost more than the decoding (a 16384x8192 map has tens of millions of runs).
class BufferedFileProxy final : public Filesystem::IOProxy {
  public:
    BufferedFileProxy(const std::string& path, uint64_t size)
        : IOProxy(path, Read), size_(size), buf_(1 << 20) {
        fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd_ < 0)
            m_mode = Closed;
    }
    ~BufferedFileProxy() override { close(); }
    const char* proxytype() const override { return "envtrace-buffered-file"; }
    void close() override {
        if (fd_ >= 0)
            ::close(fd_);
        fd_ = -1;
        m_mode = Closed;
    }
    size_t size() const override { return size_; }
    size_t read(void* buf, size_t size) override {
        char* dst = static_cast<char*>(buf);
        size_t done = 0;
        while (done < size) {
            if (m_pos >= buf_at_ && m_pos < buf_at_ + static_cast<int64_t>(buf_len_)) {
                const size_t at = static_cast<size_t>(m_pos - buf_at_);
                const size_t n = std::min(size - done, buf_len_ - at);
                std::memcpy(dst + done, buf_.data() + at, n);
                m_pos += static_cast<int64_t>(n);
                done += n;
            } else if (size - done >= buf_.size()) {
                const size_t n = pread(dst + done, size - done, m_pos);
                m_pos += static_cast<int64_t>(n);
                done += n;
                break;
            } else {
                buf_at_ = m_pos;
                buf_len_ = pread(buf_.data(), buf_.size(), m_pos);
                if (buf_len_ == 0)
                    break;
            }
        }
        return done;
    }
    // Unbuffered, so that concurrent calls stay safe as IOProxy promises.
    size_t pread(void* buf, size_t size, int64_t offset) override {
        return pread_full(fd_, buf, size, offset);
    }
    size_t write(const void*, size_t) override { return 0; }
    size_t pwrite(const void*, size_t, int64_t) override { return 0; }

  private:
    int fd_ = -1;
    uint64_t size_;
    std::vector<char> buf_;
    int64_t buf_at_ = 0; // file offset of buf_[0]
    size_t buf_len_ = 0;
};

// What a Radiance texel (m, m, m, e) is worth per unit of m: 2^(e - 136), 0 for e = 0, as
// OpenImageIO's decoder has it. Its table holds decimal literals, three of which (e = 40, 223, 226
// in 2.4) are not exact powers of two; the scales are read back from it once, through a 256-texel
// image in memory, so that texels decoded here are bit for bit those it would give.
const std::array<float, 256>& rgbe_scales() {
    static const std::array<float, 256> scales = [] {
        std::array<float, 256> t;
        t[0] = 0.0f;
        for (int e = 1; e < 256; ++e)
            t[e] = std::ldexp(1.0f, e - 136);
        // One flat scanline (its first texel does not start with 2, 2) of (1, 1, 1, e).
        std::string file = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 256\n";
        for (int e = 0; e < 256; ++e)
            file += {'\1', '\1', '\1', static_cast<char>(e)};
        Filesystem::IOMemReader mem(file.data(), file.size());
        Filesystem::IOProxy* p = &mem;
        ImageSpec config, spec;
        config.attribute("oiio:ioproxy", TypeDesc::PTR, &p);
        std::vector<float> rgb(3 * 256);
        auto in = ImageInput::create("hdr");
        if (in && in->open("rgbe-scales.hdr", spec, config) && spec.width == 256 &&
            in->read_image(0, 0, 0, 3, TypeDesc::FLOAT, rgb.data()))
            for (int e = 0; e < 256; ++e)
                t[e] = rgb[3 * e];
        (void)OIIO::geterror();
        return t;
    }();
    return scales;
}

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

bool starts_with(const std::string& path, const char* magic) {
    char head[8] = {};
    const size_t n = std::strlen(magic);
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f)
        return false;
    const bool ok = std::fread(head, 1, n, f) == n && std::memcmp(head, magic, n) == 0;
    std::fclose(f);
    return ok;
}

// A grey or colour PNM's maxval (P2, P3, P5, P6) must be 1..65535: OpenImageIO reads 0 as
// "every value is full scale", and an all-black file rendered as a white furnace.
void check_pnm_maxval(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f)
        return;
    char head[512] = {};
    const size_t n = std::fread(head, 1, sizeof head - 1, f);
    std::fclose(f);
    if (n < 2 || head[0] != 'P' || head[1] == '\0' || !std::strchr("2356", head[1]))
        return;
    // Three numbers after the magic (width, height, maxval), '#' comments to the line's end.
    long values[3] = {};
    size_t at = 2;
    for (int k = 0; k < 3; ++k) {
        for (;;) {
            while (at < n && std::isspace(static_cast<unsigned char>(head[at])))
                ++at;
            if (at < n && head[at] == '#') {
                while (at < n && head[at] != '\n')
                    ++at;
                continue;
            }
            break;
        }
        if (at >= n || !std::isdigit(static_cast<unsigned char>(head[at])))
            return; // not a header we can read: the library's own checks answer
        values[k] = std::strtol(head + at, nullptr, 10);
        while (at < n && std::isdigit(static_cast<unsigned char>(head[at])))
            ++at;
    }
    if (values[2] < 1 || values[2] > 65535)
        throw Error(path + ": PNM header: maxval " + std::to_string(values[2]) +
                    " is not in 1..65535");
}

// The lines of a Radiance header, from its first 64 kB, up to the blank line that ends it.
std::vector<std::string> radiance_header(const std::string& path) {
    std::vector<std::string> lines;
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f)
        return lines;
    std::string head(65536, '\0');
    head.resize(std::fread(&head[0], 1, head.size(), f));
    std::fclose(f);
    for (size_t at = 0; at < head.size();) {
        size_t end = head.find('\n', at);
        end = end == std::string::npos ? head.size() : end;
        if (end == at)
            break;
        lines.push_back(head.substr(at, end - at));
        at = end + 1;
    }
    return lines;
}

// The FORMAT= value ("" when absent): OpenImageIO reports an XYZE file as having no FORMAT.
std::string radiance_format(const std::vector<std::string>& header) {
    for (const std::string& line : header)
        if (line.rfind("FORMAT=", 0) == 0)
            return line.substr(7, line.find_last_not_of(" \t\r") - 6);
    return "";
}

// The product of the EXPOSURE= values, which Radiance says were applied to the stored pixels
// (radiance = pixel / exposure). Read as stored, as OpenImageIO and Blender read such files,
// and said when it is not 1.
void warn_radiance_exposure(const std::string& path, const std::vector<std::string>& header) {
    double exposure = 1.0;
    for (const std::string& line : header)
        if (line.rfind("EXPOSURE=", 0) == 0)
            exposure *= std::strtod(line.c_str() + 9, nullptr);
    if (exposure != 1.0) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", exposure);
        warn(path + ": the header's EXPOSURE (" + buf +
             ") is not applied: pixels are read as stored (radiance would be pixels / exposure; "
             "set the map's intensity to undo it)");
    }
}

// "R, G" (at most 8 names) for messages.
std::string channel_list(const ImageSpec& spec) {
    std::string out;
    for (int c = 0; c < spec.nchannels && c < 8; ++c)
        out += (c ? ", " : "") + spec.channelnames[static_cast<size_t>(c)];
    return out + (spec.nchannels > 8 ? ", ..." : "");
}

// Files whose stored pixels are not the picture as shown: turned (an orientation other than
// "normal": Radiance's "+Y H +X W", EXIF's rotations) or covering another window than the one
// shown (an EXR's data window inside or around its display window). Read as stored, a map would
// light the scene upside down, mirrored or stretched without a word; refused instead, with the
// command that writes the picture as shown.
void check_upright_and_whole(const std::string& path, const ImageSpec& spec, bool exr) {
    // What the stored pixels need to be shown upright (EXIF's orientations 2-8; 0, which some
    // cameras write, means unspecified: as stored).
    static const char* const needs[] = {"",
                                        "",
                                        "flipping horizontally",
                                        "turning 180 degrees",
                                        "flipping vertically (stored bottom-up)",
                                        "transposing",
                                        "turning 90 degrees clockwise",
                                        "transversing",
                                        "turning 90 degrees counter-clockwise"};
    const int o = spec.get_int_attribute("Orientation", 1);
    if (o != 1 && o != 0)
        throw Error(path + ": its pixels need " +
                    (o >= 2 && o <= 8 ? needs[o] : "an unknown reorientation") +
                    " to be upright (orientation " + std::to_string(o) +
                    "), which envtrace does not apply; write it upright first, e.g. oiiotool \"" +
                    path + "\" --reorient -o upright" + lower_extension(path));
    // Only OpenEXR separates the two windows (a PNG's oFFs offset, which OpenImageIO reports as
    // a data window off a display window at 0, places the picture on a page: it is the picture).
    const bool full_known = exr && spec.full_width > 0 && spec.full_height > 0;
    if (full_known && (spec.x != spec.full_x || spec.y != spec.full_y ||
                       spec.width != spec.full_width || spec.height != spec.full_height)) {
        auto window = [](int w, int h, int x, int y) {
            return std::to_string(w) + "x" + std::to_string(h) + (x >= 0 ? "+" : "") +
                   std::to_string(x) + (y >= 0 ? "+" : "") + std::to_string(y);
        };
        throw Error(path + ": its pixels (data window " +
                    window(spec.width, spec.height, spec.x, spec.y) +
                    ") are not its picture (display window " +
                    window(spec.full_width, spec.full_height, spec.full_x, spec.full_y) +
                    "); write the picture as shown first, e.g. oiiotool \"" + path +
                    "\" --croptofull -o whole" + lower_extension(path));
    }
}

// An image OpenImageIO reads, decoded a band of rows at a time.
struct OiioSource final : RowSource {
    std::unique_ptr<BufferedFileProxy> proxy; // outlives `in`, which reads through it
    std::unique_ptr<ImageInput> in;
    ImageSpec spec;
    int idx[3] = {0, 0, 0}; // the channels that become R, G, B
    int lo = 0, hi = 0;     // the range of channels decoded
    bool direct = false;    // float R, G, B adjacent: decoded straight into the texels
    bool decode_srgb = false;
    bool row_by_row = false;            // scanlines one at a time (TIFF MinIsWhite, F8)
    std::vector<unsigned char> scratch; // one band of the decoded channels otherwise
    std::unique_ptr<RgbeDecoder> rgbe;  // Radiance pixels, decoded here

    OiioSource(const std::string& path, uint64_t file_bytes, bool colour);
    int width() const override { return spec.width; }
    int height() const override { return spec.height; }
    int band_rows() const override;
    void read_rows(const std::string& path, int y0, int y1, float* dst) override;
    void finish() override { in->close(); }
};

OiioSource::OiioSource(const std::string& path, uint64_t file_bytes, bool colour) {
    // PNG, TIFF, TGA, ... colour as stored: OpenImageIO would otherwise multiply it by an
    // unassociated alpha, and a map's texels are radiance whatever its alpha says.
    ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    if (starts_with(path, "\x76\x2f\x31\x01")) { // OpenEXR, whatever the file is called
        // Every header walked before OpenEXR allocates what it claims (F10, F11), and the first
        // part's size checked against the budget before OpenEXR sizes its tables by it.
        const ExrHeaderInfo exr = check_exr_header(path, file_bytes);
        check_declared_size(path, exr.width, exr.height, 1, exr.stored_bytes, file_bytes);
    }
    check_pnm_maxval(path);
    if (starts_with(path, "#?")) { // Radiance HDR, read through our buffered proxy
        const std::vector<std::string> header = radiance_header(path);
        warn_radiance_exposure(path, header);
        if (radiance_format(header) == "32-bit_rle_xyze")
            throw Error(path + ": Radiance XYZE pixels (CIE XYZ) are not read; write the map as "
                               "RGBE (Radiance's ra_xyze -r IN OUT) or as OpenEXR");
        proxy = std::make_unique<BufferedFileProxy>(path, file_bytes);
        Filesystem::IOProxy* p = proxy.get();
        ImageSpec hdr_config = config;
        hdr_config.attribute("oiio:ioproxy", TypeDesc::PTR, &p);
        in = ImageInput::create("hdr");
        ImageSpec opened;
        if (!proxy->opened() || !in || !in->supports("ioproxy") ||
            !in->open(path, opened, hdr_config)) {
            in.reset(); // left to the general open below, which tries every reader
            proxy.reset();
            (void)OIIO::geterror();
        } else {
            // The header read, the proxy stands at the first scanline.
            rgbe = std::make_unique<RgbeDecoder>(path, proxy->tell(), opened.width);
            if (!rgbe->opened())
                rgbe.reset();
        }
    }
    if (!in)
        in = ImageInput::open(path, &config);
    if (!in)
        throw Error(path + ": cannot read image: " + one_line(OIIO::geterror()));
    spec = in->spec();
    const int w = spec.width, h = spec.height, nch = spec.nchannels;
    if (nch <= 0)
        throw Error(path + ": image has no channels");
    if (spec.deep)
        throw Error(path + ": deep images are not supported");
    check_declared_size(path, w, h, spec.depth, spec.image_bytes(true), file_bytes);
    const bool exr = std::string(in->format_name()) == "openexr";
    check_upright_and_whole(path, spec, exr);

    // Which channels become R, G, B.
    idx[1] = nch > 1 ? 1 : 0;
    idx[2] = nch > 2 ? 2 : 0;
    if (nch == 2)
        idx[1] = idx[2] = 0; // grey + alpha
    int r = spec.channelindex("R"), g = spec.channelindex("G"), b = spec.channelindex("B");
    // A layered EXR's colour (Blender's "Image.R", "Image.G", "Image.B"): the first layer that
    // has all three. EXR stores channels sorted by name, so the first three in file order were B,
    // G and R: the map's colours swapped without a word.
    if (exr && !(r >= 0 && g >= 0 && b >= 0))
        for (int c = 0; c < nch; ++c) {
            const std::string& n = spec.channelnames[static_cast<size_t>(c)];
            if (n.size() < 2 || n.compare(n.size() - 2, 2, ".R"))
                continue;
            const std::string layer = n.substr(0, n.size() - 1);
            const int lg = spec.channelindex(layer + "G"), lb = spec.channelindex(layer + "B");
            if (lg >= 0 && lb >= 0) {
                r = c;
                g = lg;
                b = lb;
                break;
            }
        }
    if (r >= 0 && g >= 0 && b >= 0) {
        idx[0] = r;
        idx[1] = g;
        idx[2] = b;
    }
    if (exr) {
        // An EXR names what its channels hold: one without colour or luminance names (depth,
        // alpha, XYZ, a vector) is read as colour from the first channels, and said so.
        const int y = spec.channelindex("Y");
        if (!(r >= 0 && g >= 0 && b >= 0) && r < 0 && g < 0 && b < 0) {
            if (y >= 0 && nch > 1 && spec.channelindex("X") < 0) {
                idx[0] = idx[1] = idx[2] = y; // luminance with others (alpha): grey from Y
            } else if (y < 0 || nch > 1) {
                std::string used;
                for (int k = 0; k < (nch > 2 ? 3 : 1); ++k)
                    used += (k ? ", " : "") + spec.channelnames[static_cast<size_t>(idx[k])];
                warn(path + ": no channels named as colour (R, G, B)" +
                     (y < 0 ? " or luminance (Y)" : "") + " among " + channel_list(spec) +
                     "; read " + used + " as " + (nch > 2 ? "red, green and blue" : "grey"));
            }
        }
        for (int k = 0; k < 3; ++k) {
            const TypeDesc t = spec.channelformat(idx[k]);
            if (t.basetype == TypeDesc::UINT32 || t.basetype == TypeDesc::INT32) {
                warn(path + ": channel '" + spec.channelnames[static_cast<size_t>(idx[k])] +
                     "' holds integers (an EXR's ids, not light); read scaled to [0, 1]");
                break;
            }
        }
        // A multi-part EXR: the first part is read, and said (a render's passes may come first).
        if (in->seek_subimage(1, 0)) {
            int parts = 2;
            while (parts < 64 && in->seek_subimage(parts, 0))
                ++parts;
            warn(path + ": " + std::to_string(parts) + (parts == 64 ? " or more" : "") +
                 " parts; the first (channels " + channel_list(spec) +
                 ") is read, the others ignored");
            if (!in->seek_subimage(0, 0))
                throw Error(path + ": cannot read image: " + one_line(in->geterror()));
        }
    }
    // An EXR's channels named as colour but not all three ("R, G"): read as grey from the first,
    // which is not the picture -- said once, not silently. (Other readers name unnamed channels
    // R, G, ... themselves: a grey + alpha TIFF would read as "R, G".)
    if (exr && !(r >= 0 && g >= 0 && b >= 0) && (g >= 0 || b >= 0))
        warn(path + ": has colour channels but not all of R, G and B (" + channel_list(spec) +
             "); read as grey from channel '" + spec.channelnames[static_cast<size_t>(idx[0])] +
             "'");
    lo = std::min({idx[0], idx[1], idx[2]});
    hi = std::max({idx[0], idx[1], idx[2]}) + 1;
    const std::string cs = spec.get_string_attribute("oiio:ColorSpace");
    const bool integer =
        spec.format.basetype == TypeDesc::UINT8 || spec.format.basetype == TypeDesc::UINT16;
    decode_srgb = colour && integer && cs != "Linear" && cs != "linear";
    direct = spec.tile_width == 0 && spec.format == TypeDesc::FLOAT &&
             spec.channelformats.empty() && idx[0] == lo && idx[1] == lo + 1 && idx[2] == lo + 2;
    // OpenImageIO 2.4's TIFF reader decodes a range of whole strips itself (zip, 8 or 16 bits,
    // contiguous channels) and then, for PhotometricInterpretation MinIsWhite (0), inverts
    // nchannels times too many values per strip, past the end of the buffer: a 191-byte file
    // crashed the CLI (fuzz finding F8). Single scanlines go through libtiff's scanline path,
    // which inverts the right count, so such files are read a row at a time.
    row_by_row = spec.tile_width == 0 && nch > 1 && std::string(in->format_name()) == "tiff" &&
                 spec.get_int_attribute("tiff:PhotometricInterpretation", -1) == 0;
}

int OiioSource::band_rows() const {
    // EXR in whole compression blocks (DWAB's 256 lines are the most), tiles and TIFF strips
    // whole, so that no block is decoded twice; other formats in bands of about 4 MB of texels,
    // which the caller then sanitises while they are still in cache.
    const int unit = spec.tile_width > 0 ? std::max(1, spec.tile_height)
                                         : spec.get_int_attribute("tiff:RowsPerStrip", 0);
    const int64_t row_bytes = 3 * sizeof(float) * static_cast<int64_t>(spec.width);
    int rows = std::string(in->format_name()) == "openexr"
                   ? 256
                   : static_cast<int>(std::clamp<int64_t>((4 << 20) / row_bytes, 1, 256));
    if (unit > 0 && unit <= spec.height)
        rows = (rows + unit - 1) / unit * unit;
    // At most 64 MB of texels a band (whole blocks where they fit; a 16384-wide map keeps its
    // 256-row bands): the reader touches memory a band ahead of the data, so a header that
    // declares a very wide image its file cannot hold (a 25 kB EXR claiming 1048640x32, one
    // 403 MB band) fails having touched one band, not the whole image (F7's class).
    const int max_rows = static_cast<int>(std::max<int64_t>(1, (int64_t(64) << 20) / row_bytes));
    if (rows > max_rows)
        rows = unit > 0 && max_rows >= unit ? max_rows / unit * unit : max_rows;
    return std::max(1, std::min(rows, spec.height));
}

void OiioSource::read_rows(const std::string& path, int y0, int y1, float* dst) {
    if (row_by_row && y1 - y0 > 1) {
        for (int y = y0; y < y1; ++y)
            read_rows(path, y, y + 1, dst + static_cast<size_t>(y - y0) * spec.width * 3);
        return;
    }
    const int w = spec.width, rows = y1 - y0;
    const int ybegin = spec.y + y0, yend = spec.y + y1;
    const stride_t xstride = 3 * sizeof(float), ystride = xstride * w;
    auto fail = [&] { throw Error(path + ": cannot decode image: " + one_line(in->geterror())); };
    if (rgbe) {
        const std::string err = rgbe->read_rows(y0, y1, dst);
        if (!err.empty())
            throw Error(path + ": cannot decode image: " + err);
    } else if (direct) {
        // Native float pixels are the texels: no conversion, no temporary (read_scanlines would
        // allocate and fill a 64 MB buffer per call, then copy).
        if (!in->read_native_scanlines(0, 0, ybegin, yend, spec.z, lo, lo + 3, dst))
            fail();
    } else if (spec.tile_width > 0) {
        // Whole rows of tiles come converted to float; the rows asked for are copied out.
        const int th = std::max(1, spec.tile_height), n = hi - lo;
        const int t0 = y0 / th * th, t1 = std::min(spec.height, (y1 + th - 1) / th * th);
        scratch.resize(static_cast<size_t>(w) * (t1 - t0) * n * sizeof(float));
        const float* band = reinterpret_cast<float*>(scratch.data());
        if (!in->read_tiles(0, 0, spec.x, spec.x + w, spec.y + t0, spec.y + t1, spec.z, spec.z + 1,
                            lo, hi, TypeDesc::FLOAT, scratch.data()))
            fail();
        band += static_cast<size_t>(y0 - t0) * w * n;
        for (size_t p = 0, np = static_cast<size_t>(w) * rows; p < np; ++p)
            for (int c = 0; c < 3; ++c)
                dst[3 * p + c] = band[n * p + (idx[c] - lo)];
    } else {
        // Native pixels of channels [lo, hi) into the band buffer, then converted per channel
        // (channels may differ in type) into the RGB stride.
        const stride_t pixel = static_cast<stride_t>(spec.pixel_bytes(lo, hi, true));
        scratch.resize(static_cast<size_t>(pixel) * w * rows);
        if (!in->read_native_scanlines(0, 0, ybegin, yend, spec.z, lo, hi, scratch.data()))
            fail();
        for (int c = 0; c < 3; ++c) {
            const int ch = idx[c];
            const TypeDesc type = spec.channelformat(ch);
            const unsigned char* src = scratch.data() + spec.pixel_bytes(lo, ch, true);
            if (!convert_image(1, w, rows, 1, src, type, pixel, pixel * w, AutoStride, dst + c,
                               TypeDesc::FLOAT, xstride, ystride, AutoStride))
                throw Error(path + ": cannot convert pixels of type " + type.c_str());
        }
    }
    if (decode_srgb)
        for (size_t i = 0, n = static_cast<size_t>(w) * rows * 3; i < n; ++i)
            dst[i] = srgb_to_linear(dst[i]);
}

} // namespace

bool library_available() {
    return true;
}

std::unique_ptr<RowSource> open_with_library(const std::string& path, uint64_t file_bytes,
                                             bool colour) {
    return std::make_unique<OiioSource>(path, file_bytes, colour);
}

// The bytes into `file`, every write() and the close() checked (a full disk is an error).
static void write_bytes_checked(const std::string& path, const std::string& file,
                                const std::vector<unsigned char>& bytes) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    auto fail = [&](int err) { throw Error(path + ": cannot write: " + std::strerror(err)); };
    if (fd < 0)
        fail(errno);
    size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            const int err = n < 0 ? errno : ENOSPC;
            ::close(fd);
            fail(err);
        }
        done += static_cast<size_t>(n);
    }
    if (::close(fd) != 0)
        fail(errno);
}

void check_library_writer(const std::string& path, const std::string& ext) {
    auto out = ImageOutput::create(ext.substr(1));
    if (!out)
        throw Error(path + ": cannot write: this OpenImageIO build has no writer for '" + ext +
                    "'");
}

void write_with_library(const std::string& path, const std::string& file, int width, int height,
                        int channels, const float* pixels, bool floating,
                        const std::vector<std::pair<std::string, std::string>>& attributes,
                        const std::vector<std::string>* names) {
    auto out = ImageOutput::create(file);
    if (!out)
        throw Error(path + ": cannot write: " + one_line(OIIO::geterror()));
    ImageSpec spec(width, height, channels, floating ? TypeDesc::FLOAT : TypeDesc::UINT8);
    if (lower_extension(path) == ".exr")
        spec.attribute("compression", "zip");
    if (names) {
        spec.channelnames = *names;
        spec.alpha_channel = -1; // no channel is alpha: the layers are alpha-free
        spec.z_channel = -1;
        for (int c = 0; c < channels; ++c)
            if ((*names)[static_cast<size_t>(c)] == "Z")
                spec.z_channel = c;
    }
    for (const auto& [k, v] : attributes)
        spec.attribute(k, v);
    // 8-bit previews are encoded in memory and written here: OpenImageIO's PNG writer reports
    // no error when the disk fills (libpng's fwrite results go unchecked), and committed a
    // truncated preview with exit status 0. The float formats' writers report it.
    std::vector<unsigned char> encoded;
    Filesystem::IOVecOutput memory(encoded);
    const bool in_memory = !floating && out->supports("ioproxy") && out->set_ioproxy(&memory);
    const bool ok = out->open(in_memory ? path : file, spec) &&
                    out->write_image(TypeDesc::FLOAT, pixels) && out->close();
    if (!ok)
        throw Error(path + ": cannot write: " + one_line(out->geterror()));
    if (in_memory)
        write_bytes_checked(path, file, encoded);
}

} // namespace et::image_detail
