#include "util/data_path.h"

#include "util/error.h"

#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace et {

std::vector<std::string> data_search_path() {
    std::vector<std::string> dirs;
    if (const char* env = std::getenv("ENVTRACE_DATA"); env && *env) {
        std::stringstream ss(env);
        std::string d;
        while (std::getline(ss, d, ':'))
            if (!d.empty())
                dirs.push_back(d);
    }
#ifdef ENVTRACE_SOURCE_DIR
    std::error_code ec;
    fs::path shared = fs::path(ENVTRACE_SOURCE_DIR) / ".." / "shared" / "data";
    if (fs::is_directory(shared, ec))
        dirs.push_back(fs::weakly_canonical(shared, ec).string());
#endif
    return dirs;
}

std::string resolve_data_file(const std::string& path, const std::string& base_dir) {
    std::error_code ec;
    fs::path p(path);
    std::vector<fs::path> tried;
    if (p.is_absolute()) {
        tried.push_back(p);
    } else {
        tried.push_back(base_dir.empty() ? p : fs::path(base_dir) / p);
        for (const auto& d : data_search_path())
            tried.push_back(fs::path(d) / p);
    }
    for (const auto& t : tried)
        if (fs::exists(t, ec))
            return t.string();
    std::string msg = path + ": no such file (looked in";
    for (size_t i = 0; i < tried.size(); ++i)
        msg += (i ? ", " : " ") + tried[i].string();
    msg += "; set ENVTRACE_DATA to a colon-separated list of data folders)";
    throw Error(msg);
}

} // namespace et
