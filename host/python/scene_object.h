// The scene object the binding's files share: a loaded scene and the folder its edits resolve
// files against; and the conversions of its inputs.
#pragma once
#include "bindings.h"

#include "image/image_io.h"
#include "load/scene.h"

#include <string>

namespace et::py_bind {

struct PyScene {
    Scene scene;
    std::string dir;
    // Applies an edit (JSON text in the scene file's schema) in place: all or nothing.
    void edit(const std::string& edit_json, const std::string& where);
};

// An H x W x 3 array as a linear RGB image; et::Error naming `what` for another shape.
RgbImage rgb_image(const py::handle& a, const std::string& what);

} // namespace et::py_bind
