#include "util/error.h"
#include "util/file_check.h"
#include "util/json_file.h"
#include "kernels/bsdf.h"
#include "load/mtl_options.h"
#include "load/scene.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>

namespace et {

glm::vec3 unit_face_normal(const glm::vec3 p[3]) {
    const glm::dvec3 c =
        glm::cross(glm::dvec3(p[1]) - glm::dvec3(p[0]), glm::dvec3(p[2]) - glm::dvec3(p[0]));
    const double len = glm::length(c);
    if (!(len > 0.0) || !std::isfinite(len))
        return glm::vec3(0.0f);
    return glm::vec3(c / len);
}

bool add_triangle(TriangleSoup& soup, const glm::vec3 p[3], const glm::vec3 n[3], int material,
                  const glm::vec2 uv[3]) {
    for (int k = 0; k < 3; ++k)
        if (!(std::fabs(p[k].x) <= kMaxSceneCoordinate) ||
            !(std::fabs(p[k].y) <= kMaxSceneCoordinate) ||
            !(std::fabs(p[k].z) <= kMaxSceneCoordinate)) // NaN fails too
            return false;
    const glm::vec3 ng = unit_face_normal(p);
    if (ng == glm::vec3(0.0f))
        return false;
    for (int k = 0; k < 3; ++k) {
        soup.positions.push_back(p[k]);
        // In double: a normal's squared length under- or overflows in float (1e-30, 1e30),
        // and a file need not write unit normals.
        const glm::dvec3 nk(n ? n[k] : ng);
        const double l = glm::length(nk);
        soup.normals.push_back(l > 0.0 && std::isfinite(l) ? glm::vec3(nk / l) : ng);
    }
    soup.material.push_back(material);
    // Kept parallel to the triangles even when a caller filled them without this function.
    soup.uvs.resize(3 * (soup.material.size() - 1), glm::vec2(0.0f));
    for (int k = 0; k < 3; ++k) {
        const glm::vec2 t = uv ? uv[k] : glm::vec2(0.0f);
        soup.uvs.push_back(std::isfinite(t.x) && std::isfinite(t.y) ? t : glm::vec2(0.0f));
    }
    return true;
}

void reverse_winding(TriangleSoup& soup, size_t from) {
    for (size_t t = from; t < soup.size(); ++t) {
        std::swap(soup.positions[3 * t + 1], soup.positions[3 * t + 2]);
        std::swap(soup.normals[3 * t + 1], soup.normals[3 * t + 2]);
        if (soup.uvs.size() >= 3 * t + 3)
            std::swap(soup.uvs[3 * t + 1], soup.uvs[3 * t + 2]);
    }
}

namespace {

// One line from tinyobjloader's messages: newlines become ';', at most a short excerpt.
std::string tinyobj_text(std::string msg) {
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' '))
        msg.pop_back();
    for (auto& c : msg)
        if (c == '\n')
            c = ';';
    return excerpt(msg, 200);
}

// A file an OBJ or MTL names, as written or, when relative, in the OBJ's folder `dir`. Files
// written on Windows separate folders by '\': where no file has the name as written, the one with
// '/' in their place is meant.
std::filesystem::path beside(const std::string& dir, const std::string& name) {
    auto resolve = [&](const std::string& n) {
        return std::filesystem::path(n).is_absolute() ? std::filesystem::path(n)
                                                      : std::filesystem::path(dir) / n;
    };
    const std::filesystem::path p = resolve(name);
    std::error_code ec;
    if (name.find('\\') == std::string::npos || std::filesystem::exists(p, ec))
        return p;
    std::string slashed = name;
    std::replace(slashed.begin(), slashed.end(), '\\', '/');
    const std::filesystem::path q = resolve(slashed);
    return std::filesystem::exists(q, ec) ? q : p;
}

// MTL files named by `mtllib`, resolved against the OBJ's folder and read through the regular-file
// check (a FIFO or /dev/zero named as mtllib is an error, not a hang). A missing MTL is a warning
// (tinyobjloader's), as before.
class MtlReader : public tinyobj::MaterialReader {
  public:
    explicit MtlReader(std::string dir) : dir_(std::move(dir)) {}
    bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* names, std::string* warning,
                    std::string* err) override {
        const std::filesystem::path p = beside(dir_, name);
        std::error_code ec;
        if (!std::filesystem::exists(p, ec)) {
            if (warning)
                *warning += "material file '" + excerpt(name, 60) + "' not found\n";
            return false;
        }
        std::istringstream in(normalise_mtl_texture_options(
            read_text_file(p.string(), kMaxMtlBytes, "MTL file"), p.string()));
        tinyobj::LoadMtl(names, materials, &in, warning, err);
        return true;
    }

  private:
    std::string dir_;
};

} // namespace

