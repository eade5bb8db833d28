// OpenCL sources embedded at build time (cmake/embed_kernels.cmake), so the binary runs from
// any directory.
#pragma once
#include <map>
#include <string>

namespace et {

// File name (e.g. "envmap.h") -> contents.
const std::map<std::string, std::string>& embedded_kernel_sources();

// The named kernel file with its quoted #includes of embedded files expanded in place (each
// file once), wrapped in #line directives so compiler messages name kernels/FILE and its line.
std::string expand_kernel_source(const std::string& name);

} // namespace et
