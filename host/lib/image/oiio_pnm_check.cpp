// PNM headers checked before OpenImageIO reads them (oiio_format_checks.h).
#include "image/oiio_format_checks.h"
#include "util/error.h"

#include <cctype>
#include <cstdio>
#include <string>

namespace et::image_detail {

// A grey or colour PNM's maxval (P2, P3, P5, P6) must be 1..65535: OpenImageIO reads 0 as
// "every value is full scale", and an all-black file rendered as a white furnace.
void check_pnm_maxval(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f)
        return;
    char head[512] = {};
    const size_t n = std::fread(head, 1, sizeof head - 1, f);
    std::fclose(f);
    if (n < 2 || head[0] != 'P' || head[1] == '\0' || !std::strchr("2356", head[1]))
        return;
    // Three numbers after the magic (width, height, maxval), '#' comments to the line's end.
    long values[3] = {};
    size_t at = 2;
    for (int k = 0; k < 3; ++k) {
        for (;;) {
            while (at < n && std::isspace(static_cast<unsigned char>(head[at])))
                ++at;
            if (at < n && head[at] == '#') {
                while (at < n && head[at] != '\n')
                    ++at;
                continue;
            }
            break;
        }
        if (at >= n || !std::isdigit(static_cast<unsigned char>(head[at])))
            return; // not a header we can read: the library's own checks answer
        values[k] = std::strtol(head + at, nullptr, 10);
        while (at < n && std::isdigit(static_cast<unsigned char>(head[at])))
            ++at;
    }
    if (values[2] < 1 || values[2] > 65535)
        throw Error(path + ": PNM header: maxval " + std::to_string(values[2]) +
                    " is not in 1..65535");
}

} // namespace et::image_detail
