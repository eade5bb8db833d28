// A scene whose passes are slow on purpose, for tests of what happens inside a pass (a signal,
// a time limit): the camera inside a closed mirror sphere, every path 1000 bounces long (no
// roulette). 64x64 takes about 2 s a pass on two cores of the development machine.
#pragma once
#include <fstream>
#include <string>

namespace ett {

// Writes DIR/deep.json (size x size pixels) and returns its path.
inline std::string write_deep_scene(const std::string& dir, int size) {
    const std::string path = dir + "/deep.json";
    std::ofstream(path) << R"({
  "camera": {"eye": [0, 0, 0], "target": [0, 0, -1], "fov": 60},
  "film": {"width": )" << size
                        << R"(, "height": )" << size << R"(},
  "environment": {"sky": {"resolution": [64, 32], "sun_elevation": 35, "sun_azimuth": 40}},
  "materials": {"m": {"type": "mirror", "specular": 1}},
  "shapes": [{"type": "sphere", "radius": 2, "center": [0, 0, 0], "material": "m"}],
  "render": {"max_depth": 1000, "rr_depth": 1000}
}
)";
    return path;
}

} // namespace ett
