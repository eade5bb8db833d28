// The image formats other than PFM, for image_io.cpp alone: read and written through
// OpenImageIO (the oiio_*.cpp files) or, in a build without it (CMake ENVTRACE_OPENIMAGEIO=OFF,
// for machines such as GPU nodes that lack its ~270 libraries), refused with an error that names
// the file (image_library_none.cpp). PFM is read and written in image_io.cpp by either build.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace et::image_detail {

// An opened image, decoded a band of rows at a time from the top (RgbImageReader's source).
class RowSource {
  public:
    virtual ~RowSource() = default;
    virtual int width() const = 0;
    virtual int height() const = 0;
    // Rows per call that suit the file (whole blocks of its compression or tiles).
    virtual int band_rows() const = 0;
    // Rows [y0, y1) into dst, 3 floats per pixel; throws et::Error naming `path`.
    virtual void read_rows(const std::string& path, int y0, int y1, float* dst) = 0;
    // Called once the last row is read: the file may be let go.
    virtual void finish() {}
};

// True where the build has the library; false: the functions below throw.
bool library_available();
// Opens a file that is not PFM; file_bytes is its size (already checked). Throws et::Error.
std::unique_ptr<RowSource> open_with_library(const std::string& path, uint64_t file_bytes,
                                             bool colour);
// Every channel of a file that is not PFM, as stored (float, no sRGB decoding), with the
// checks open_with_library makes first: `names` gets the channel names, the result the pixels
// interleaved. Throws et::Error naming `path`.
std::vector<float> read_channels_with_library(const std::string& path, uint64_t file_bytes,
                                              int& width, int& height,
                                              std::vector<std::string>& names);
// Throws et::Error "PATH: ..." unless the library can write `ext` (".exr", ".png", ...).
void check_library_writer(const std::string& path, const std::string& ext);
// Writes the finite pixels to `file` as float (`floating`) or 8-bit values; messages name `path`,
// the output it becomes. Named channels (`names`, may be null) make a multi-layer OpenEXR file.
void write_with_library(const std::string& path, const std::string& file, int width, int height,
                        int channels, const float* pixels, bool floating,
                        const std::vector<std::pair<std::string, std::string>>& attributes,
                        const std::vector<std::string>* names);

// Shared with image_io.cpp, which defines them.
std::string one_line(std::string s);
// The declared size of an image against what can be held and indexed, before any pixel is read.
void check_declared_size(const std::string& path, int64_t w, int64_t h, int64_t depth,
                         uint64_t stored_bytes, uint64_t file_bytes);

} // namespace et::image_detail
