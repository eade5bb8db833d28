// envtrace convert: an image as envtrace reads maps (linear RGB floats: 8- and 16-bit files decoded
// from sRGB, alpha ignored), written in the output's format. To PFM the floats travel bit for bit,
// which is how a data folder is made for a build without OpenImageIO (tools/gpu/README.md).
#include "commands.h"

#include "image/image_io.h"

#include <cstdio>
#include <memory>

namespace et::cli {

namespace {

struct ConvertArgs {
    std::string input, output;
};

void run(const ConvertArgs& a) {
    check_writable_format(a.output);
    const RgbImage img = read_rgb_image(a.input);
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