namespace {

// An MTL texture map of material `m` (map_Kd and the like), resolved against the OBJ's folder,
// with its -s (scale) and -o (offset) options as the texture's uv transform; -1 when absent.
int mtl_texture(const std::string& obj_path, const tinyobj::material_t& m, const char* key,
                const std::string& name, const tinyobj::texture_option_t& opt, TextureUse use,
                TextureSet& textures) {
    if (name.empty())
        return -1;
    const std::string where =
        obj_path + ": material '" + excerpt(m.name, 60) + "': " + key + " '" + excerpt(name) + "'";
    const glm::vec2 scale(opt.scale[0], opt.scale[1]),
        offset(opt.origin_offset[0], opt.origin_offset[1]);
    for (float v : {scale.x, scale.y, offset.x, offset.y})
        if (!std::isfinite(v) || std::fabs(v) > 1e6f)
            throw Error(where + ": -s / -o values must be finite and within +-1e6");
    const std::filesystem::path p =
        beside(std::filesystem::path(obj_path).parent_path().string(), name);
    return textures.add_file(p.string(), use, scale, offset, where);
}

// The corners a face may have: tinyobjloader's triangulation of a polygon takes time that
// grows with the square of its corners (40,000: 8 s; 500,000 in a 15 MB file: ~20 minutes).
constexpr size_t kMaxObjFaceCorners = 16384;

// An "f" line (from `p` to `end`, line `line` starting at `pos`): each corner's indices are
// integers within int's range, as tinyobjloader reads them (it took 4294967299 as 3, a number of
// 23 digits as another vertex, "3abc" as 3, without a word), and a face has at most
// kMaxObjFaceCorners corners.
void check_obj_face(const std::string& path, const std::string& text, size_t line, size_t pos,
                    size_t p, size_t end) {
    auto fail = [&](const std::string& problem) {
        throw Error(path + ": line " + std::to_string(line) + ": " + problem + " ('" +
                    excerpt(text.substr(pos, std::min<size_t>(end - pos, 80)), 60) + "')");
    };
    size_t corners = 0;
    while (p < end) {
        while (p < end && std::isspace(static_cast<unsigned char>(text[p])))
            ++p;
        if (p >= end || text[p] == '#')
            break;
        size_t q = p;
        while (q < end && !std::isspace(static_cast<unsigned char>(text[q])))
            ++q;
        const std::string corner = text.substr(p, q - p);
        // v, v/vt, v/vt/vn or v//vn: up to three fields, the first one required.
        size_t at = 0;
        for (int field = 0; field < 3 && at <= corner.size(); ++field) {
            size_t stop = corner.find('/', at);
            if (stop == std::string::npos)
                stop = corner.size();
            const std::string number = corner.substr(at, stop - at);
            if (!(number.empty() && field > 0)) {
                size_t k = number.size() > 0 && number[0] == '-' ? 1 : 0;
                bool digits = k < number.size();
                for (; k < number.size(); ++k)
                    digits = digits && std::isdigit(static_cast<unsigned char>(number[k]));
                if (!digits)
                    fail("face corner '" + excerpt(corner, 24) +
                         "' is not v, v/vt, v/vt/vn or v//vn");
                if (number.size() > 11 || std::llabs(std::stoll(number)) > 2147483647LL)
                    fail("index " + excerpt(number, 24) + " of face corner '" +
                         excerpt(corner, 24) + "' is beyond any vertex list");
            }
            if (stop == corner.size())
                break;
            at = stop + 1;
            if (field == 2)
                fail("face corner '" + excerpt(corner, 24) + "' has more than three indices");
        }
        if (++corners > kMaxObjFaceCorners)
            fail("a face of more than " + std::to_string(kMaxObjFaceCorners) +
                 " corners (split the polygon)");
        p = q;
    }
}

// tinyobjloader reads a vertex coordinate it cannot parse ("nan", "inf", a word) and a missing
// one ("v 1 2") as 0, which moves the vertex without a word. Every "v" line is checked here
// first: a word or a missing coordinate is an error naming the line; a coordinate that is not a
// finite float ("nan", "inf", 1e300) makes the vertex non-finite, so that the triangles using it
// are skipped with the loader's warning, as docs/scene-format.md says. Returns those vertices
// (0-based).
std::vector<size_t> check_obj_vertices(const std::string& path, const std::string& text) {
    std::vector<size_t> nonfinite;
    size_t line = 0, vertex = 0;
    for (size_t pos = 0; pos < text.size();) {
        size_t end = text.find('\n', pos);
        if (end == std::string::npos)
            end = text.size();
        ++line;
        size_t p = pos;
        while (p < end && (text[p] == ' ' || text[p] == '\t'))
            ++p;
        if (p < end && text[p] == 'f' &&
            (p + 1 == end || std::isspace(static_cast<unsigned char>(text[p + 1]))))
            check_obj_face(path, text, line, pos, p + 1, end);
        if (p < end && text[p] == 'v' &&
            (p + 1 == end || std::isspace(static_cast<unsigned char>(text[p + 1])))) {
            auto fail = [&](const std::string& problem) {
                throw Error(path + ": line " + std::to_string(line) + ": " + problem + " ('" +
                            excerpt(text.substr(pos, std::min<size_t>(end - pos, 80)), 60) + "')");
            };
            const char* c = text.c_str() + p + 1;
            const char* stop = text.c_str() + end;
            int n = 0;
            for (;;) {
                while (c < stop && std::isspace(static_cast<unsigned char>(*c)))
                    ++c;
                if (c >= stop || *c == '#')
                    break;
                const char* token_end = c;
                while (token_end < stop && !std::isspace(static_cast<unsigned char>(*token_end)))
                    ++token_end;
                const std::string token(c, token_end);
                char* after = nullptr;
                const double v = std::strtod(token.c_str(), &after);
                if (after != token.c_str() + token.size())
                    fail("vertex coordinate '" + excerpt(token, 20) + "' is not a number");
                if (n < 3 && !std::isfinite(static_cast<float>(v)) &&
                    (nonfinite.empty() || nonfinite.back() != vertex))
                    nonfinite.push_back(vertex);
                ++n;
                c = token_end;
            }
            if (n < 3)
                fail("a vertex needs three coordinates, this one has " + std::to_string(n));
            ++vertex;
        }
        pos = end + 1;
    }
    return nonfinite;
}

} // namespace

