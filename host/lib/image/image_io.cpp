#include "image/image_io.h"
#include "image/image_library.h"

#include "util/error.h"

#include "util/checked_size.h"
#include "util/file_check.h"
#include "util/json_file.h"
#include "util/output_batch.h"
#include "util/prefault.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <unistd.h>

namespace fs = std::filesystem;

namespace et {
namespace image_detail {

std::string one_line(std::string s) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    while (!s.empty() && s.back() == ' ')
        s.pop_back();
    // The library gave no reason (OpenImageIO's PNM reader on a truncated file says nothing).
    return s.empty() ? "the decoder gave no reason; the file may be truncated or damaged" : s;
}

} // namespace image_detail

using image_detail::check_declared_size;
using image_detail::one_line;
using image_detail::RowSource;

float srgb_to_linear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float v) {
    if (!(v > 0.0f))
        return 0.0f;
    if (v >= 1.0f)
        return 1.0f;
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

bool is_float_image_extension(const std::string& path) {
    std::string ext = lower_extension(path);
    return ext == ".exr" || ext == ".hdr" || ext == ".pfm";
}

// A 60-byte file claiming 25000x12500 pixels is refused without allocating anything.
void image_detail::check_declared_size(const std::string& path, int64_t w, int64_t h, int64_t depth,
                                       uint64_t stored_bytes, uint64_t file_bytes) {
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    if (w <= 0 || h <= 0)
        throw Error(path + ": image has no pixels (" + size + ")");
    if (depth > 1)
        throw Error(path + ": a volume image (depth " + std::to_string(depth) +
                    ") is not a lat-long map");
    const uint64_t pixels = checked_mul(w, h, path);
    const uint64_t bytes = checked_mul(pixels, 3 * sizeof(float), path);
    if (bytes > kMaxBufferBytes)
        throw Error(path + ": image of " + size + " pixels needs " + byte_text(bytes) +
                    " as float RGB, more than the memory budget of " + byte_text(kMaxBufferBytes));
    if (3 * pixels > kMaxDeviceIndex)
        throw Error(path + ": image of " + size +
                    " pixels has more texels than the device indexes");
    // No format these files come in compresses pixels more than about 1000:1 (deflate's bound);
    // a header claiming far more than its file holds is corrupt or truncated.
    if (file_bytes > 0 && stored_bytes / file_bytes > 100000)
        throw Error(path + ": header claims " + size + " pixels (" + byte_text(stored_bytes) +
                    ") but the file has only " + byte_text(file_bytes) + ": corrupt or truncated");
}

namespace {

// PFM ("PF" colour, "Pf" grey; width height; scale, negative for little-endian; rows of floats
// from the bottom up), read here a band of rows at a time.
struct PfmSource final : RowSource {
    struct Closer {
        void operator()(std::FILE* f) const { std::fclose(f); }
    };
    // Closed by its own destructor, so also when the constructor throws on a corrupt header (a
    // raw FILE* closed in ~PfmSource leaked one descriptor per refused file: fuzz finding F9).
    std::unique_ptr<std::FILE, Closer> file;
    int w = 0, h = 0;
    bool colour = false, swap = false;
    uint64_t header = 0; // bytes before the first pixel
    std::vector<float> grey;

    PfmSource(const std::string& path, uint64_t file_bytes);
    int width() const override { return w; }
    int height() const override { return h; }
    int band_rows() const override { return std::min(256, h); }
    void read_rows(const std::string& path, int y0, int y1, float* dst) override;
};

PfmSource::PfmSource(const std::string& path, uint64_t file_bytes)
    : file(std::fopen(path.c_str(), "rb")) {
    std::FILE* const f = file.get();
    if (!f)
        throw Error(path + ": cannot open: " + std::strerror(errno));
    // The header: three whitespace-separated tokens after the magic, then one whitespace byte.
    std::string tokens[4];
    int c = 0;
    for (int t = 0; t < 4; ++t) {
        c = std::fgetc(f);
        while (t > 0 && c != EOF && std::isspace(c))
            c = std::fgetc(f);
        while (c != EOF && !std::isspace(c) && tokens[t].size() < 32) {
            tokens[t].push_back(static_cast<char>(c));
            c = std::fgetc(f);
        }
        if (c == EOF || !std::isspace(c))
            throw Error(path + ": corrupt PFM header (expected 'PF' or 'Pf', width, height and "
                               "scale)");
    }
    colour = tokens[0] == "PF";
    if (!colour && tokens[0] != "Pf")
        throw Error(path + ": not a PFM file (it starts with '" + excerpt(tokens[0], 8) +
                    "', not 'PF' or 'Pf')");
    char* end = nullptr;
    const long long lw = std::strtoll(tokens[1].c_str(), &end, 10);
    const bool w_ok = *end == 0 && !tokens[1].empty();
    const long long lh = std::strtoll(tokens[2].c_str(), &end, 10);
    const bool h_ok = *end == 0 && !tokens[2].empty();
    const double scale = std::strtod(tokens[3].c_str(), &end);
    if (!w_ok || !h_ok || *end != 0 || tokens[3].empty() || !std::isfinite(scale) || scale == 0.0)
        throw Error(path + ": corrupt PFM header ('" + tokens[1] + " " + tokens[2] + " " +
                    tokens[3] + "': expected width, height and a non-zero scale)");
    const int channels = colour ? 3 : 1;
    header = static_cast<uint64_t>(std::ftell(f));
    const uint64_t stored =
        lw > 0 && lh > 0 ? checked_mul(checked_mul(lw, lh, path), 4 * channels, path) : 0;
    check_declared_size(path, lw, lh, 1, stored, file_bytes);
    // A header written with Windows line ends ("-1.0\r\n"): the pixels start after the '\n',
    // which the file's size confirms (read one byte early, every texel was garbage).
    if (c == '\r' && file_bytes == header + 1 + stored && std::fgetc(f) == '\n')
        header += 1;
    if (file_bytes > header + stored)
        warn(path + ": " + std::to_string(file_bytes - header - stored) +
             " bytes after the pixels are ignored (is the header's size right?)");
    if (file_bytes < header + stored)
        throw Error(path + ": truncated PFM: " + std::to_string(lw) + "x" + std::to_string(lh) +
                    " needs " + std::to_string(stored) + " bytes of pixels, the file has " +
                    std::to_string(file_bytes - header));
    w = static_cast<int>(lw);
    h = static_cast<int>(lh);
    swap = scale > 0.0; // big-endian data on this little-endian host
    grey.resize(colour ? 0 : w);
}

void PfmSource::read_rows(const std::string& path, int y0, int y1, float* dst) {
    const int channels = colour ? 3 : 1;
    const size_t n = static_cast<size_t>(w) * channels;
    for (int y = y0; y < y1; ++y) {
        float* row = dst + static_cast<size_t>(y - y0) * w * 3;
        float* in = colour ? row : grey.data();
        const uint64_t at = header + static_cast<uint64_t>(h - 1 - y) * n * sizeof(float);
        std::FILE* const f = file.get();
        if (fseeko(f, static_cast<off_t>(at), SEEK_SET) != 0 ||
            std::fread(in, sizeof(float), n, f) != n)
            throw Error(path + ": truncated PFM (read error in the pixel data)");
        if (swap)
            for (size_t i = 0; i < n; ++i) {
                uint32_t u;
                std::memcpy(&u, in + i, 4);
                u = __builtin_bswap32(u);
                std::memcpy(in + i, &u, 4);
            }
        if (!colour)
            for (int x = 0; x < w; ++x)
                row[3 * x] = row[3 * x + 1] = row[3 * x + 2] = grey[x];
    }
}

// Returns "" or what went wrong.
std::string write_pfm(const std::string& path, int width, int height, int channels,
                      const std::vector<float>& pixels) {
    errno = 0;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f)
        return std::strerror(errno);
    const bool colour = channels >= 3;
    bool ok = std::fprintf(f, "%s\n%d %d\n-1.0\n", colour ? "PF" : "Pf", width, height) > 0;
    std::vector<float> row(static_cast<size_t>(width) * (colour ? 3 : 1));
    for (int y = height - 1; y >= 0 && ok; --y) {
        const float* src = pixels.data() + static_cast<size_t>(y) * width * channels;
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < (colour ? 3 : 1); ++c)
                row[static_cast<size_t>(x) * (colour ? 3 : 1) + c] = src[x * channels + c];
        ok = std::fwrite(row.data(), sizeof(float), row.size(), f) == row.size();
    }
    int err = ok ? 0 : errno;
    if (std::fclose(f) != 0 && ok) {
        ok = false;
        err = errno;
    }
    return ok ? "" : err ? std::strerror(err) : "write failed";
}

