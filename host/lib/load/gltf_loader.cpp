// glTF 2.0 meshes (.gltf with embedded or external buffers, and .glb) through tinygltf (Debian's
// libtinygltf-dev): the triangle primitives of the default scene with the node hierarchy's
// transforms, POSITION, NORMAL and TEXCOORD_0, and the metallic-roughness material mapped onto
// envtrace's (docs/scene-format.md). The JSON is parsed and checked here first (prepare_json,
// prepare_glb), then tinygltf parses it and the GLB container and decodes the buffers; every
// accessor is bounds-checked here before it is read, since tinygltf 2.7 does not.
#include "util/error.h"
#include "util/file_check.h"
#include "util/json_file.h"
#include "kernels/bsdf.h"
#include "load/scene.h"

#include <tiny_gltf.h>

#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <map>
#include <vector>

namespace et {

namespace {

// File access for tinygltf: external buffers go through the regular-file check and size cap
// like every input (images never reach tinygltf: prepare_json removes them); paths are used as
// written (tinygltf's own ExpandFilePath runs wordexp on them, a shell expansion a scene file
// must not trigger). tinygltf looks for an external file beside the glTF, then in the working
// folder ("./uri"): the second is refused (user data: the glTF's folder), so a scene never
// depends on where envtrace was started.
bool fs_exists(const std::string& path, void* gltf_dir) {
    const std::string& dir = *static_cast<const std::string*>(gltf_dir);
    if (path.compare(0, 2, "./") == 0 && !dir.empty() && dir != ".")
        return false;
    std::error_code ec;
    return std::filesystem::exists(path, ec);
}
std::string fs_expand(const std::string& path, void*) {
    return path;
}
bool fs_read(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
    try {
        const std::string bytes = read_regular_file(path, kMaxMeshBytes, "glTF buffer");
        out->assign(bytes.begin(), bytes.end());
        return true;
    } catch (const std::exception& e) {
        if (err)
            *err += std::string(e.what()) + "\n";
        return false;
    }
}
bool fs_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err)
        *err += "envtrace does not write glTF files\n";
    return false;
}
// Textures are not mapped yet: images are not decoded (a warning names the materials).
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                const unsigned char*, int, void*) {
    return true;
}

std::string one_line(std::string msg) {
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' '))
        msg.pop_back();
    for (auto& c : msg)
        if (c == '\n')
            c = ';';
    return excerpt(msg, 300);
}

uint32_t le32(const std::string& b, size_t at) {
    uint32_t v = 0;
    for (int k = 3; k >= 0; --k)
        v = (v << 8) | static_cast<unsigned char>(b[at + k]);
    return v;
}
void put_le32(std::string& b, uint32_t v) {
    for (int k = 0; k < 4; ++k)
        b += static_cast<char>((v >> (8 * k)) & 0xFF);
}

