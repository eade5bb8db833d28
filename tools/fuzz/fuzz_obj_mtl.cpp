// libFuzzer harness: an OBJ file and its MTL file through et::load_obj (tinyobjloader plus our
// mapping of faces and materials). The input is the OBJ text, optionally followed by a line
// "#---mtl---" and the text of fuzz.mtl, which the OBJ names with "mtllib fuzz.mtl" (the seed
// corpus, tools/fuzz/make_corpus.py, is written that way).
#include "fuzz_common.h"
#include "load/scene.h"

#include <cmath>
#include <cstring>
#include <string_view>

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    etfuzz::silence_warnings();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const etfuzz::FdCheck fds;
    static constexpr std::string_view sep = "#---mtl---\n";
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const size_t at = text.find(sep);
    const size_t obj_size = at == std::string_view::npos ? size : at;
    const std::string path = etfuzz::write_file("fuzz.obj", data, obj_size);
    if (at != std::string_view::npos)
        etfuzz::write_file("fuzz.mtl", data + at + sep.size(), size - at - sep.size());
    else
        etfuzz::write_file("fuzz.mtl", nullptr, 0);
    try {
        std::vector<et::Material> materials;
        et::TriangleSoup soup;
        et::load_obj(path, glm::mat4(1.0f), -1, materials, soup);
        // What the renderer relies on: 3 positions and normals per triangle, finite positions,
        // unit normals, material indices in range.
        if (soup.positions.size() != 3 * soup.size() || soup.normals.size() != 3 * soup.size())
            std::abort();
        for (size_t i = 0; i < soup.positions.size(); ++i) {
            const glm::vec3 p = soup.positions[i], n = soup.normals[i];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
                !(std::fabs(glm::length(n) - 1.0f) < 1e-3f))
                std::abort();
        }
        for (int m : soup.material)
            if (m < 0 || static_cast<size_t>(m) >= materials.size())
                std::abort();
    } catch (const et::Error&) {
    }
    return 0;
}
