// Where a render's resumable state lives, and whether a saved one continues this render. The
// state itself (what it holds, why a resumed render is bit-identical) is render/render_state.h.
#pragma once
#include "render/render_state.h"
#include "session/render_session.h"

#include <string>

namespace et {

// The state file of a render to `image`: "out.exr" -> "out.envtrace-state".
std::string default_state_path(const std::string& image);
// The state file of a farm task's samples first .. end-1: "out.samples-0-64.envtrace-state".
std::string partial_state_path(const std::string& image, int first, int end);

// Throws et::Error naming `o.state_path` unless `state` continues the render of `scene` that `o`
// asks for: the same render key and film, the same first sample index, and no more samples than
// asked for (samples cannot be taken away). `asked_by` names where the spp came from.
void check_resume_state(const RenderState& state, const DeviceScene& scene, const SessionOptions& o,
                        const std::string& asked_by);

} // namespace et