// The glTF JSON as tinygltf gets it: parsed here first (depth and number checks, errors with
// line and column), the buffers' declared sizes summed against the mesh size cap (tinygltf
// allocates every buffer, and a GLB's buffers without a uri each copy the BIN chunk), and the
// "images" removed, so that tinygltf neither reads image files nor decodes images (textures are
// not mapped yet; the no-op image loader below is a second guard).
// The sizes, offsets and indices that tinygltf reads into unsigned or int fields: a negative or
// fractional value there is taken as 0 (or truncated) without a word, which reads the wrong
// bytes or the wrong accessor, so each must be a whole number >= 0 where it is given.
void check_indices_and_sizes(const std::string& name, const nlohmann::json& j) {
    auto check = [&](const nlohmann::json& value, const std::string& where) {
        const bool whole =
            value.is_number_unsigned() || (value.is_number_float() && value.get<double>() >= 0.0 &&
                                           value.get<double>() <= 9007199254740992.0 &&
                                           std::floor(value.get<double>()) == value.get<double>());
        if (!whole)
            throw Error(name + ": glTF: " + where + ": expected a whole number >= 0, got " +
                        json_excerpt(value));
    };
    auto each = [&](const char* array, std::initializer_list<const char*> keys) {
        const auto a = j.find(array);
        if (a == j.end() || !a->is_array())
            return;
        for (size_t i = 0; i < a->size(); ++i) {
            const auto& item = (*a)[i];
            if (!item.is_object())
                continue;
            const std::string at = std::string(array) + "[" + std::to_string(i) + "]";
            for (const char* key : keys)
                if (item.contains(key))
                    check(item[key], at + "." + key);
            if (std::string(array) == "meshes" && item.contains("primitives") &&
                item["primitives"].is_array())
                for (size_t k = 0; k < item["primitives"].size(); ++k) {
                    const auto& p = item["primitives"][k];
                    if (!p.is_object())
                        continue;
                    const std::string pat = at + ".primitives[" + std::to_string(k) + "]";
                    for (const char* key : {"indices", "material", "mode"})
                        if (p.contains(key))
                            check(p[key], pat + "." + key);
                    if (p.contains("attributes") && p["attributes"].is_object())
                        for (const auto& [attr, v] : p["attributes"].items())
                            check(v, pat + ".attributes." + attr);
                }
            for (const char* list : {"children", "nodes"})
                if (item.contains(list) && item[list].is_array())
                    for (size_t k = 0; k < item[list].size(); ++k)
                        check(item[list][k], at + "." + list + "[" + std::to_string(k) + "]");
        }
    };
    each("buffers", {"byteLength"});
    each("bufferViews", {"buffer", "byteOffset", "byteLength", "byteStride"});
    each("accessors", {"bufferView", "byteOffset", "count", "componentType"});
    each("meshes", {});
    each("nodes", {"mesh"});
    each("scenes", {});
    if (j.contains("scene"))
        check(j["scene"], "scene");
}

