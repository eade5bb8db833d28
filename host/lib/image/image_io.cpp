#include "image/image_io.h"

#include "util/error.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
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

RgbImage read_rgb_image(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec))
        throw Error(path + ": no such file");
    if (fs::is_directory(path, ec))
        throw Error(path + ": is a directory, not an image");
    if (fs::file_size(path, ec) == 0)
        throw Error(path + ": file is empty (0 bytes)");

    auto in = ImageInput::open(path);
    if (!in)
        throw Error(path + ": cannot read image: " + one_line(OIIO::geterror()));
    const ImageSpec& spec = in->spec();
    const int w = spec.width, h = spec.height, nch = spec.nchannels;
    if (w <= 0 || h <= 0 || nch <= 0)
        throw Error(path + ": image has no pixels (" + std::to_string(w) + "x" + std::to_string(h) +
                    ", " + std::to_string(nch) + " channels)");
    if (static_cast<double>(w) * h * nch > 2.0e9)
        throw Error(path + ": image too large (" + std::to_string(w) + "x" + std::to_string(h) +
                    ")");

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

    std::vector<float> px(static_cast<size_t>(w) * h * nch);
    if (!in->read_image(0, 0, 0, nch, TypeDesc::FLOAT, px.data()))
        throw Error(path + ": cannot decode image: " + one_line(in->geterror()));
    in->close();

    std::string cs = spec.get_string_attribute("oiio:ColorSpace");
    bool integer =
        spec.format.basetype == TypeDesc::UINT8 || spec.format.basetype == TypeDesc::UINT16;
    bool decode_srgb = integer && cs != "Linear" && cs != "linear";

    RgbImage img;
    img.width = w;
    img.height = h;
    img.rgb.resize(static_cast<size_t>(w) * h * 3);
    for (size_t p = 0, n = static_cast<size_t>(w) * h; p < n; ++p)
        for (int c = 0; c < 3; ++c) {
            float v = px[p * nch + idx[c]];
            img.rgb[3 * p + c] = decode_srgb ? srgb_to_linear(v) : v;
        }
    return img;
}

void write_image(const std::string& path, int width, int height, int channels,
                 const std::vector<float>& pixels,
                 const std::vector<std::pair<std::string, std::string>>& attributes) {
    fs::path target(path);
    fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw Error(path + ": cannot write: folder '" + dir.string() + "' does not exist");
    std::string ext = lower_extension(path);
    bool floating = is_float_image_extension(path);
    if (!floating && ext != ".png" && ext != ".jpg" && ext != ".jpeg")
        throw Error(path + ": unsupported output format '" + ext +
                    "' (use .exr, .hdr, .pfm, .png or .jpg)");

    fs::path tmp = dir / ("." + target.stem().string() + ".tmp" + std::to_string(getpid()) + ext);
    auto out = ImageOutput::create(tmp.string());
    if (!out)
        throw Error(path + ": cannot write: " + one_line(OIIO::geterror()));
    ImageSpec spec(width, height, channels, floating ? TypeDesc::FLOAT : TypeDesc::UINT8);
    if (ext == ".exr")
        spec.attribute("compression", "zip");
    for (const auto& [k, v] : attributes)
        spec.attribute(k, v);
    bool ok = out->open(tmp.string(), spec) && out->write_image(TypeDesc::FLOAT, pixels.data()) &&
              out->close();
    if (!ok) {
        std::string msg = one_line(out->geterror());
        fs::remove(tmp, ec);
        throw Error(path + ": cannot write: " + msg);
    }
    fs::rename(tmp, target, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw Error(path + ": cannot write: " + ec.message());
    }
}

} // namespace et
