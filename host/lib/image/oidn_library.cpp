#include "image/oidn_library.h"

#include "util/error.h"

#include <dlfcn.h>
#include <glob.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <vector>

#ifndef ENVTRACE_OIDN_VENV
#define ENVTRACE_OIDN_VENV ""
#endif

#if defined(__SANITIZE_ADDRESS__)
#define ENVTRACE_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ENVTRACE_ASAN 1
#endif
#endif

namespace et {
namespace {

constexpr const char* kSoname = "libOpenImageDenoise.so.2";
constexpr const char* kHowToInstall =
    "run tools/setup (it installs the PyPI wheel pyoidn, which ships OIDN's libraries, into "
    "build/oidn-venv), or set ENVTRACE_OIDN to a libOpenImageDenoise.so.2 (e.g. the one under "
    "site-packages/pyoidn/oidn/lib/ after 'pip install pyoidn')";

// The wheel's library inside the virtual environment, whatever its Python version.
std::string venv_library(const std::string& venv) {
    if (venv.empty())
        return "";
    const std::string pattern = venv + "/lib/python3*/site-packages/pyoidn/oidn/lib/" + kSoname;
    glob_t g{};
    std::string found;
    if (glob(pattern.c_str(), 0, nullptr, &g) == 0 && g.gl_pathc > 0)
        found = g.gl_pathv[0];
    globfree(&g);
    return found;
}

template <class F> void resolve(void* lib, const char* name, F& fn, const std::string& file) {
    fn = reinterpret_cast<F>(dlsym(lib, name));
    if (!fn)
        throw Error(file + ": not an Open Image Denoise 2 library (no " + name + "); " +
                    kHowToInstall);
}

oidn::Api resolve_api(void* lib, const std::string& file) {
    oidn::Api a{};
    resolve(lib, "oidnNewDevice", a.NewDevice, file);
    resolve(lib, "oidnCommitDevice", a.CommitDevice, file);
    resolve(lib, "oidnReleaseDevice", a.ReleaseDevice, file);
    resolve(lib, "oidnGetDeviceInt", a.GetDeviceInt, file);
    resolve(lib, "oidnGetDeviceError", a.GetDeviceError, file);
    resolve(lib, "oidnNewBuffer", a.NewBuffer, file);
    resolve(lib, "oidnWriteBuffer", a.WriteBuffer, file);
    resolve(lib, "oidnReadBuffer", a.ReadBuffer, file);
    resolve(lib, "oidnReleaseBuffer", a.ReleaseBuffer, file);
    resolve(lib, "oidnNewFilter", a.NewFilter, file);
    resolve(lib, "oidnSetFilterImage", a.SetFilterImage, file);
    resolve(lib, "oidnSetFilterBool", a.SetFilterBool, file);
    resolve(lib, "oidnCommitFilter", a.CommitFilter, file);
    resolve(lib, "oidnExecuteFilter", a.ExecuteFilter, file);
    resolve(lib, "oidnReleaseFilter", a.ReleaseFilter, file);
    return a;
}

std::string dl_error() {
    const char* e = dlerror();
    return e ? e : "unknown error";
}

struct Loaded {
    oidn::Api api{};
    std::string file, error;
};

// The search of oidn_library.h, in order; the first library that loads is kept.
Loaded load() {
#ifdef ENVTRACE_ASAN
    // OIDN's TBB loads its helpers with RTLD_DEEPBIND, which AddressSanitizer's runtime refuses
    // (ending the process), unless told it runs under a sanitizer.
    setenv("TBB_ENABLE_SANITIZERS", "1", 0);
#endif
    Loaded r;
    void* lib = nullptr;
    const char* env = std::getenv("ENVTRACE_OIDN");
    if (env && *env) {
        r.file = env;
        if (!std::filesystem::exists(r.file))
            throw Error("ENVTRACE_OIDN=" + r.file +
                        ": no such file (it names the Open Image Denoise 2 library to load); " +
                        kHowToInstall);
        lib = dlopen(r.file.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!lib)
            throw Error("ENVTRACE_OIDN=" + r.file + ": cannot load it: " + dl_error() + "; " +
                        kHowToInstall);
    } else {
        std::vector<std::string> tried;
        r.file = venv_library(ENVTRACE_OIDN_VENV);
        if (!r.file.empty()) {
            lib = dlopen(r.file.c_str(), RTLD_NOW | RTLD_LOCAL);
            if (!lib)
                tried.push_back(r.file + " (" + dl_error() + ")");
        } else if (*ENVTRACE_OIDN_VENV) {
            tried.push_back(std::string(ENVTRACE_OIDN_VENV) + " (no pyoidn in it)");
        }
        if (!lib) {
            r.file = kSoname;
            lib = dlopen(kSoname, RTLD_NOW | RTLD_LOCAL);
            if (!lib)
                tried.push_back(std::string(kSoname) + " (" + dl_error() + ")");
        }
        if (!lib) {
            std::string list;
            for (const std::string& t : tried)
                list += (list.empty() ? "" : ", ") + t;
            throw Error("denoising needs Intel Open Image Denoise 2, which was not found (tried " +
                        list + "): " + kHowToInstall);
        }
    }
    r.api = resolve_api(lib, r.file);
    return r;
}

std::mutex load_mutex;
bool tried_load = false;
Loaded loaded;

} // namespace

const oidn::Api& oidn_api() {
    std::lock_guard<std::mutex> lock(load_mutex);
    if (!tried_load) {
        tried_load = true;
        try {
            loaded = load();
        } catch (const Error& e) {
            loaded.file.clear();
            loaded.error = e.what();
        }
    }
    if (!loaded.error.empty())
        throw Error(loaded.error);
    return loaded.api;
}

std::string oidn_library_file() {
    std::lock_guard<std::mutex> lock(load_mutex);
    return loaded.file;
}

} // namespace et
