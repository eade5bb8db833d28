#include "image/image_io.h"

#include "util/error.h"

#include "util/checked_size.h"
#include "util/file_check.h"
#include "util/json_file.h"
#include "util/output_batch.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <unistd.h>

namespace fs = std::filesystem;
OIIO_NAMESPACE_USING

namespace et {
namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    return ext;
}

std::string one_line(std::string s) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    while (!s.empty() && s.back() == ' ')
        s.pop_back();
    return s.empty() ? "unknown error" : s;
}

} // namespace

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

namespace {

// The declared size of an image against what can be held and indexed, before any pixel is read:
// a 60-byte file claiming 25000x12500 pixels is refused without allocating anything.
void check_declared_size(const std::string& path, int64_t w, int64_t h, int64_t depth,
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

// PFM ("PF" colour, "Pf" grey; width height; scale, negative for little-endian; rows of floats
// from the bottom up), read directly into the texels.
RgbImage read_pfm(const std::string& path, uint64_t file_bytes) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f)
        throw Error(path + ": cannot open: " + std::strerror(errno));
    struct Closer {
        std::FILE* f;
        ~Closer() { std::fclose(f); }
    } closer{f};
    // The header: three whitespace-separated tokens after the magic, then one whitespace byte.
    std::string tokens[4];
    for (int t = 0; t < 4; ++t) {
        int c = std::fgetc(f);
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
    const bool colour = tokens[0] == "PF";
    if (!colour && tokens[0] != "Pf")
        throw Error(path + ": not a PFM file (it starts with '" + excerpt(tokens[0], 8) +
                    "', not 'PF' or 'Pf')");
    char* end = nullptr;
    const long long w = std::strtoll(tokens[1].c_str(), &end, 10);
    const bool w_ok = *end == 0 && !tokens[1].empty();
    const long long h = std::strtoll(tokens[2].c_str(), &end, 10);
    const bool h_ok = *end == 0 && !tokens[2].empty();
    const double scale = std::strtod(tokens[3].c_str(), &end);
    if (!w_ok || !h_ok || *end != 0 || tokens[3].empty() || !std::isfinite(scale) || scale == 0.0)
        throw Error(path + ": corrupt PFM header ('" + tokens[1] + " " + tokens[2] + " " +
                    tokens[3] + "': expected width, height and a non-zero scale)");
    const int channels = colour ? 3 : 1;
    const uint64_t header = static_cast<uint64_t>(std::ftell(f));
    const uint64_t stored =
        w > 0 && h > 0 ? checked_mul(checked_mul(w, h, path), 4 * channels, path) : 0;
    check_declared_size(path, w, h, 1, stored, file_bytes);
    if (file_bytes < header + stored)
        throw Error(path + ": truncated PFM: " + std::to_string(w) + "x" + std::to_string(h) +
                    " needs " + std::to_string(stored) + " bytes of pixels, the file has " +
                    std::to_string(file_bytes - header));
    RgbImage img;
    img.width = static_cast<int>(w);
    img.height = static_cast<int>(h);
    img.rgb.resize(static_cast<size_t>(w) * h * 3);
    const bool swap = scale > 0.0; // big-endian data on this little-endian host
    std::vector<float> grey(colour ? 0 : w);
    for (long long y = h - 1; y >= 0; --y) {
        float* row = img.at(0, static_cast<int>(y));
        float* dst = colour ? row : grey.data();
        const size_t n = static_cast<size_t>(w) * channels;
        if (std::fread(dst, sizeof(float), n, f) != n)
            throw Error(path + ": truncated PFM (read error in the pixel data)");
        if (swap)
            for (size_t i = 0; i < n; ++i) {
                uint32_t u;
                std::memcpy(&u, dst + i, 4);
                u = __builtin_bswap32(u);
                std::memcpy(dst + i, &u, 4);
            }
        if (!colour)
            for (long long x = 0; x < w; ++x)
                row[3 * x] = row[3 * x + 1] = row[3 * x + 2] = grey[x];
    }
    return img;
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

} // namespace

RgbImage read_rgb_image(const std::string& path) {
    const uint64_t file_bytes = check_regular_file(path, kMaxImageBytes, "image");
    if (file_bytes == 0)
        throw Error(path + ": file is empty (0 bytes)");
    if (lower_extension(path) == ".pfm")
        return read_pfm(path, file_bytes);

    auto in = ImageInput::open(path);
    if (!in)
        throw Error(path + ": cannot read image: " + one_line(OIIO::geterror()));
    const ImageSpec& spec = in->spec();
    const int w = spec.width, h = spec.height, nch = spec.nchannels;
    if (nch <= 0)
        throw Error(path + ": image has no channels");
    if (spec.deep)
        throw Error(path + ": deep images are not supported");
    check_declared_size(path, w, h, spec.depth, spec.image_bytes(true), file_bytes);

    // Which channels become R, G, B.
    int idx[3] = {0, nch > 1 ? 1 : 0, nch > 2 ? 2 : 0};
    if (nch == 2)
        idx[1] = idx[2] = 0; // grey + alpha
    int r = spec.channelindex("R"), g = spec.channelindex("G"), b = spec.channelindex("B");
    if (r >= 0 && g >= 0 && b >= 0) {
        idx[0] = r;
        idx[1] = g;
        idx[2] = b;
    }
    const std::string cs = spec.get_string_attribute("oiio:ColorSpace");
    const bool integer =
        spec.format.basetype == TypeDesc::UINT8 || spec.format.basetype == TypeDesc::UINT16;
    const bool decode_srgb = integer && cs != "Linear" && cs != "linear";

    // Decoded straight into the texels, channel by channel into the RGB stride (or R, G, B at
    // once when they are adjacent): one float copy of the image, no full-size temporary.
    RgbImage img;
    img.width = w;
    img.height = h;
    img.rgb.resize(static_cast<size_t>(w) * h * 3);
    const stride_t xstride = 3 * sizeof(float);
    auto read_channels = [&](int first, int count, float* dst) {
        if (!in->read_image(0, 0, first, first + count, TypeDesc::FLOAT, dst, xstride))
            throw Error(path + ": cannot decode image: " + one_line(in->geterror()));
    };
    if (idx[1] == idx[0] + 1 && idx[2] == idx[0] + 2) {
        read_channels(idx[0], 3, img.rgb.data());
    } else {
        for (int c = 0; c < 3; ++c) {
            if (c > 0 && idx[c] == idx[0]) {
                for (size_t p = 0, n = img.rgb.size() / 3; p < n; ++p)
                    img.rgb[3 * p + c] = img.rgb[3 * p];
                continue;
            }
            read_channels(idx[c], 1, img.rgb.data() + c);
        }
    }
    in->close();
    if (decode_srgb)
        for (float& v : img.rgb)
            v = srgb_to_linear(v);
    return img;
}

void check_writable_format(const std::string& path) {
    fs::path target(path);
    fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    std::error_code ec;
    const std::string ext = lower_extension(path);
    if (!is_float_image_extension(path) && ext != ".png" && ext != ".jpg" && ext != ".jpeg")
        throw Error(path + ": unsupported output format '" + excerpt(ext, 16) +
                    "' (use .exr, .hdr, .pfm, .png or .jpg)");
    if (fs::is_directory(target, ec))
        throw Error(path + ": cannot write: it is a folder");
    if (!fs::is_directory(dir, ec))
        throw Error(path + ": cannot write: folder '" + dir.string() + "' does not exist");
    if (ext == ".pfm")
        return; // written here, not by OpenImageIO
    auto out = ImageOutput::create(ext.substr(1));
    if (!out)
        throw Error(path + ": cannot write: this OpenImageIO build has no writer for '" + ext +
                    "'");
}

namespace {

// Writes the whole image to `file`; messages name `path`, the output it becomes.
void write_image_file(const std::string& path, const std::string& file, int width, int height,
                      int channels, const std::vector<float>& pixels,
                      const std::vector<std::pair<std::string, std::string>>& attributes) {
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

    if (ext == ".pfm") {
        const std::string err = write_pfm(file, width, height, channels, *data);
        if (!err.empty())
            throw Error(path + ": cannot write: " + err);
        return;
    }
    auto out = ImageOutput::create(file);
    if (!out)
        throw Error(path + ": cannot write: " + one_line(OIIO::geterror()));
    ImageSpec spec(width, height, channels, floating ? TypeDesc::FLOAT : TypeDesc::UINT8);
    if (ext == ".exr")
        spec.attribute("compression", "zip");
    for (const auto& [k, v] : attributes)
        spec.attribute(k, v);
    const bool ok = out->open(file, spec) &&
                    out->write_image(TypeDesc::FLOAT, data->data()) && out->close();
    if (!ok)
        throw Error(path + ": cannot write: " + one_line(out->geterror()));
}

} // namespace

void write_image(OutputBatch& batch, const std::string& path, int width, int height,
                 int channels, const std::vector<float>& pixels,
                 const std::vector<std::pair<std::string, std::string>>& attributes) {
    check_writable_format(path);
    batch.write(path, [&](const std::string& file) {
        write_image_file(path, file, width, height, channels, pixels, attributes);
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