// "PF" or "Pf" and a whitespace byte: a PFM file, whatever it is called (as OpenEXR's magic
// number makes an EXR file).
bool has_pfm_magic(const std::string& path) {
    unsigned char head[3] = {};
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f)
        return false;
    const bool read = std::fread(head, 1, 3, f) == 3;
    std::fclose(f);
    return read && head[0] == 'P' && (head[1] == 'F' || head[1] == 'f') && std::isspace(head[2]);
}

} // namespace

bool have_image_library() {
    return image_detail::library_available();
}

struct RgbImageReader::Impl {
    std::string path;
    std::unique_ptr<RowSource> source;
    int width = 0, height = 0, next = 0;
};

RgbImageReader::RgbImageReader(const std::string& path, bool colour)
    : impl_(std::make_unique<Impl>()) {
    impl_->path = path;
    const uint64_t file_bytes = check_regular_file(path, kMaxImageBytes, "image");
    if (file_bytes == 0)
        throw Error(path + ": file is empty (0 bytes)");
    if (lower_extension(path) == ".pfm" || has_pfm_magic(path))
        impl_->source = std::make_unique<PfmSource>(path, file_bytes);
    else
        impl_->source = image_detail::open_with_library(path, file_bytes, colour);
    impl_->width = impl_->source->width();
    impl_->height = impl_->source->height();
}

