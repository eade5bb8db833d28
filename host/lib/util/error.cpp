#include "util/error.h"

#include <iostream>
#include <mutex>

namespace et {
namespace {
std::mutex sink_mutex;
WarningSink& sink() {
    static WarningSink s;
    return s;
}
} // namespace

void warn(const std::string& message) {
    std::lock_guard<std::mutex> lock(sink_mutex);
    if (sink())
        sink()(message);
    else
        std::cerr << "envtrace: warning: " << message << "\n";
}

WarningSink set_warning_sink(WarningSink s) {
    std::lock_guard<std::mutex> lock(sink_mutex);
    std::swap(sink(), s);
    return s;
}

} // namespace et
