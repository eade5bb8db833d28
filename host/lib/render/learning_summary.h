// A learning technique's decision and cost in one sentence for a person reading a render's
// report: what `auto` (or `visibility`) rendered with, how it decided, and what its learning
// took. The figures come from RenderStats::learning (VisibilityLearning::stats); the JSON keeps
// them all for programs.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace et {

// "" where nothing learned (a null or non-object `learning`).
std::string learning_summary(const nlohmann::json& learning);

} // namespace et
