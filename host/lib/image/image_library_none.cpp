// A build without OpenImageIO (CMake ENVTRACE_OPENIMAGEIO=OFF): PFM is the only image format, and
// every other file is refused, by name, before anything is read or written (image_library.h).
#include "image/image_library.h"

#include "util/error.h"

namespace et::image_detail {
namespace {

[[noreturn]] void refuse(const std::string& path, const char* what) {
    throw Error(path + ": cannot " + what +
                ": this envtrace was built without OpenImageIO (ENVTRACE_OPENIMAGEIO=OFF) and "
                "reads and writes PFM (.pfm) only");
}

} // namespace

bool library_available() {
    return false;
}

std::unique_ptr<RowSource> open_with_library(const std::string& path, uint64_t, bool) {
    refuse(path, "read image");
}

std::vector<float> read_channels_with_library(const std::string& path, uint64_t, int&, int&,
                                              std::vector<std::string>&) {
    refuse(path, "read image");
}

void check_library_writer(const std::string& path, const std::string&) {
    refuse(path, "write");
}

void write_with_library(const std::string& path, const std::string&, int, int, int, const float*,
                        bool, const std::vector<std::pair<std::string, std::string>>&,
                        const std::vector<std::string>*) {
    refuse(path, "write");
}

} // namespace et::image_detail
