// libFuzzer harness: an environment map through et::load_envmap (OpenImageIO's readers, our
// channel mapping and sRGB decoding, texel sanitising and the sampling distribution). The first
// byte of the input picks the file's extension (and so the reader OpenImageIO tries first; it
// falls back to the others when that one refuses the file), the rest is the file.
// tools/fuzz/make_corpus.py writes the seeds that way.
#include "fuzz_common.h"
#include "load/environment_map.h"

#include <OpenImageIO/imageio.h>

#include <cmath>

namespace {

constexpr const char* extensions[] = {".exr", ".hdr", ".pfm", ".png", ".jpg", ".tif", ".img"};
constexpr size_t n_extensions = sizeof(extensions) / sizeof(extensions[0]);

// Known finding, being fixed in image/image_io.cpp (a header-size memory budget): a header may
// declare up to 2e9 channel values, which read_rgb_image allocates as floats before decoding.
// Unless ENVTRACE_FUZZ_NO_MASKS is set, inputs whose header declares more than this are skipped,
// so that the fuzzer keeps looking for other things instead of stopping on an out-of-memory.
constexpr double header_budget = 16.0 * 1024 * 1024; // channel values
bool masks = true;

bool over_budget(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        return false;
    const OIIO::ImageSpec& spec = in->spec();
    return static_cast<double>(spec.width) * spec.height * spec.depth * spec.nchannels >
           header_budget;
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    etfuzz::silence_warnings();
    masks = etfuzz::masks_on();
    OIIO::attribute("threads", 1); // one thread: reproducible, and no pool left behind
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1)
        return 0;
    const std::string name = std::string("map") + extensions[data[0] % n_extensions];
    const std::string path = etfuzz::write_file(name, data + 1, size - 1);
    if (masks && over_budget(path))
        return 0;
    try {
        et::DistributionOptions options;
        et::EnvMap env = et::load_envmap(path, options);
        // What the renderer relies on: sanitised texels (finite, >= 0) and a finite distribution.
        const size_t n = static_cast<size_t>(env.image.width) * env.image.height * 3;
        if (env.image.width <= 0 || env.image.height <= 0 || env.image.rgb.size() != n)
            std::abort();
        for (float v : env.image.rgb)
            if (!(v >= 0.0f) || !std::isfinite(v))
                std::abort();
        for (float v : env.dist.table)
            if (!std::isfinite(v))
                std::abort();
        if (!std::isfinite(env.dist.total))
            std::abort();
    } catch (const et::Error&) {
    }
    return 0;
}
