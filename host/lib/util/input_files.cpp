#include "util/input_files.h"

#include <mutex>
#include <sys/stat.h>
#include <vector>

namespace et {
namespace {

struct InputFile {
    std::string path, what;
    unsigned long long device, inode;
};

std::mutex& registry_mutex() {
    static std::mutex m;
    return m;
}
std::vector<InputFile>& registry() {
    static std::vector<InputFile> files;
    return files;
}

} // namespace

void note_input_file(const std::string& path, const char* what, unsigned long long device,
                     unsigned long long inode) {
    std::lock_guard<std::mutex> lock(registry_mutex());
    for (const auto& f : registry())
        if (f.device == device && f.inode == inode)
            return;
    registry().push_back({path, what, device, inode});
}

std::string input_file_named(const std::string& path) {
    // The identity of the file, not its name: catches links, "./x" and "dir/../x" alike.
    struct stat st;
    if (::stat(path.c_str(), &st) != 0)
        return {};
    std::lock_guard<std::mutex> lock(registry_mutex());
    for (const auto& f : registry())
        if (f.device == static_cast<unsigned long long>(st.st_dev) &&
            f.inode == static_cast<unsigned long long>(st.st_ino))
            return "the " + f.what + " '" + f.path + "'";
    return {};
}

} // namespace et
