#include "opencl/kernel_sources.h"

#include "util/error.h"

#include <set>
#include <sstream>

namespace et {
namespace {

void expand(const std::string& name, std::set<std::string>& done, std::string& out) {
    const auto& sources = embedded_kernel_sources();
    auto it = sources.find(name);
    if (it == sources.end())
        throw Error("kernel source '" + name + "' is not embedded in this build");
    if (!done.insert(name).second)
        return;
    std::istringstream in(it->second);
    std::string line;
    int number = 0;
    out += "#line 1 \"kernels/" + name + "\"\n";
    while (std::getline(in, line)) {
        ++number;
        auto first = line.find_first_not_of(" \t");
        if (first != std::string::npos && line.compare(first, 8, "#include") == 0) {
            auto q0 = line.find('"', first);
            auto q1 = q0 == std::string::npos ? q0 : line.find('"', q0 + 1);
            if (q1 != std::string::npos) {
                expand(line.substr(q0 + 1, q1 - q0 - 1), done, out);
                out += "#line " + std::to_string(number + 1) + " \"kernels/" + name + "\"\n";
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
    expand(name, done, out);
    return out;
}

} // namespace et