RgbImageReader::~RgbImageReader() = default;

int RgbImageReader::width() const {
    return impl_->width;
}

int RgbImageReader::height() const {
    return impl_->height;
}

int RgbImageReader::band_rows() const {
    return impl_->source->band_rows();
}

int RgbImageReader::read_rows(int rows, float* dst) {
    Impl& m = *impl_;
    const int y0 = m.next, y1 = std::min(m.height, y0 + std::max(0, rows));
    if (y1 <= y0)
        return 0;
    m.source->read_rows(m.path, y0, y1, dst);
    m.next = y1;
    if (m.next == m.height)
        m.source->finish();
    return y1 - y0;
}

RgbImage read_rgb_image(const std::string& path, bool colour) {
    RgbImageReader reader(path, colour);
    RgbImage img;
    img.width = reader.width();
    img.height = reader.height();
    // Reserved whole (address space only) and grown a band at a time as the file decodes: a
    // file that declares more pixels than it holds fails before that memory is touched (F7).
    const size_t row = static_cast<size_t>(img.width) * 3;
    img.rgb.reserve(row * img.height);
    const int band = reader.band_rows();
    for (int y = 0; y < img.height;) {
        grow_in_place(img.rgb, row * std::min(img.height, y + band));
        y += reader.read_rows(band, img.rgb.data() + row * y);
    }
    return img;
}

ImageChannels read_image_channels(const std::string& path) {
    ImageChannels out;
    const uint64_t file_bytes = check_regular_file(path, kMaxImageBytes, "image");
    if (file_bytes > 0 && !(lower_extension(path) == ".pfm" || has_pfm_magic(path)) &&
        image_detail::library_available()) {
        std::FILE* f = std::fopen(path.c_str(), "rb");
        unsigned char magic[4] = {};
        const bool exr = f && std::fread(magic, 1, 4, f) == 4 && magic[0] == 0x76 &&
                         magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01;
        if (f)
            std::fclose(f);
        if (exr) {
            out.pixels = image_detail::read_channels_with_library(path, file_bytes, out.width,
                                                                  out.height, out.names);
            return out;
        }
    }
    RgbImage rgb = read_rgb_image(path);
    out.width = rgb.width;
    out.height = rgb.height;
    out.names = {"R", "G", "B"};
    out.pixels = std::move(rgb.rgb);
    return out;
}

void check_writable_format(const std::string& path) {
    const fs::path target(path);
    std::error_code ec;
    const std::string ext = lower_extension(path);
    if (!is_float_image_extension(path) && ext != ".png" && ext != ".jpg" && ext != ".jpeg")
        throw Error(path + ": unsupported output format '" + excerpt(ext, 16) +
                    "' (use .exr, .hdr, .pfm, .png or .jpg)");
    if (fs::is_directory(target, ec))
        throw Error(path + ": cannot write: it is a folder");
    check_output_folder(path);
    if (ext != ".pfm") // PFM is written here, the rest by the library
        image_detail::check_library_writer(path, ext);
}

