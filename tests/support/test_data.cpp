#include "test_data.h"

#include "util/data_path.h"
#include "util/error.h"

#if ENVTRACE_TEST_OPENIMAGEIO
#include <OpenImageIO/imageio.h>
#endif

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace ett {

std::string data_dir() {
    std::vector<std::string> candidates = et::data_search_path();
    candidates.push_back(ENVTRACE_TEST_DATA_DIR);
    std::error_code ec;
    for (const auto& d : candidates)
        if (fs::is_directory(fs::path(d) / "envmaps", ec))
            return d;
    return "";
}

std::string data_file(const std::string& relative) {
    const std::string dir = data_dir();
    if (dir.empty())
        return "";
    fs::path p = fs::path(dir) / relative;
    std::error_code ec;
    return fs::exists(p, ec) ? p.string() : "";
}

std::string scratch_dir(const std::string& name) {
    fs::path p = fs::path(ENVTRACE_TEST_TMP_DIR) / (name + "-" + std::to_string(getpid()));
    std::error_code ec;
    fs::remove_all(p, ec);
    fs::create_directories(p);
    return p.string();
}

et::ClRuntime& runtime() {
    static std::unique_ptr<et::ClRuntime> rt;
    if (!rt)
        rt = std::make_unique<et::ClRuntime>(0);
    return *rt;
}

et::RgbImage constant_image(int w, int h, float value) {
    et::RgbImage img;
    img.width = w;
    img.height = h;
    img.rgb.assign(static_cast<size_t>(w) * h * 3, value);
    return img;
}

et::EnvMap load_map(const std::string& path, const et::DistributionOptions& options) {
    return et::load_envmap(path, options);
}

WarningCapture::WarningCapture() {
    previous_ = et::set_warning_sink([this](const std::string& m) { messages_.push_back(m); });
}

WarningCapture::~WarningCapture() {
    et::set_warning_sink(previous_);
}

size_t WarningCapture::count_containing(const std::string& text) const {
    size_t n = 0;
    for (const auto& m : messages_)
        n += m.find(text) != std::string::npos;
    return n;
}

void write_raw_exr(const std::string& path, int w, int h, const std::vector<float>& rgb) {
#if !ENVTRACE_TEST_OPENIMAGEIO
    (void)w, (void)h, (void)rgb;
    throw et::Error(path + ": writing EXR needs OpenImageIO (ENVTRACE_OPENIMAGEIO=OFF)");
#else
    auto out = OIIO::ImageOutput::create(path);
    const OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::FLOAT);
    if (!out || !out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, rgb.data()) ||
        !out->close())
        throw et::Error(path + ": cannot write the test image");
#endif
}

} // namespace ett
