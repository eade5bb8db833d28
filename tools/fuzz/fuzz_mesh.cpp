// libFuzzer harness: a PLY, glTF or GLB file through et::load_mesh (ply_loader, and gltf_loader
// with tinygltf). The first byte picks the extension (.ply, .gltf, .glb, modulo 3), the rest is
// the file; a .gltf input may end with a line "#---bin---" and the bytes of fuzz.bin, a buffer
// it can name by "uri": "fuzz.bin" (the seed corpus, tools/fuzz/make_corpus.py, is written so).
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
    if (size < 1)
        return 0;
    const etfuzz::FdCheck fds;
    static const char* const kExt[] = {".ply", ".gltf", ".glb"};
    const char* ext = kExt[data[0] % 3];
    ++data, --size;
    static constexpr std::string_view sep = "\n#---bin---\n";
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    size_t at = std::string_view::npos;
    if (std::strcmp(ext, ".gltf") == 0)
        at = text.find(sep);
    const size_t mesh_size = at == std::string_view::npos ? size : at;
    const std::string path = etfuzz::write_file(std::string("fuzz") + ext, data, mesh_size);
    if (at != std::string_view::npos)
        etfuzz::write_file("fuzz.bin", data + at + sep.size(), size - at - sep.size());
    else
        etfuzz::write_file("fuzz.bin", nullptr, 0);
    try {
        std::vector<et::Material> materials;
        et::TriangleSoup soup;
        et::load_mesh(path, glm::mat4(1.0f), -1, materials, soup);
        // What the renderer relies on: 3 positions, normals and uvs per triangle, finite
        // positions, unit normals, material indices in range.
        if (soup.positions.size() != 3 * soup.size() || soup.normals.size() != 3 * soup.size() ||
            soup.uvs.size() != 3 * soup.size())
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
