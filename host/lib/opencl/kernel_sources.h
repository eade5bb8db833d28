// OpenCL sources embedded at build time (cmake/embed_kernels.cmake), so the binary runs from
// any directory.
#pragma once
#include <map>
#include <string>

namespace et {

// File name (e.g. "envmap.h") -> contents: the product's kernels/ only.
const std::map<std::string, std::string>& embedded_kernel_sources();

// The named kernel file with its quoted #includes of embedded files expanded in place (each
// file once), wrapped in #line directives so compiler messages name kernels/FILE and its line.
std::string expand_kernel_source(const std::string& name);

// The same for a program of a test or benchmark binary, which embeds its own sources (`own`:
// file name -> contents, named `own_dir`/FILE in #line directives; cmake/embed_kernels.cmake)
// and includes the product's kernels by name; the product binary holds none of them.
std::string expand_kernel_source(const std::string& name,
                                 const std::map<std::string, std::string>& own,
                                 const std::string& own_dir);

// A build log with the locations of compilers that ignore #line (NVIDIA's reports
// "<kernel>:3:12: error") turned into the file and line that `source`'s #line directives name
// ("kernels/broken.cl:2:12: error"). Locations that cannot be mapped are left as they are.
std::string logical_locations(const std::string& log, const std::string& source);

} // namespace et
