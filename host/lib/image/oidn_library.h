// Finding and loading Open Image Denoise 2 at run time (dlopen), so that envtrace builds and runs
// where it is absent and only a denoised render needs it. Where it is looked for, in order:
//   1. $ENVTRACE_OIDN: the path of libOpenImageDenoise.so(.2); when set, nothing else is tried;
//   2. the virtual environment tools/setup installs the PyPI wheel pyoidn into (CMake's
//      ENVTRACE_OIDN_VENV, default build/oidn-venv of the source tree): the wheel's
//      pyoidn/oidn/lib/libOpenImageDenoise.so.2, which finds its core and CPU device beside it;
//   3. the system's loader (libOpenImageDenoise.so.2 on LD_LIBRARY_PATH or in its cache).
// The library is loaded once per process and never unloaded (its thread pools outlive calls).
#pragma once
#include "image/oidn_api.h"

#include <string>

namespace et {

// The loaded library's functions. Throws et::Error, saying where it looked and how to install
// it, when no OIDN 2 library can be loaded (the same error on every later call).
const oidn::Api& oidn_api();

// The file oidn_api() loaded ("" before a successful load).
std::string oidn_library_file();

} // namespace et
