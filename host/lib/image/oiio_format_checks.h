// Checks of image files before (or after) OpenImageIO opens them, for what it would read
// differently from what the file means: each format's own rules (oiio_pnm_check.cpp,
// oiio_radiance_header.cpp) and the orientation and windows of any image
// (oiio_orientation_check.cpp). Errors are et::Error naming `path`.
#pragma once
#include <OpenImageIO/imageio.h>

#include <string>
#include <vector>

namespace et::image_detail {

// A grey or colour PNM's maxval (P2, P3, P5, P6) must be 1..65535: OpenImageIO reads 0 as
// "every value is full scale", and an all-black file rendered as a white furnace.
void check_pnm_maxval(const std::string& path);

// The lines of a Radiance header, from its first 64 kB, up to the blank line that ends it.
std::vector<std::string> radiance_header(const std::string& path);
// The FORMAT= value ("" when absent): OpenImageIO reports an XYZE file as having no FORMAT.
std::string radiance_format(const std::vector<std::string>& header);
// Warns when the product of the EXPOSURE= values is not 1 (pixels are read as stored).
void warn_radiance_exposure(const std::string& path, const std::vector<std::string>& header);

// Refuses files whose stored pixels are not the picture as shown: turned, or (OpenEXR, `exr`)
// covering another window than the one shown.
void check_upright_and_whole(const std::string& path, const OIIO::ImageSpec& spec, bool exr);

} // namespace et::image_detail
