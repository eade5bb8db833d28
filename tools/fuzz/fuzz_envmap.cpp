// libFuzzer harness: an environment map through et::load_envmap (OpenImageIO's readers, our
// channel mapping and sRGB decoding, texel sanitising and the sampling distribution). The first
// byte of the input picks the file's extension (and so the reader OpenImageIO tries first; it
// falls back to the others when that one refuses the file), the rest is the file.
// tools/fuzz/make_corpus.py writes the seeds that way.
#include "fuzz_common.h"
#include "image/image_io.h"
#include "load/environment_map.h"
#include "util/checked_size.h"

#include <OpenImageIO/imageio.h>

#include <cmath>

namespace {

constexpr const char* extensions[] = {".exr", ".hdr", ".pfm", ".png", ".jpg", ".tif", ".img"};
constexpr size_t n_extensions = sizeof(extensions) / sizeof(extensions[0]);

// Cost bound, not a mask: the loader accepts a declared size up to its memory budget
// (kMaxBufferBytes, 3 GiB of float RGB texels; F5, fixed), more than libFuzzer's 2 GiB malloc
// limit and far more than hundreds of executions a second afford (a 2.6 KB file may declare
// 16000x16000 pixels and pass the header checks; since F7's fix it fails on the missing data
// having touched one band, but a valid map that large still takes seconds). Inputs whose header
// declares more than this many texel values (256x256 pixels) but no more than the budget are
// skipped; above the budget they go on, and the loader must refuse them before allocating.
// (The larger seeds, 512x512 to 911x876 EXRs, are skipped: decoding them is OpenEXR's code, not
// instrumented, and building their distributions under coverage instrumentation took most of
// the run's time; 16x8 seeds of every compression remain.)
constexpr double fuzz_texel_values = 3.0 * 256 * 256;

// The size is read by the loader's own reader (its checks first: asking OpenImageIO directly
// would let a corrupt EXR header allocate gigabytes here, before the loader's guard, F10); a
// file it refuses is left to the loader, which refuses it the same way.
bool too_costly(const std::string& path) {
    try {
        const et::RgbImageReader reader(path);
        const double values = 3.0 * reader.width() * reader.height();
        return values > fuzz_texel_values && values * sizeof(float) <= double(et::kMaxBufferBytes);
    } catch (const et::Error&) {
        return false;
    }
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    etfuzz::silence_warnings();
    OIIO::attribute("threads", 1); // one thread: reproducible, and no pool left behind
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const etfuzz::FdCheck fds;
    if (size < 1)
        return 0;
    const std::string name = std::string("map") + extensions[data[0] % n_extensions];
    const std::string path = etfuzz::write_file(name, data + 1, size - 1);
    if (too_costly(path))
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
