// The image names of `envtrace render` and `envtrace merge` (commands.h).
#include "commands.h"

#include "image/image_io.h"
#include "util/error.h"
#include "util/file_check.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace et::cli {

// out.exr -> (out.exr, out.png); out.png -> (out.exr, out.png). A build without OpenImageIO
// writes no preview: out.pfm -> (out.pfm, "").
std::pair<std::string, std::string> output_names(const std::string& out) {
    fs::path p(out);
    std::error_code ec;
    if (!out.empty() && (out.back() == '/' || p.filename() == "." || p.filename() == ".." ||
                         fs::is_directory(p, ec)))
        throw Error(out + ": is a folder: name the image to write in it (e.g. " +
                    (fs::path(out) / "render.exr").lexically_normal().string() + ")");
    const std::string ext = lower_extension(out);
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg")
        return {fs::path(p).replace_extension(".exr").string(), out};
    if (ext == ".exr" || ext == ".hdr" || ext == ".pfm")
        return {out, have_image_library() ? fs::path(p).replace_extension(".png").string() : ""};
    throw Error(out + ": unsupported output format '" + ext +
                "' (use .exr, .hdr, .pfm, or .png / .jpg for the preview beside an .exr)");
}

std::string denoised_name(const std::string& image) {
    fs::path p(image);
    const fs::path ext = p.extension();
    return p.replace_extension(".denoised" + ext.string()).string();
}

} // namespace et::cli
