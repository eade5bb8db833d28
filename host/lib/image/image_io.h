// Reading images as linear RGB floats and writing images without ever leaving a half-written
// file behind.
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace et {

class OutputBatch;

struct RgbImage {
    int width = 0, height = 0;
    std::vector<float> rgb; // row-major, 3 floats per pixel, row 0 at the top
    float* at(int x, int y) { return &rgb[3 * (static_cast<size_t>(y) * width + x)]; }
    const float* at(int x, int y) const { return &rgb[3 * (static_cast<size_t>(y) * width + x)]; }
};

// Any format OpenImageIO reads (EXR of every compression, HDR, PNG, JPEG, ...) and PFM (read
// here; the only format of a build without OpenImageIO). Only regular files of at most
// kMaxImageBytes are opened, and the declared size is checked against the memory budget and the
// file's size before any pixel is read. 8- and 16-bit images are decoded from sRGB to linear. One
// channel is replicated to RGB; otherwise the R, G, B channels are used (the first three when they
// are not named so), as stored: alpha is ignored, colour is never multiplied or divided by it.
// Throws et::Error naming the file and the problem. `colour` false reads data (a roughness
// texture): 8- and 16-bit values as stored, not decoded.
RgbImage read_rgb_image(const std::string& path, bool colour = true);

// Every channel of an image, by name (an envtrace render's layers: film_layers.h): an OpenEXR
// file's channels as stored, in the file's order; any other format's as read_rgb_image reads it,
// named R, G, B. Throws et::Error naming the file and the problem.
struct ImageChannels {
    int width = 0, height = 0;
    std::vector<std::string> names;
    std::vector<float> pixels; // row-major, names.size() floats per pixel, row 0 at the top
};
ImageChannels read_image_channels(const std::string& path);

// read_rgb_image a band of rows at a time, from the top, so that a caller can work on the first
// rows while later ones decode (load_envmap builds the distribution meanwhile).
class RgbImageReader {
  public:
    // Opens the file and checks its header, as read_rgb_image does; throws et::Error.
    explicit RgbImageReader(const std::string& path, bool colour = true);
    ~RgbImageReader();
    RgbImageReader(const RgbImageReader&) = delete;
    RgbImageReader& operator=(const RgbImageReader&) = delete;

    int width() const;
    int height() const;
    // Rows per call that suit the file (whole blocks of its compression or tiles).
    int band_rows() const;
    // Decodes the next `rows` rows (fewer at the bottom) into dst, 3 floats per pixel; returns
    // how many it decoded. Throws et::Error when the file is corrupt.
    int read_rows(int rows, float* dst);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Writes `channels`-channel float pixels. .exr/.hdr/.pfm keep linear floats; .png/.jpg expect
// display values in [0,1] and store 8 bits. `attributes` are name/value string metadata. NaN and
// Inf are written as 0 with a warning: no output of envtrace holds them. All-or-nothing: written
// to a temporary and renamed into place (util/output_batch.h), never over an input of the run.
void write_image(const std::string& path, int width, int height, int channels,
                 const std::vector<float>& pixels,
                 const std::vector<std::pair<std::string, std::string>>& attributes = {});
// The same as one file of a batch: renamed into place with the others by batch.commit().
void write_image(OutputBatch& batch, const std::string& path, int width, int height, int channels,
                 const std::vector<float>& pixels,
                 const std::vector<std::pair<std::string, std::string>>& attributes = {});

// An OpenEXR image of named channels (a multi-layer file: "R", "albedo.R", "N.X", "Z", ...),
// one float per channel and pixel, interleaved in the order of `names`; else as write_image.
void write_image_channels(OutputBatch& batch, const std::string& path, int width, int height,
                          const std::vector<std::string>& names, const std::vector<float>& pixels,
                          const std::vector<std::pair<std::string, std::string>>& attributes = {});

// Throws et::Error "PATH: problem" unless an image can be written at `path`: a supported
// extension with a writer (.pfm is written here, the rest by OpenImageIO), an existing folder,
// and not a folder itself. write_image checks this first; a command can call it before it
// spends time on a render.
void check_writable_format(const std::string& path);

// False in a build without OpenImageIO (CMake ENVTRACE_OPENIMAGEIO=OFF): PFM is then the only
// format read or written (others are refused by name), and commands write no .png previews.
bool have_image_library();

// Linear radiance to display sRGB in [0,1]: exposure scale, then a clamped sRGB curve.
float linear_to_srgb(float v);
float srgb_to_linear(float v);

bool is_float_image_extension(const std::string& path);

} // namespace et
