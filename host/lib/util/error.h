// User-facing errors and warnings: one line each, naming the file and what is wrong.
#pragma once
#include <functional>
#include <stdexcept>
#include <string>

namespace et {

// Thrown for anything the user can fix (bad file, bad option); main prints it and exits non-zero.
struct Error : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Prints "envtrace: warning: MESSAGE" to stderr, or hands it to the installed sink (tests).
void warn(const std::string& message);
using WarningSink = std::function<void(const std::string&)>;
WarningSink set_warning_sink(WarningSink sink);

} // namespace et