namespace {

// Writes the whole image to `file`; messages name `path`, the output it becomes.
// Half of the RGBE step of each pixel added to its positive components (see the caller).
void round_for_rgbe(std::vector<float>& px, int channels) {
    const int colour = std::min(channels, 3);
    for (size_t i = 0; i + channels <= px.size(); i += static_cast<size_t>(channels)) {
        float m = 0.0f;
        for (int c = 0; c < colour; ++c)
            m = std::max(m, px[i + c]);
        if (!(m > 1e-32f)) // the encoders write 0 below this
            continue;
        int e = 0;
        std::frexp(m, &e); // m = f 2^e, f in [0.5, 1): the step is 2^(e-8)
        float half = std::ldexp(1.0f, e - 9);
        if (m + half >= std::ldexp(1.0f, e)) // rounds up into the next exponent: a step twice
            half *= 2.0f;                    // as large for every component
        for (int c = 0; c < colour; ++c)
            if (px[i + c] > 0.0f)
                px[i + c] += half;
    }
}

void write_image_file(const std::string& path, const std::string& file, int width, int height,
                      int channels, const std::vector<float>& pixels,
                      const std::vector<std::pair<std::string, std::string>>& attributes,
                      const std::vector<std::string>* names = nullptr) {
    const std::string ext = lower_extension(path);
    const bool floating = is_float_image_extension(path);
    if (width <= 0 || height <= 0 || channels <= 0 ||
        pixels.size() < static_cast<size_t>(width) * height * channels)
        throw Error(path + ": cannot write: " + std::to_string(pixels.size()) + " values for a " +
                    std::to_string(width) + "x" + std::to_string(height) + "x" +
                    std::to_string(channels) + " image");

    // No output ever holds NaN or Inf: such values (a bug upstream) are written as 0, loudly.
    const std::vector<float>* data = &pixels;
    std::vector<float> finite;
    size_t bad = 0;
    for (float v : pixels)
        bad += !std::isfinite(v);
    if (bad) {
        finite = pixels;
        for (float& v : finite)
            v = std::isfinite(v) ? v : 0.0f;
        data = &finite;
        warn(path + ": " + std::to_string(bad) + " non-finite values written as 0");
    }
    // Radiance RGBE holds magnitudes below 2^128 (an 8-bit exponent): larger ones would wrap to
    // 0 in the encoder. They are written as the largest it holds, loudly.
    if (ext == ".hdr") {
        const float top = 255.0f / 256.0f * 0x1p127f;
        size_t over = 0;
        for (float v : *data)
            over += std::fabs(v) > top;
        if (over) {
            if (data != &finite) {
                finite = pixels;
                data = &finite;
            }
            for (float& v : finite)
                v = std::clamp(v, -top, top);
            warn(path + ": " + std::to_string(over) +
                 " values beyond Radiance RGBE's range (about 1.7e38) written as its largest");
        }
        // RGBE writers truncate each component to 8 bits under the pixel's shared exponent, and
        // the common readers (OpenImageIO, stb_image, Walter's rgbe.c: envtrace, Cycles, pbrt,
        // Mitsuba) decode without Radiance's +0.5: written as they were, values came back 0.28%
        // darker on average (never brighter). Half a step added first makes the truncation a
        // rounding to nearest for all of them.
        if (data != &finite) {
            finite = pixels;
            data = &finite;
        }
        round_for_rgbe(finite, channels);
    }

    if (ext == ".pfm") {
        const std::string err = write_pfm(file, width, height, channels, *data);
        if (!err.empty())
            throw Error(path + ": cannot write: " + err);
        return;
    }
    image_detail::write_with_library(path, file, width, height, channels, data->data(), floating,
                                     attributes, names);
}

} // namespace

void write_image(OutputBatch& batch, const std::string& path, int width, int height, int channels,
                 const std::vector<float>& pixels,
                 const std::vector<std::pair<std::string, std::string>>& attributes) {
    check_writable_format(path);
    batch.write(path, [&](const std::string& file) {
        write_image_file(path, file, width, height, channels, pixels, attributes);
    });
}

void write_image_channels(OutputBatch& batch, const std::string& path, int width, int height,
                          const std::vector<std::string>& names, const std::vector<float>& pixels,
                          const std::vector<std::pair<std::string, std::string>>& attributes) {
    check_writable_format(path);
    if (lower_extension(path) != ".exr")
        throw Error(path + ": named channels (AOV layers) need an OpenEXR output (.exr)");
    batch.write(path, [&](const std::string& file) {
        write_image_file(path, file, width, height, static_cast<int>(names.size()), pixels,
                         attributes, &names);
    });
}

void write_image(const std::string& path, int width, int height, int channels,
                 const std::vector<float>& pixels,
                 const std::vector<std::pair<std::string, std::string>>& attributes) {
    check_writable_format(path);
    OutputBatch batch({path});
    write_image(batch, path, width, height, channels, pixels, attributes);
    batch.commit();
}

} // namespace et
