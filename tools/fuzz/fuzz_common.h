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
#include <filesystem>
#include <string>
#include <unistd.h>

namespace etfuzz {

// The folder (created on first use, removed at normal exit).
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

// Known findings, reported and left to the files' owners (tools/fuzz/README.md): inputs that hit
// them are skipped, so that a long run goes on looking for other things, unless
// ENVTRACE_FUZZ_NO_MASKS is set (then they are reported as crashes, as they should be).
inline bool masks_on() {
    static const bool on = std::getenv("ENVTRACE_FUZZ_NO_MASKS") == nullptr;
    return on;
}

} // namespace etfuzz
