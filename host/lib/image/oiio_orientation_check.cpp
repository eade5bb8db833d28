// Images whose stored pixels are not the picture as shown, refused (oiio_format_checks.h).
#include "image/oiio_format_checks.h"
#include "util/error.h"
#include "util/file_check.h"

#include <string>

OIIO_NAMESPACE_USING

namespace et::image_detail {

// Files whose stored pixels are not the picture as shown: turned (an orientation other than
// "normal": Radiance's "+Y H +X W", EXIF's rotations) or covering another window than the one
// shown (an EXR's data window inside or around its display window). Read as stored, a map would
// light the scene upside down, mirrored or stretched without a word; refused instead, with the
// command that writes the picture as shown.
void check_upright_and_whole(const std::string& path, const ImageSpec& spec, bool exr) {
    // What the stored pixels need to be shown upright (EXIF's orientations 2-8; 0, which some
    // cameras write, means unspecified: as stored).
    static const char* const needs[] = {"",
                                        "",
                                        "flipping horizontally",
                                        "turning 180 degrees",
                                        "flipping vertically (stored bottom-up)",
                                        "transposing",
                                        "turning 90 degrees clockwise",
                                        "transversing",
                                        "turning 90 degrees counter-clockwise"};
    const int o = spec.get_int_attribute("Orientation", 1);
    if (o != 1 && o != 0)
        throw Error(path + ": its pixels need " +
                    (o >= 2 && o <= 8 ? needs[o] : "an unknown reorientation") +
                    " to be upright (orientation " + std::to_string(o) +
                    "), which envtrace does not apply; write it upright first, e.g. oiiotool \"" +
                    path + "\" --reorient -o upright" + lower_extension(path));
    // Only OpenEXR separates the two windows (a PNG's oFFs offset, which OpenImageIO reports as
    // a data window off a display window at 0, places the picture on a page: it is the picture).
    const bool full_known = exr && spec.full_width > 0 && spec.full_height > 0;
    if (full_known && (spec.x != spec.full_x || spec.y != spec.full_y ||
                       spec.width != spec.full_width || spec.height != spec.full_height)) {
        auto window = [](int w, int h, int x, int y) {
            return std::to_string(w) + "x" + std::to_string(h) + (x >= 0 ? "+" : "") +
                   std::to_string(x) + (y >= 0 ? "+" : "") + std::to_string(y);
        };
        throw Error(path + ": its pixels (data window " +
                    window(spec.width, spec.height, spec.x, spec.y) +
                    ") are not its picture (display window " +
                    window(spec.full_width, spec.full_height, spec.full_x, spec.full_y) +
                    "); write the picture as shown first, e.g. oiiotool \"" + path +
                    "\" --croptofull -o whole" + lower_extension(path));
    }
}

} // namespace et::image_detail
