#include "util/json_file.h"

#include "util/error.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace et {

nlohmann::json read_json_file(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw Error(path + ": no such file");
    if (std::filesystem::is_directory(path, ec))
        throw Error(path + ": is a directory, not a JSON file");
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw Error(path + ": cannot open for reading");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        // e.byte is 1-based and points just past the offending character.
        size_t pos = e.byte > 0 ? std::min(text.size(), e.byte - 1) : 0;
        int line = 1, col = 1;
        for (size_t i = 0; i < pos; ++i) {
            if (text[i] == '\n') {
                ++line;
                col = 1;
            } else {
                ++col;
            }
        }
        std::string what = e.what();
        auto colon = what.rfind(": ");
        if (colon != std::string::npos)
            what = what.substr(colon + 2);
        throw Error(path + ":" + std::to_string(line) + ":" + std::to_string(col) +
                    ": malformed JSON: " + what);
    }
}

void write_json_file(const std::string& path, const nlohmann::json& j, int indent) {
    namespace fs = std::filesystem;
    const std::string tmp = path + ".tmp" + std::to_string(::getpid());
    std::error_code ec;
    {
        std::ofstream f(tmp);
        if (f)
            f << j.dump(indent) << "\n";
        if (!f) {
            fs::remove(tmp, ec);
            throw Error(path + ": cannot write");
        }
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw Error(path + ": cannot write: " + ec.message());
    }
}

void warn_unknown_keys(const nlohmann::json& object, const std::vector<std::string>& known,
                       const std::string& where) {
    if (!object.is_object())
        return;
    std::string unknown;
    for (auto it = object.begin(); it != object.end(); ++it)
        if (std::find(known.begin(), known.end(), it.key()) == known.end())
            unknown += (unknown.empty() ? "'" : ", '") + it.key() + "'";
    if (!unknown.empty())
        warn(where + ": unknown key(s) " + unknown + " ignored");
}

} // namespace et