void load_obj(const std::string& path, const glm::mat4& transform, int override_material,
              std::vector<Material>& materials, TriangleSoup& out, TextureSet* textures) {
    const std::string text = read_text_file(path, kMaxMeshBytes, "OBJ file");
    const std::vector<size_t> nonfinite = check_obj_vertices(path, text);
    std::istringstream obj(text);
    tinyobj::attrib_t attrib_data;
    std::vector<tinyobj::shape_t> shapes_data;
    std::vector<tinyobj::material_t> mtls_data;
    std::string warning, error;
    MtlReader mtl_reader(std::filesystem::path(path).parent_path().string());
    if (!tinyobj::LoadObj(&attrib_data, &shapes_data, &mtls_data, &warning, &error, &obj,
                          &mtl_reader, /*triangulate=*/true, /*default_vcols_fallback=*/false)) {
        const std::string msg = tinyobj_text(error);
        throw Error(path + ": cannot read OBJ: " + (msg.empty() ? "no geometry found" : msg));
    }
    for (size_t k : nonfinite)
        if (3 * k + 2 < attrib_data.vertices.size())
            attrib_data.vertices[3 * k] = std::numeric_limits<float>::quiet_NaN();
    if (!error.empty()) // reported, but the geometry was read
        warning += error;
    if (!warning.empty())
        warn(path + ": " + tinyobj_text(warning));
    const auto& attrib = attrib_data;
    const auto& shapes = shapes_data;
    const auto& mtls = mtls_data;

    // OBJ/MTL materials map onto ours: Kd -> albedo, Ks/Ns -> specular/roughness.
    const int base = static_cast<int>(materials.size());
    if (override_material < 0) {
        for (const auto& m : mtls) {
            Material mat;
            mat.name = m.name;
            mat.albedo =
                glm::clamp(glm::vec3(m.diffuse[0], m.diffuse[1], m.diffuse[2]), 0.0f, 1.0f);
            mat.specular =
                glm::clamp(glm::vec3(m.specular[0], m.specular[1], m.specular[2]), 0.0f, 1.0f);
            float ns = std::isfinite(m.shininess) ? std::max(0.0f, m.shininess) : 0.0f;
            mat.roughness = std::clamp(std::sqrt(2.0f / (ns + 2.0f)), 0.01f, 1.0f);
            if (textures) {
                mat.albedo_tex = mtl_texture(path, m, "map_Kd", m.diffuse_texname, m.diffuse_texopt,
                                             TextureUse::colour, *textures);
                mat.specular_tex = mtl_texture(path, m, "map_Ks", m.specular_texname,
                                               m.specular_texopt, TextureUse::colour, *textures);
                // map_Pr (the PBR extension's roughness); else map_Ns, which Blender's exporter
                // writes for a roughness texture.
                mat.roughness_tex =
                    !m.roughness_texname.empty()
                        ? mtl_texture(path, m, "map_Pr", m.roughness_texname, m.roughness_texopt,
                                      TextureUse::data, *textures)
                        : mtl_texture(path, m, "map_Ns", m.specular_highlight_texname,
                                      m.specular_highlight_texopt, TextureUse::data, *textures);
            }
            mat.type = std::max({mat.specular.x, mat.specular.y, mat.specular.z}) > 0.0f ||
                               mat.specular_tex >= 0
                           ? ETK_MAT_MICROFACET
                           : ETK_MAT_DIFFUSE;
            // illum 4, 6, 7 (the MTL's refracting "glass" models) become a dielectric: index Ni
            // (1.5 where Ni is absent or <= 1: an unrefracting glass is rarely meant), tint Tf
            // (white where absent or black), smooth unless Pr (PBR roughness) is set.
            if (m.illum == 4 || m.illum == 6 || m.illum == 7) {
                const float pr = std::isfinite(m.roughness) ? m.roughness : 0.0f;
                mat.type = pr >= 1e-3f ? ETK_MAT_DIELECTRIC : ETK_MAT_SMOOTH_DIELECTRIC;
                mat.roughness = std::clamp(pr, 0.0f, 1.0f);
                mat.ior = std::isfinite(m.ior) && m.ior > 1.0f ? std::min(m.ior, 4.0f) : 1.5f;
                glm::vec3 tf(0.0f);
                for (int k = 0; k < 3; ++k)
                    tf[k] = std::isfinite(m.transmittance[k])
                                ? std::clamp(float(m.transmittance[k]), 0.0f, 1.0f)
                                : 0.0f;
                mat.albedo = std::max({tf.x, tf.y, tf.z}) > 0.0f ? tf : glm::vec3(1.0f);
                // A dielectric keeps its tint in albedo and its index in specular.x (bsdf.h):
                // colour maps would overwrite them, so glass takes no textures.
                if (mat.albedo_tex >= 0 || mat.specular_tex >= 0 || mat.roughness_tex >= 0)
                    warn(path + ": material " + m.name + ": a refracting material (illum " +
                         std::to_string(m.illum) + ") takes no texture maps; they are ignored");
                mat.albedo_tex = mat.specular_tex = mat.roughness_tex = -1;
            }
            materials.push_back(mat);
        }
    }
    int default_material = override_material;
    if (default_material < 0) {
        default_material = static_cast<int>(materials.size());
        Material grey;
        grey.name = path + ":default";
        materials.push_back(grey);
    }

    const glm::mat3 normal_m = glm::transpose(glm::inverse(glm::mat3(transform)));
    const size_t nv = attrib.vertices.size() / 3, nn = attrib.normals.size() / 3,
                 nt = attrib.texcoords.size() / 2;
    size_t dropped = 0, bad_index = 0;
    for (const auto& shape : shapes) {
        size_t offset = 0;
        for (size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
            const int fv = shape.mesh.num_face_vertices[f];
            if (fv != 3) { // points or lines, or a polygon tinyobjloader could not triangulate
                offset += fv;
                ++dropped;
                continue;
            }
            glm::vec3 p[3], n[3];
            glm::vec2 uv[3];
            bool has_normals = true, has_uvs = true, ok = true;
            for (int k = 0; k < 3; ++k) {
                const auto& idx = shape.mesh.indices[offset + k];
                if (idx.vertex_index < 0 || static_cast<size_t>(idx.vertex_index) >= nv) {
                    ok = false;
                    break;
                }
                const float* v = &attrib.vertices[3 * idx.vertex_index];
                p[k] = glm::vec3(transform * glm::vec4(v[0], v[1], v[2], 1.0f));
                if (idx.normal_index >= 0 && static_cast<size_t>(idx.normal_index) < nn) {
                    const float* vn = &attrib.normals[3 * idx.normal_index];
                    n[k] = normal_m * glm::vec3(vn[0], vn[1], vn[2]);
                } else {
                    has_normals = false;
                }
                if (idx.texcoord_index >= 0 && static_cast<size_t>(idx.texcoord_index) < nt) {
                    const float* vt = &attrib.texcoords[2 * idx.texcoord_index];
                    uv[k] = glm::vec2(vt[0], vt[1]);
                } else {
                    has_uvs = false;
                }
            }
            offset += 3;
            if (!ok) {
                ++bad_index;
                continue;
            }
            int mat = default_material;
            if (override_material < 0 && f < shape.mesh.material_ids.size()) {
                int id = shape.mesh.material_ids[f];
                if (id >= 0 && id < static_cast<int>(mtls.size()))
                    mat = base + id;
            }
            if (!add_triangle(out, p, has_normals ? n : nullptr, mat, has_uvs ? uv : nullptr))
                ++dropped;
        }
    }
    if (bad_index)
        warn(path + ": " + std::to_string(bad_index) +
             " faces with invalid vertex indices skipped");
    if (dropped)
        warn(path + ": " + std::to_string(dropped) +
             " degenerate, non-finite, out-of-range or non-triangle faces skipped");
}

} // namespace et
