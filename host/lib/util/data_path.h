// Finding input files: next to the scene file, then in each folder of ENVTRACE_DATA
// (colon-separated), then in ../shared/data beside the source tree when it exists.
#pragma once
#include <string>
#include <vector>

namespace et {

std::vector<std::string> data_search_path();

// Returns the first existing candidate, or throws et::Error listing where it looked.
std::string resolve_data_file(const std::string& path, const std::string& base_dir = "");

} // namespace et
