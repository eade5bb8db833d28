// A main() for the fuzz harnesses without libFuzzer: runs LLVMFuzzerTestOneInput once on each
// file named, and on each regular file inside each folder named (sorted, not recursive). Linked
// into every build with tests (tools/fuzz/CMakeLists.txt), with any compiler, so that the
// per-stop test suite replays the seed corpora and the findings' reproducers through the
// harnesses' checks in seconds; finding new inputs is the libFuzzer build's job (README).
// Exit status 0 when every input ran (a harness that finds something aborts), 2 on bad usage.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv);
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace fs = std::filesystem;

int main(int argc, char** argv) {
    LLVMFuzzerInitialize(&argc, &argv);
    std::vector<std::string> inputs;
    for (int i = 1; i < argc; ++i) {
        std::error_code ec;
        if (fs::is_directory(argv[i], ec)) {
            std::vector<std::string> files;
            for (const auto& e : fs::directory_iterator(argv[i], ec))
                if (e.is_regular_file(ec))
                    files.push_back(e.path().string());
            std::sort(files.begin(), files.end());
            inputs.insert(inputs.end(), files.begin(), files.end());
        } else if (fs::is_regular_file(argv[i], ec)) {
            inputs.push_back(argv[i]);
        } else {
            std::fprintf(stderr, "replay: %s: no such file or folder\n", argv[i]);
            return 2;
        }
    }
    if (inputs.empty()) {
        std::fprintf(stderr, "usage: %s FILE_OR_FOLDER... (no inputs found)\n", argv[0]);
        return 2;
    }
    for (const std::string& path : inputs) {
        // Named before it runs, so that a harness that aborts points at its input.
        std::fprintf(stderr, "replay: %s\n", path.c_str());
        std::ifstream f(path, std::ios::binary);
        const std::vector<char> bytes{std::istreambuf_iterator<char>(f),
                                      std::istreambuf_iterator<char>()};
        LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    }
    std::printf("replay: %zu inputs, no finding\n", inputs.size());
    return 0;
}
