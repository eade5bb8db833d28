// Shared helpers of the tests: where the shared data lives, scratch folders, the OpenCL runtime
// of the process, synthetic maps and capturing warnings.
#pragma once
#include "load/environment_map.h"
#include "util/error.h"
#include "opencl/opencl_runtime.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace ett {

// The shared data folder (../shared/data beside the source tree, or the first folder of
// ENVTRACE_DATA holding envmaps/), or "" when there is none.
std::string data_dir();

// DATA/relative when it exists, else "".
std::string data_file(const std::string& relative);

// A fresh, empty scratch folder build/test-tmp/NAME for this process.
std::string scratch_dir(const std::string& name);

// One OpenCL runtime (device 0) per test process.
et::ClRuntime& runtime();

// An RGB image of w x h texels, every texel `value`.
et::RgbImage constant_image(int w, int h, float value);

// Loads DATA/envmaps/NAME with the given options.
// Writes float RGB pixels to an EXR exactly as given, NaN and Inf included (envtrace's own
// writer never does: this makes hostile inputs for tests).
void write_raw_exr(const std::string& path, int w, int h, const std::vector<float>& rgb);

et::EnvMap load_map(const std::string& path, const et::DistributionOptions& options = {});

// The message of the et::Error that f throws, "" when it throws none.
template <class F> std::string error_of(F f) {
    try {
        f();
    } catch (const et::Error& e) {
        return e.what();
    }
    return "";
}

// Collects et::warn messages while alive (restores the previous sink on destruction).
class WarningCapture {
  public:
    WarningCapture();
    ~WarningCapture();
    const std::vector<std::string>& messages() const { return messages_; }
    size_t count_containing(const std::string& text) const;

  private:
    std::vector<std::string> messages_;
    et::WarningSink previous_;
};

} // namespace ett

// Declares `var` as the full path of a shared data file, or skips the test when it is missing.
#define ETT_DATA_FILE(var, relative)                                                               \
    const std::string var = ett::data_file(relative);                                              \
    if (var.empty())                                                                               \
    GTEST_SKIP() << "shared data file '" << (relative)                                             \
                 << "' not found: set ENVTRACE_DATA to ../shared/data (CI has it)"