std::string prepare_json(const std::string& name, const std::string& text) {
    nlohmann::json j = parse_json_text(name, text);
    if (!j.is_object())
        throw Error(name + ": glTF: the JSON is not an object");
    check_indices_and_sizes(name, j);
    const auto buffers = j.find("buffers");
    if (buffers != j.end() && buffers->is_array()) {
        double total = 0.0;
        for (const auto& b : *buffers)
            if (b.is_object() && b.contains("byteLength") && b["byteLength"].is_number())
                total += std::max(0.0, b["byteLength"].get<double>());
        if (total > double(kMaxMeshBytes))
            throw Error(name + ": glTF: the buffers declare " + byte_text(uint64_t(total)) +
                        " in all, more than the " + byte_text(kMaxMeshBytes) + " read at most");
    }
    j.erase("images");
    return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// A .glb with its JSON chunk replaced by prepare_json's; the BIN chunk as it was. The header is
// checked here so that its errors name the problem (tinygltf says only "Invalid glTF binary").
std::string prepare_glb(const std::string& path, const std::string& bytes) {
    auto fail = [&](const std::string& problem) { throw Error(path + ": GLB: " + problem); };
    if (bytes.size() < 20)
        fail("the file (" + std::to_string(bytes.size()) +
             " bytes) is shorter than the 20-byte header");
    if (bytes.compare(0, 4, "glTF") != 0)
        fail("it does not start with 'glTF'");
    if (le32(bytes, 4) != 2)
        fail("version " + std::to_string(le32(bytes, 4)) + ", not 2");
    const uint64_t length = le32(bytes, 8), json_len = le32(bytes, 12);
    if (length > bytes.size())
        fail("the header's length " + std::to_string(length) + " is more than the file's " +
             std::to_string(bytes.size()) + " bytes (truncated?)");
    if (le32(bytes, 16) != 0x4E4F534A)
        fail("the first chunk is not JSON");
    if (20 + json_len > length)
        fail("the JSON chunk (" + std::to_string(json_len) + " bytes at byte 20) runs past the " +
             std::to_string(length) + " bytes of the file");
    std::string json = prepare_json(path + " (JSON chunk)", bytes.substr(20, json_len));
    while (json.size() % 4)
        json += ' ';
    const std::string rest = bytes.substr(20 + json_len, length - 20 - json_len);
    std::string out = "glTF";
    put_le32(out, 2);
    put_le32(out, static_cast<uint32_t>(20 + json.size() + rest.size()));
    put_le32(out, static_cast<uint32_t>(json.size()));
    put_le32(out, 0x4E4F534A);
    return out + json + rest;
}

// More triangles than this from one glTF file is refused: node hierarchies instance meshes, so
// the count is not bounded by the file's size (about 13 GiB of triangle soup).
constexpr size_t kMaxGltfTriangles = size_t(1) << 27;

class GltfReader {
  public:
    GltfReader(const std::string& path, const tinygltf::Model& model) : path_(path), model_(model) {
        for (const auto* list : {&model.extensionsUsed, &model.extensionsRequired})
            for (const std::string& e : *list)
                quantized_ = quantized_ || e == "KHR_mesh_quantization";
    }

    [[noreturn]] void fail(const std::string& problem) const {
        throw Error(path_ + ": glTF: " + problem);
    }

    // The accessor's elements as up to 4 floats each (normalized integers mapped to [0, 1] or
    // [-1, 1]), after checking that every byte read lies inside its buffer. `type`: the vector
    // type the attribute must have (glTF 2.0: VEC3 for POSITION and NORMAL, VEC2 for
    // TEXCOORD_0); floats, or with `normalized_ok` normalized unsigned bytes or shorts (what
    // the specification allows a TEXCOORD), or under KHR_mesh_quantization any byte or short.
    // Anything else read as floats would be garbage.
    std::vector<glm::vec4> floats(int index, const char* what, int type,
                                  bool normalized_ok = false) const {
        const tinygltf::Accessor& a = accessor(index, what);
        const int comps = tinygltf::GetNumComponentsInType(a.type);
        if (a.type != type)
            fail(std::string(what) + ": accessor " + std::to_string(index) + " is a " +
                 type_name(a.type) + ", not a " + type_name(type));
        const bool is_float = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
        const bool is_unorm =
            a.normalized && (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                             a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
        const bool is_short_int = a.componentType == TINYGLTF_COMPONENT_TYPE_BYTE ||
                                  a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                  a.componentType == TINYGLTF_COMPONENT_TYPE_SHORT ||
                                  a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
        if (!is_float && !(normalized_ok && is_unorm) && !(quantized_ && is_short_int))
            fail(std::string(what) + ": accessor " + std::to_string(index) + " has componentType " +
                 std::to_string(a.componentType) +
                 (normalized_ok ? " (expected 5126, float, or normalized 5121 or 5123)"
                                : " (expected 5126, float)"));
        const View view = checked_view(a, index, what, comps); // before allocating
        std::vector<glm::vec4> v(a.count, glm::vec4(0.0f));
        for (size_t i = 0; i < a.count; ++i)
            for (int c = 0; c < comps; ++c)
                v[i][c] = float(view.get(i, c, a.componentType, a.normalized));
        return v;
    }

    std::vector<uint32_t> indices(int index) const {
        const tinygltf::Accessor& a = accessor(index, "indices");
        if (a.type != TINYGLTF_TYPE_SCALAR ||
            (a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
             a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
             a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
            fail("indices: accessor " + std::to_string(index) +
                 " is not a scalar of unsigned integers");
        const View view = checked_view(a, index, "indices", 1); // before allocating
        std::vector<uint32_t> v(a.count);
        for (size_t i = 0; i < a.count; ++i)
            v[i] = uint32_t(view.get(i, 0, a.componentType, false));
        return v;
    }

  private:
    bool quantized_ = false; // KHR_mesh_quantization: attributes may be bytes or shorts

    static std::string type_name(int type) {
        switch (type) {
        case TINYGLTF_TYPE_SCALAR:
            return "SCALAR";
        case TINYGLTF_TYPE_VEC2:
            return "VEC2";
        case TINYGLTF_TYPE_VEC3:
            return "VEC3";
        case TINYGLTF_TYPE_VEC4:
            return "VEC4";
        default:
            return "type " + std::to_string(type);
        }
    }

    const tinygltf::Accessor& accessor(int index, const char* what) const {
        if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
            fail(std::string(what) + ": accessor " + std::to_string(index) + " does not exist");
        const tinygltf::Accessor& a = model_.accessors[index];
        if (a.sparse.isSparse)
            fail(std::string(what) + ": accessor " + std::to_string(index) +
                 " is sparse, which envtrace does not read");
        return a;
    }

    // An accessor's bytes: element i's component c is at base + i * stride + c * csize.
    struct View {
        const unsigned char* base = nullptr;
        size_t stride = 0, csize = 0;
        double get(size_t i, int c, int type, bool normalized) const {
            return component(base + i * stride + c * csize, type, normalized);
        }
    };

    // Checks that every byte the accessor's elements occupy lies inside its buffer.
    View checked_view(const tinygltf::Accessor& a, int index, const char* what, int comps) const {
        const std::string where = std::string(what) + ": accessor " + std::to_string(index);
        if (a.count == 0)
            return View();
        if (a.bufferView < 0 || static_cast<size_t>(a.bufferView) >= model_.bufferViews.size())
            fail(where + " has no valid bufferView");
        const tinygltf::BufferView& bv = model_.bufferViews[a.bufferView];
        if (bv.buffer < 0 || static_cast<size_t>(bv.buffer) >= model_.buffers.size())
            fail(where + ": bufferView " + std::to_string(a.bufferView) + " has no valid buffer");
        const std::vector<unsigned char>& buf = model_.buffers[bv.buffer].data;
        const int csize = tinygltf::GetComponentSizeInBytes(a.componentType);
        if (csize <= 0)
            fail(where + ": unknown componentType " + std::to_string(a.componentType));
        const uint64_t elem = uint64_t(csize) * comps;
        const uint64_t stride = bv.byteStride ? bv.byteStride : elem;
        if (stride < elem || stride > (uint64_t(1) << 20))
            fail(where + ": byteStride " + std::to_string(bv.byteStride) +
                 " is smaller than an element or absurd");
        // Every byte of the last element must lie inside the view, and the view inside its
        // buffer; checked in 64-bit arithmetic with the counts bounded first.
        if (bv.byteOffset > buf.size() || bv.byteLength > buf.size() - bv.byteOffset)
            fail(where + ": bufferView " + std::to_string(a.bufferView) +
                 " lies outside its buffer (" + std::to_string(buf.size()) + " bytes)");
        if (a.count > bv.byteLength || a.byteOffset > bv.byteLength ||
            uint64_t(a.byteOffset) + stride * (a.count - 1) + elem > bv.byteLength)
            fail(where + ": " + std::to_string(a.count) +
                 " elements run past the end of bufferView " + std::to_string(a.bufferView) + " (" +
                 std::to_string(bv.byteLength) + " bytes)");
        View view;
        view.base = buf.data() + bv.byteOffset + a.byteOffset;
        view.stride = stride;
        view.csize = static_cast<size_t>(csize);
        return view;
    }

    static double component(const unsigned char* p, int type, bool normalized) {
        auto get = [p](auto v) {
            std::memcpy(&v, p, sizeof v);
            return v;
        };
        switch (type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return get(float());
        case TINYGLTF_COMPONENT_TYPE_DOUBLE:
            return get(double());
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return normalized ? get(uint8_t()) / 255.0 : get(uint8_t());
        case TINYGLTF_COMPONENT_TYPE_BYTE:
            return normalized ? std::max(get(int8_t()) / 127.0, -1.0) : get(int8_t());
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return normalized ? get(uint16_t()) / 65535.0 : get(uint16_t());
        case TINYGLTF_COMPONENT_TYPE_SHORT:
            return normalized ? std::max(get(int16_t()) / 32767.0, -1.0) : get(int16_t());
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
            return get(uint32_t());
        case TINYGLTF_COMPONENT_TYPE_INT:
            return get(int32_t());
        }
        return 0.0;
    }

    const std::string& path_;
    const tinygltf::Model& model_;
};

glm::mat4 node_matrix(const tinygltf::Node& n, const GltfReader& r, size_t index) {
    glm::dmat4 m(1.0);
    if (n.matrix.size() == 16) {
        m = glm::make_mat4(n.matrix.data()); // column-major, as glTF stores it
    } else {
        glm::dvec3 t(0.0), s(1.0);
        glm::dquat q(1.0, 0.0, 0.0, 0.0);
        if (n.translation.size() == 3)
            t = glm::make_vec3(n.translation.data());
        if (n.scale.size() == 3)
            s = glm::make_vec3(n.scale.data());
        if (n.rotation.size() == 4) // glTF: (x, y, z, w)
            q = glm::normalize(
                glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]));
        m = glm::translate(glm::dmat4(1.0), t) * glm::mat4_cast(q) * glm::scale(glm::dmat4(1.0), s);
    }
    for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 4; ++k)
            if (!std::isfinite(m[c][k]) || std::fabs(m[c][k]) > 1e30)
                r.fail("node " + std::to_string(index) + ": its transform is not finite");
    return glm::mat4(m);
}

} // namespace

