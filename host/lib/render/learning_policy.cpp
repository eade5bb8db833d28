#include "render/learning_policy.h"

#include "prepare/device_scene.h"
#include "render/visibility_learning.h"

namespace et {

std::unique_ptr<LearningPolicy> make_learning_policy(const DeviceScene& scene, bool batches) {
    if (scene.params.light_first == ETK_LIGHT_LEARNED)
        return std::make_unique<VisibilityLearning>(scene, batches);
    return nullptr;
}

} // namespace et
