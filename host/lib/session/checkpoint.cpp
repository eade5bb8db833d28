#include "session/checkpoint.h"

#include "util/error.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace et {

std::string default_state_path(const std::string& image) {
    return fs::path(image).replace_extension(".envtrace-state").string();
}

std::string partial_state_path(const std::string& image, int first, int end) {
    return fs::path(image).replace_extension("").string() + ".samples-" + std::to_string(first) +
           "-" + std::to_string(end) + ".envtrace-state";
}

void check_resume_state(const RenderState& state, const DeviceScene& scene, const SessionOptions& o,
                        const std::string& asked_by) {
    check_render_state(state, scene, o.state_path);
    const int first = o.partial ? o.first : 0;
    if (state.first != first)
        throw Error(o.state_path + ": the render state holds samples from index " +
                    std::to_string(state.first) + ", this render starts at " +
                    std::to_string(first));
    // Uncapped (a time limit or noise target without a user's spp): the settings' spp is no cap.
    const int asked = o.partial ? o.end - o.first : scene.settings.spp;
    if (!uncapped_render(o, scene.settings) && state.spp > asked)
        throw Error(o.state_path + ": the render state has " + std::to_string(state.spp) +
                    " spp, more than the " + std::to_string(asked) + " of " + asked_by +
                    " asked for; samples cannot be taken away");
}

} // namespace et
