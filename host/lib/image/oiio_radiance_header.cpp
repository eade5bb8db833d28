// Radiance HDR headers read for what OpenImageIO does not report (oiio_format_checks.h).
#include "image/oiio_format_checks.h"
#include "util/error.h"

#include <cstdio>
#include <cstdlib>
#include <string>

namespace et::image_detail {

// The lines of a Radiance header, from its first 64 kB, up to the blank line that ends it.
std::vector<std::string> radiance_header(const std::string& path) {
    std::vector<std::string> lines;
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f)
        return lines;
    std::string head(65536, '\0');
    head.resize(std::fread(&head[0], 1, head.size(), f));
    std::fclose(f);
    for (size_t at = 0; at < head.size();) {
        size_t end = head.find('\n', at);
        end = end == std::string::npos ? head.size() : end;
        if (end == at)
            break;
        lines.push_back(head.substr(at, end - at));
        at = end + 1;
    }
    return lines;
}

// The FORMAT= value ("" when absent): OpenImageIO reports an XYZE file as having no FORMAT.
std::string radiance_format(const std::vector<std::string>& header) {
    for (const std::string& line : header)
        if (line.rfind("FORMAT=", 0) == 0)
            return line.substr(7, line.find_last_not_of(" \t\r") - 6);
    return "";
}

// The product of the EXPOSURE= values, which Radiance says were applied to the stored pixels
// (radiance = pixel / exposure). Read as stored, as OpenImageIO and Blender read such files,
// and said when it is not 1.
void warn_radiance_exposure(const std::string& path, const std::vector<std::string>& header) {
    double exposure = 1.0;
    for (const std::string& line : header)
        if (line.rfind("EXPOSURE=", 0) == 0)
            exposure *= std::strtod(line.c_str() + 9, nullptr);
    if (exposure != 1.0) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", exposure);
        warn(path + ": the header's EXPOSURE (" + buf +
             ") is not applied: pixels are read as stored (radiance would be pixels / exposure; "
             "set the map's intensity to undo it)");
    }
}

} // namespace et::image_detail
