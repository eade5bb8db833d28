// The scales of Radiance texels, read back from OpenImageIO's own decoder (oiio_rgbe_decoder.h).
#include "image/oiio_rgbe_decoder.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cmath>

OIIO_NAMESPACE_USING

namespace et::image_detail {

const std::array<float, 256>& rgbe_scales() {
    static const std::array<float, 256> scales = [] {
        std::array<float, 256> t;
        t[0] = 0.0f;
        for (int e = 1; e < 256; ++e)
            t[e] = std::ldexp(1.0f, e - 136);
        // One flat scanline (its first texel does not start with 2, 2) of (1, 1, 1, e).
        std::string file = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 256\n";
        for (int e = 0; e < 256; ++e)
            file += {'\1', '\1', '\1', static_cast<char>(e)};
        Filesystem::IOMemReader mem(file.data(), file.size());
        Filesystem::IOProxy* p = &mem;
        ImageSpec config, spec;
        config.attribute("oiio:ioproxy", TypeDesc::PTR, &p);
        std::vector<float> rgb(3 * 256);
        auto in = ImageInput::create("hdr");
        if (in && in->open("rgbe-scales.hdr", spec, config) && spec.width == 256 &&
            in->read_image(0, 0, 0, 3, TypeDesc::FLOAT, rgb.data()))
            for (int e = 0; e < 256; ++e)
                t[e] = rgb[3 * e];
        (void)OIIO::geterror();
        return t;
    }();
    return scales;
}

} // namespace et::image_detail
