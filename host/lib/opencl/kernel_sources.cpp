#include "opencl/kernel_sources.h"

#include "util/error.h"

#include <regex>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

namespace et {
namespace {

struct Sources {
    const std::map<std::string, std::string>* own; // looked up first; may be null
    std::string own_dir;
};

void expand(const std::string& name, const Sources& from, std::set<std::string>& done,
            std::string& out) {
    const std::string* text = nullptr;
    std::string path;
    if (from.own)
        if (auto it = from.own->find(name); it != from.own->end()) {
            text = &it->second;
            path = from.own_dir + "/" + name;
        }
    if (!text) {
        const auto& sources = embedded_kernel_sources();
        auto it = sources.find(name);
        if (it == sources.end())
            throw Error("kernel source '" + name + "' is not embedded in this build");
        text = &it->second;
        path = "kernels/" + name;
    }
    if (!done.insert(name).second)
        return;
    std::istringstream in(*text);
    std::string line;
    int number = 0;
    out += "#line 1 \"" + path + "\"\n";
    while (std::getline(in, line)) {
        ++number;
        auto first = line.find_first_not_of(" \t");
        if (first != std::string::npos && line.compare(first, 8, "#include") == 0) {
            auto q0 = line.find('"', first);
            auto q1 = q0 == std::string::npos ? q0 : line.find('"', q0 + 1);
            if (q1 != std::string::npos) {
                expand(line.substr(q0 + 1, q1 - q0 - 1), from, done, out);
                out += "#line " + std::to_string(number + 1) + " \"" + path + "\"\n";
                continue;
            }
        }
        out += line;
        out += '\n';
    }
}

} // namespace

std::string expand_kernel_source(const std::string& name) {
    std::set<std::string> done;
    std::string out;
    expand(name, {nullptr, ""}, done, out);
    return out;
}

std::string expand_kernel_source(const std::string& name,
                                 const std::map<std::string, std::string>& own,
                                 const std::string& own_dir) {
    std::set<std::string> done;
    std::string out;
    expand(name, {&own, own_dir}, done, out);
    return out;
}

std::string logical_locations(const std::string& log, const std::string& source) {
    if (log.find('<') == std::string::npos)
        return log; // nothing to map (a clean build's log is empty): no pass over the source
    // Physical line p (1-based) of `source` -> (file, line) after the #line directives before it.
    std::vector<std::pair<std::string, int>> where{{"", 0}};
    const std::regex directive(R"re(^\s*#\s*line\s+(\d{1,9})(\s+"([^"]*)")?)re");
    std::istringstream in(source);
    std::string line, file;
    int next = 1;
    std::smatch m;
    while (std::getline(in, line)) {
        where.emplace_back(file, next);
        if (std::regex_search(line, m, directive)) {
            next = std::stoi(m[1].str());
            if (m[3].matched)
                file = m[3].str();
        } else {
            ++next;
        }
    }
    // "<kernel>:LINE" and the like: the program's own name for a source string.
    const std::regex location(R"(<[A-Za-z ]+>:(\d{1,9}))");
    std::string out;
    auto begin = log.cbegin();
    for (std::sregex_iterator it(log.begin(), log.end(), location), end; it != end; ++it) {
        const std::smatch& hit = *it;
        out.append(begin, hit[0].first);
        const size_t p = std::stoul(hit[1].str());
        if (p < where.size() && !where[p].first.empty())
            out += where[p].first + ":" + std::to_string(where[p].second);
        else
            out += hit[0].str();
        begin = hit[0].second;
    }
    out.append(begin, log.cend());
    return out;
}

} // namespace et
