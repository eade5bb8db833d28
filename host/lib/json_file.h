// Reading JSON files with errors that give file, line and column.
#pragma once
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace et {

nlohmann::json read_json_file(const std::string& path);

// Warns once about keys of `object` that are not in `known`, naming them and where they are.
void warn_unknown_keys(const nlohmann::json& object, const std::vector<std::string>& known,
                       const std::string& where);

} // namespace et
