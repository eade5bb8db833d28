// Reading JSON files with errors that give file, line and column.
#pragma once
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace et {

nlohmann::json read_json_file(const std::string& path);

// Writes `j` (indented by `indent`) to a temporary file beside `path` and renames it into
// place; on failure removes the temporary and throws et::Error naming `path`.
void write_json_file(const std::string& path, const nlohmann::json& j, int indent = 2);

// Warns once about keys of `object` that are not in `known`, naming them and where they are.
void warn_unknown_keys(const nlohmann::json& object, const std::vector<std::string>& known,
                       const std::string& where);

} // namespace et
