// Every channel of an OpenEXR file through OpenImageIO (image_library.h): a render's layers,
// read back as stored. The header is walked and the size checked first, as for a map.
#include "image/exr_header.h"
#include "image/image_library.h"
#include "util/checked_size.h"
#include "util/error.h"

#include <OpenImageIO/imageio.h>

OIIO_NAMESPACE_USING

namespace et::image_detail {

std::vector<float> read_channels_with_library(const std::string& path, uint64_t file_bytes,
                                              int& width, int& height,
                                              std::vector<std::string>& names) {
    const ExrHeaderInfo exr = check_exr_header(path, file_bytes);
    check_declared_size(path, exr.width, exr.height, 1, exr.stored_bytes, file_bytes);
    auto in = ImageInput::open(path);
    if (!in)
        throw Error(path + ": cannot read image: " + one_line(OIIO::geterror()));
    const ImageSpec& spec = in->spec();
    if (spec.deep)
        throw Error(path + ": deep images are not supported");
    width = spec.width;
    height = spec.height;
    names = spec.channelnames;
    const std::string what = path + ": pixels";
    std::vector<float> pixels(checked_mul(
        checked_mul(static_cast<uint64_t>(spec.width), static_cast<uint64_t>(spec.height), what),
        static_cast<uint64_t>(spec.nchannels), what));
    if (!in->read_image(0, 0, 0, spec.nchannels, TypeDesc::FLOAT, pixels.data()))
        throw Error(path + ": cannot decode image: " + one_line(in->geterror()));
    return pixels;
}

} // namespace et::image_detail