void load_gltf(const std::string& path, const glm::mat4& transform, int override_material,
               std::vector<Material>& materials, TriangleSoup& out) {
    const std::string bytes = read_regular_file(path, kMaxMeshBytes, "glTF file");
    const std::string ext = lower_extension(path);
    const bool binary = ext == ".glb" || bytes.compare(0, 4, "glTF") == 0;
    const std::string prepared = binary ? prepare_glb(path, bytes) : prepare_json(path, bytes);
    if (prepared.size() > std::numeric_limits<unsigned int>::max())
        throw Error(path + ": glTF: the file is more than 4 GiB");

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    tinygltf::Model model;
    std::string err, warning;
    const std::string dir = std::filesystem::path(path).parent_path().string();
    loader.SetFsCallbacks({fs_exists, fs_expand, fs_read, fs_write,
                           const_cast<void*>(static_cast<const void*>(&dir))});
    bool ok = false;
    try {
        ok = binary ? loader.LoadBinaryFromMemory(
                          &model, &err, &warning,
                          reinterpret_cast<const unsigned char*>(prepared.data()),
                          static_cast<unsigned int>(prepared.size()), dir)
                    : loader.LoadASCIIFromString(&model, &err, &warning, prepared.data(),
                                                 static_cast<unsigned int>(prepared.size()), dir);
    } catch (const std::exception& e) {
        err += e.what();
        ok = false;
    }
    if (!ok)
        throw Error(path + ": cannot read glTF: " +
                    (err.empty() ? std::string("unknown error") : one_line(err)));
    if (!warning.empty())
        warn(path + ": " + one_line(warning));
    const GltfReader r(path, model);
    // A required extension changes what the data means (Draco or meshopt compression leaves the
    // accessors without a bufferView); those whose meaning envtrace keeps or may ignore pass.
    for (const std::string& e : model.extensionsRequired)
        if (e != "KHR_mesh_quantization" && e != "KHR_texture_transform" &&
            e.rfind("KHR_materials_", 0) != 0)
            r.fail("it requires the extension '" + excerpt(e, 60) +
                   "', which envtrace does not read");

    // The default scene's root nodes; without a scene, every node that is no other's child.
    std::vector<int> roots;
    if (!model.scenes.empty()) {
        const int s = model.defaultScene >= 0 ? model.defaultScene : 0;
        if (static_cast<size_t>(s) >= model.scenes.size())
            r.fail("the default scene " + std::to_string(s) + " does not exist");
        roots = model.scenes[s].nodes;
    } else {
        std::vector<char> child(model.nodes.size(), 0);
        for (const auto& n : model.nodes)
            for (int c : n.children)
                if (c >= 0 && static_cast<size_t>(c) < child.size())
                    child[c] = 1;
        for (size_t i = 0; i < model.nodes.size(); ++i)
            if (!child[i])
                roots.push_back(static_cast<int>(i));
    }

    // glTF materials become envtrace materials on first use; -1: none given.
    std::map<int, int> mat_of;
    int default_material = override_material;
    auto material_for = [&](int gm) {
        if (override_material >= 0)
            return override_material;
        if (gm < 0 || static_cast<size_t>(gm) >= model.materials.size()) {
            if (default_material < 0) {
                default_material = static_cast<int>(materials.size());
                Material grey;
                grey.name = path + ":default";
                materials.push_back(grey);
            }
            return default_material;
        }
        auto it = mat_of.find(gm);
        if (it != mat_of.end())
            return it->second;
        const tinygltf::Material& g = model.materials[gm];
        const auto& pbr = g.pbrMetallicRoughness;
        glm::vec3 base(1.0f);
        if (pbr.baseColorFactor.size() >= 3)
            for (int k = 0; k < 3; ++k)
                base[k] = std::isfinite(pbr.baseColorFactor[k])
                              ? std::clamp(float(pbr.baseColorFactor[k]), 0.0f, 1.0f)
                              : 0.0f;
        const float metallic = std::isfinite(pbr.metallicFactor)
                                   ? std::clamp(float(pbr.metallicFactor), 0.0f, 1.0f)
                                   : 0.0f;
        const float rough = std::isfinite(pbr.roughnessFactor)
                                ? std::clamp(float(pbr.roughnessFactor), 0.0f, 1.0f)
                                : 1.0f;
        Material m;
        m.name = g.name.empty() ? path + ":material" + std::to_string(gm) : g.name;
        // The glTF BRDF's usual split: F0 runs from 0.04 (a dielectric, envtrace's "plastic")
        // to the base colour (a metal), and the Lambertian base fades out as metallic grows.
        m.type = ETK_MAT_MICROFACET;
        m.specular = glm::mix(glm::vec3(0.04f), base, metallic);
        m.albedo = base * (1.0f - metallic);
        m.roughness = rough * rough; // glTF's perceptual roughness squared is the GGX alpha
        if (pbr.baseColorTexture.index >= 0 || pbr.metallicRoughnessTexture.index >= 0 ||
            g.normalTexture.index >= 0)
            warn(path + ": material '" + excerpt(m.name, 60) +
                 "': textures are not read from glTF yet; its factors are used");
        const int id = static_cast<int>(materials.size());
        materials.push_back(m);
        mat_of[gm] = id;
        return id;
    };

    size_t skipped_mode = 0, skipped_nopos = 0, dropped = 0, triangles = 0;
    std::vector<int> visits(model.nodes.size(), 0);
    struct Item {
        int node;
        glm::mat4 parent;
        int depth;
    };
    std::vector<Item> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it)
        stack.push_back({*it, transform, 0});
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        if (item.node < 0 || static_cast<size_t>(item.node) >= model.nodes.size())
            r.fail("node " + std::to_string(item.node) + " does not exist");
        if (++visits[item.node] > 1 || item.depth > 1024)
            r.fail("node " + std::to_string(item.node) +
                   " is reached twice: the node hierarchy is not a tree");
        const tinygltf::Node& node = model.nodes[item.node];
        const glm::mat4 world = item.parent * node_matrix(node, r, item.node);
        for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
            stack.push_back({*c, world, item.depth + 1});
        if (node.mesh < 0)
            continue;
        if (static_cast<size_t>(node.mesh) >= model.meshes.size())
            r.fail("node " + std::to_string(item.node) + ": mesh " + std::to_string(node.mesh) +
                   " does not exist");
        const glm::mat3 normal_m = glm::transpose(glm::inverse(glm::mat3(world)));
        // A mirroring transform turns the winding around; glTF keeps the front face by flipping
        // it back.
        const bool flip = glm::determinant(glm::mat3(world)) < 0.0f;
        const tinygltf::Mesh& mesh = model.meshes[node.mesh];
        for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
            const tinygltf::Primitive& prim = mesh.primitives[pi];
            if (prim.mode != TINYGLTF_MODE_TRIANGLES) {
                ++skipped_mode;
                continue;
            }
            const auto attr = [&](const char* name) {
                auto it = prim.attributes.find(name);
                return it == prim.attributes.end() ? -1 : it->second;
            };
            if (attr("POSITION") < 0) {
                ++skipped_nopos;
                continue;
            }
            const std::string where =
                "mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(pi);
            const auto P =
                r.floats(attr("POSITION"), (where + " POSITION").c_str(), TINYGLTF_TYPE_VEC3);
            std::vector<glm::vec4> N, T;
            if (attr("NORMAL") >= 0)
                N = r.floats(attr("NORMAL"), (where + " NORMAL").c_str(), TINYGLTF_TYPE_VEC3);
            if (attr("TEXCOORD_0") >= 0)
                T = r.floats(attr("TEXCOORD_0"), (where + " TEXCOORD_0").c_str(),
                             TINYGLTF_TYPE_VEC2, true);
            if (prim.material >= 0 && static_cast<size_t>(prim.material) >= model.materials.size())
                r.fail(where + ": material " + std::to_string(prim.material) + " does not exist (" +
                       std::to_string(model.materials.size()) + " materials)");
            if ((!N.empty() && N.size() != P.size()) || (!T.empty() && T.size() != P.size()))
                r.fail(where + ": NORMAL or TEXCOORD_0 has a count other than POSITION's");
            for (const auto& p : P)
                if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                    r.fail(where + ": a POSITION is not finite");
            std::vector<uint32_t> idx;
            if (prim.indices >= 0) {
                idx = r.indices(prim.indices);
                for (uint32_t i : idx)
                    if (i >= P.size())
                        r.fail(where + ": index " + std::to_string(i) + " is out of range (" +
                               std::to_string(P.size()) + " vertices)");
            } else {
                idx.resize(P.size());
                for (size_t i = 0; i < idx.size(); ++i)
                    idx[i] = static_cast<uint32_t>(i);
            }
            if (idx.size() % 3 != 0)
                warn(path + ": " + where + ": " + std::to_string(idx.size()) +
                     " indices are not a whole number of triangles; the rest is ignored");
            if (idx.size() / 3 > kMaxGltfTriangles - triangles)
                r.fail(where + " (node " + std::to_string(item.node) + "): more than " +
                       std::to_string(kMaxGltfTriangles) + " triangles in all");
            const int mat = material_for(prim.material);
            for (size_t t = 0; t + 2 < idx.size(); t += 3) {
                glm::vec3 p[3], n[3];
                glm::vec2 uv[3];
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = idx[t + (flip && k ? 3 - k : k)];
                    p[k] = glm::vec3(world * glm::vec4(glm::vec3(P[v]), 1.0f));
                    if (!N.empty())
                        n[k] = normal_m * glm::vec3(N[v]);
                    if (!T.empty()) // glTF's v runs down the image, OBJ's (and envtrace's) up
                        uv[k] = glm::vec2(T[v].x, 1.0f - T[v].y);
                }
                ++triangles;
                if (!add_triangle(out, p, N.empty() ? nullptr : n, mat, T.empty() ? nullptr : uv))
                    ++dropped;
            }
        }
    }
    if (skipped_mode)
        warn(path + ": " + std::to_string(skipped_mode) +
             " primitives that are not triangle lists (points, lines, strips, fans) skipped");
    if (skipped_nopos)
        warn(path + ": " + std::to_string(skipped_nopos) + " primitives without POSITION skipped");
    if (dropped)
        warn(path + ": " + std::to_string(dropped) +
             " degenerate, non-finite or out-of-range triangles skipped (of " +
             std::to_string(triangles) + ")");
}

} // namespace et
