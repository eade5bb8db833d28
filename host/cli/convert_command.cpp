// envtrace convert: an image as envtrace reads maps (linear RGB floats: 8- and 16-bit files decoded
// from sRGB, alpha ignored), written in the output's format. To PFM the floats travel bit for bit,
// which is how a data folder is made for a build without OpenImageIO (docs/devices.md); to
// 8-bit formats they are encoded as sRGB, so that envtrace reads back what it wrote.
#include "commands.h"

#include "image/image_io.h"
#include "util/error.h"

#include <cstdio>
#include <memory>

namespace et::cli {

namespace {

struct ConvertArgs {
    std::string input, output;
};

void run(const ConvertArgs& a) {
    check_writable_format(a.output);
    RgbImage img = read_rgb_image(a.input);
    // 8-bit outputs hold sRGB-encoded values in [0, 1], as envtrace decodes 8-bit files: the
    // linear values written as they were came back darker (0.5 as 0.21), and PNG to PNG lost
    // more with every pass. What the range cannot hold is clipped, and said.
    if (!is_float_image_extension(a.output)) {
        size_t clipped = 0;
        for (float& v : img.rgb) {
            clipped += !(v >= 0.0f && v <= 1.0f);
            v = linear_to_srgb(v);
        }
        if (clipped)
            warn(a.output + ": " + std::to_string(clipped) + " of " +
                 std::to_string(img.rgb.size()) +
                 " values outside [0, 1] clipped (an 8-bit format; .exr, .hdr or .pfm keep "
                 "them)");
    }
    write_image(a.output, img.width, img.height, 3, img.rgb); // refuses to replace the input
    std::printf("wrote %s (%dx%d, from %s)\n", a.output.c_str(), img.width, img.height,
                a.input.c_str());
}

} // namespace

void add_convert_command(CLI::App& app, Globals&) {
    auto a = std::make_shared<ConvertArgs>();
    auto* cmd = app.add_subcommand(
        "convert", "Write an image as envtrace reads it (linear RGB) in OUTPUT's format");
    cmd->add_option("input", a->input, "Image envtrace reads (.exr, .hdr, .pfm, .png, ...)")
        ->required();
    cmd->add_option("output", a->output, "Image to write (.pfm: the floats bit for bit; .exr, ...)")
        ->required();
    cmd->callback([a] { run(*a); });
}

} // namespace et::cli
