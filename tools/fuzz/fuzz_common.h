// Shared by the libFuzzer harnesses: the loaders take file paths, so each input is written to a
// file in a private folder of this process (in /dev/shm when there is one), reused across runs.
// et::Error is the loaders' expected way to refuse an input; any other exception escaping, a
// crash, a hang or a sanitizer report is a finding.
#pragma once
#include "util/error.h"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <dirent.h>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace etfuzz {

// The folder (created on first use, removed at normal exit). Its path goes to stderr: when the
// process dies without writing a crash artifact (a heap corrupted by uninstrumented code can
// deadlock libFuzzer's crash handler in malloc: F8), the input that did it is still there.
inline const std::string& work_dir() {
    struct Dir {
        std::string path;
        ~Dir() {
            std::error_code ec;
            std::filesystem::remove_all(path, ec);
        }
    };
    static const Dir dir{[] {
        std::error_code ec;
        std::string base = std::filesystem::is_directory("/dev/shm", ec) ? "/dev/shm" : "";
        if (base.empty()) {
            const char* t = std::getenv("TMPDIR");
            base = t && *t ? t : "/tmp";
        }
        std::string tmpl = base + "/envtrace-fuzz-XXXXXX";
        if (!mkdtemp(tmpl.data())) {
            std::perror("envtrace fuzz: mkdtemp");
            std::abort();
        }
        std::fprintf(stderr, "envtrace fuzz: inputs are written to %s (left there if the process "
                             "dies)\n", tmpl.c_str());
        return tmpl;
    }()};
    return dir.path;
}

// Writes `size` bytes to work_dir()/name (replacing it) and returns the path.
inline std::string write_file(const std::string& name, const uint8_t* data, size_t size) {
    const std::string path = work_dir() + "/" + name;
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f || (size && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
        std::perror(("envtrace fuzz: " + path).c_str());
        std::abort();
    }
    return path;
}

// Warnings are part of normal operation; printing them would only slow the fuzzer down.
inline void silence_warnings() {
    et::set_warning_sink([](const std::string&) {});
}

// Descriptors open in this process (-1 where /proc/self/fd cannot be read).
inline int open_fds() {
    DIR* d = opendir("/proc/self/fd");
    if (!d)
        return -1;
    int n = 0;
    while (readdir(d))
        ++n;
    closedir(d);
    return n;
}

// Declared first in LLVMFuzzerTestOneInput: the input must leave no more descriptors open than
// there were before it. A loader that leaks one per refused file (F9) is then a finding at the
// input that does it, not when the process runs out of descriptors tens of thousands later.
struct FdCheck {
    const int before = open_fds();
    ~FdCheck() {
        const int after = open_fds();
        if (before >= 0 && after > before) {
            std::fprintf(stderr, "envtrace fuzz: the input left %d file descriptor(s) open\n",
                         after - before);
            std::abort();
        }
    }
};

// Known findings, reported and left to the files' owners (tools/fuzz/README.md): inputs that hit
// them are skipped, so that a long run goes on looking for other things, unless
// ENVTRACE_FUZZ_NO_MASKS is set (then they are reported as crashes, as they should be).
inline bool masks_on() {
    static const bool on = std::getenv("ENVTRACE_FUZZ_NO_MASKS") == nullptr;
    return on;
}

} // namespace etfuzz
