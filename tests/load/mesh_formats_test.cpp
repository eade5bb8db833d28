// PLY and glTF 2.0 meshes (host/lib/load/ply_loader.cpp, gltf_loader.cpp, mesh_loader.cpp): the
// same tetrahedron written as OBJ, ASCII PLY, binary PLY (both byte orders), glTF with a base64
// buffer and GLB loads to the same triangles; polygons are fanned; glTF node transforms (TRS and
// matrix, through a hierarchy) and materials are applied; hostile files (missing, not regular,
// truncated, indices out of range, absurd counts, NaN) are errors naming the file, not crashes.
#include "load/scene.h"
#include "kernels/bsdf.h"
#include "util/error.h"
#include "test_data.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <filesystem>
#include <random>
#include <sys/stat.h>

namespace {

void write_file(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

struct Loaded {
    std::vector<et::Material> materials;
    et::TriangleSoup soup;
};

Loaded load(const std::string& path, const glm::mat4& m = glm::mat4(1.0f), int override_mat = -1) {
    Loaded l;
    if (override_mat >= 0)
        l.materials.resize(override_mat + 1);
    et::load_mesh(path, m, override_mat, l.materials, l.soup);
    return l;
}

// The triangles as sorted lists of rounded corners, so loaders that order faces or rotate
// corners differently still compare equal (winding is compared through the normals).
using Tri = std::array<std::array<long, 3>, 3>;
std::vector<Tri> triangles(const et::TriangleSoup& s) {
    std::vector<Tri> out;
    for (size_t t = 0; t < s.size(); ++t) {
        Tri tri;
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c)
                tri[k][c] = std::lround(s.positions[3 * t + k][c] * 1e4f);
        // Rotate so the smallest corner comes first (keeps the winding).
        const int first = static_cast<int>(std::min_element(tri.begin(), tri.end()) - tri.begin());
        std::rotate(tri.begin(), tri.begin() + first, tri.end());
        out.push_back(tri);
    }
    std::sort(out.begin(), out.end());
    return out;
}

void expect_same_geometry(const Loaded& a, const Loaded& b, const std::string& what) {
    ASSERT_EQ(a.soup.size(), b.soup.size()) << what;
    EXPECT_EQ(triangles(a.soup), triangles(b.soup)) << what;
}

// A unit tetrahedron, outward-facing counter-clockwise triangles.
const float kTetV[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
const int kTetF[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

std::string tet_obj() {
    std::string s;
    for (auto& v : kTetV)
        s += "v " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) +
             "\n";
    for (auto& f : kTetF)
        s += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " +
             std::to_string(f[2] + 1) + "\n";
    return s;
}

std::string tet_ply_ascii() {
    std::string s = "ply\nformat ascii 1.0\ncomment envtrace test\nelement vertex 4\n"
                    "property float x\nproperty float y\nproperty float z\nelement face 4\n"
                    "property list uchar int vertex_indices\nend_header\n";
    for (auto& v : kTetV)
        s += std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
    for (auto& f : kTetF)
        s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
             "\n";
    return s;
}

template <class T> void put(std::string& s, T v, bool big) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big)
        std::reverse(b, b + sizeof(T));
    s.append(b, sizeof(T));
}

std::string tet_ply_binary(bool big, int vertex_count = 4) {
    std::string s = std::string("ply\nformat ") +
                    (big ? "binary_big_endian" : "binary_little_endian") + " 1.0\nelement vertex " +
                    std::to_string(vertex_count) +
                    "\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\nelement face 4\n"
                    "property list uchar uint vertex_indices\nproperty int flags\nend_header\n";
    for (auto& v : kTetV) {
        for (float c : v)
            put(s, c, big);
        put(s, uint8_t(200), big); // an extra property, skipped
    }
    for (auto& f : kTetF) {
        put(s, uint8_t(3), big);
        for (int i : f)
            put(s, uint32_t(i), big);
        put(s, int32_t(-7), big);
    }
    return s;
}

std::string base64(const std::string& in) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        uint32_t n = uint8_t(in[i]) << 16 | uint8_t(in[i + 1]) << 8 | uint8_t(in[i + 2]);
        for (int s = 18; s >= 0; s -= 6)
            out += k[(n >> s) & 63];
    }
    if (i + 1 == in.size()) {
        uint32_t n = uint8_t(in[i]) << 16;
        out += k[(n >> 18) & 63];
        out += k[(n >> 12) & 63];
        out += "==";
    } else if (i + 2 == in.size()) {
        uint32_t n = uint8_t(in[i]) << 16 | uint8_t(in[i + 1]) << 8;
        out += k[(n >> 18) & 63];
        out += k[(n >> 12) & 63];
        out += k[(n >> 6) & 63];
        out += '=';
    }
    return out;
}

// The tetrahedron's buffer: 4 float3 positions (48 bytes), then 12 uint16 indices (24 bytes).
std::string tet_buffer(int bad_index = -1) {
    std::string b;
    for (auto& v : kTetV)
        for (float c : v)
            put(b, c, false);
    for (auto& f : kTetF)
        for (int i : f)
            put(b, uint16_t(i), false);
    if (bad_index >= 0)
        std::memcpy(&b[48 + 2 * 5], &bad_index, 2);
    return b;
}

// The glTF JSON around that buffer: `uri` (absent in GLB), `nodes` and `scene_nodes` as JSON
// text, the position accessor's `count`, and materials.
std::string tet_gltf(const std::string& uri, const std::string& nodes = R"([{"mesh": 0}])",
                     const std::string& scene_nodes = "[0]", int count = 4,
                     const std::string& material = "") {
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": )" + scene_nodes +
           R"(}], "nodes": )" + nodes +
           R"(, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1)" +
           (material.empty() ? "" : R"(, "material": 0)") + R"(}]}],)" +
           (material.empty() ? "" : R"("materials": [)" + material + "],") +
           R"("buffers": [{"byteLength": 72)" + (uri.empty() ? "" : R"(, "uri": ")" + uri + "\"") +
           R"(}], "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
              {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": )" +
           std::to_string(count) + R"(, "type": "VEC3"},
              {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}]})";
}

std::string data_uri(const std::string& buffer) {
    return "data:application/octet-stream;base64," + base64(buffer);
}

std::string glb(std::string json, std::string bin) {
    while (json.size() % 4)
        json += ' ';
    while (bin.size() % 4)
        bin += '\0';
    std::string s = "glTF";
    put(s, uint32_t(2), false);
    put(s, uint32_t(12 + 8 + json.size() + 8 + bin.size()), false);
    put(s, uint32_t(json.size()), false);
    put(s, uint32_t(0x4E4F534A), false); // JSON
    s += json;
    put(s, uint32_t(bin.size()), false);
    put(s, uint32_t(0x004E4942), false); // BIN
    s += bin;
    return s;
}

class MeshFormats : public ::testing::Test {
  protected:
    void SetUp() override {
        dir = ett::scratch_dir("mesh_formats");
        write_file(dir + "/tet.obj", tet_obj());
        obj = load(dir + "/tet.obj");
        ASSERT_EQ(obj.soup.size(), 4u);
    }
    void expect_error(const std::string& name, const std::string& bytes, const std::string& what) {
        const std::string p = dir + "/" + name;
        write_file(p, bytes);
        try {
            load(p);
            ADD_FAILURE() << name << ": no error, expected one mentioning '" << what << "'";
        } catch (const et::Error& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(p), std::string::npos) << msg;
            EXPECT_NE(msg.find(what), std::string::npos) << msg;
        }
    }
    // A folder or FIFO named as a mesh: refused by the regular-file check, not opened.
    void expect_not_regular(const std::string& name, const std::string& kind) {
        const std::string p = dir + "/" + name;
        try {
            load(p);
            ADD_FAILURE() << name << ": no error";
        } catch (const et::Error& e) {
            EXPECT_NE(std::string(e.what()).find(p + ": "), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(kind), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos)
                << e.what();
        }
    }
    std::string dir;
    Loaded obj;
};

TEST_F(MeshFormats, PlyAsciiAndBinaryMatchObj) {
    write_file(dir + "/a.ply", tet_ply_ascii());
    write_file(dir + "/le.ply", tet_ply_binary(false));
    write_file(dir + "/be.ply", tet_ply_binary(true));
    write_file(dir + "/UPPER.PLY", tet_ply_binary(true)); // the extension in any case
    for (const char* name : {"a.ply", "le.ply", "be.ply", "UPPER.PLY"}) {
        const Loaded ply = load(dir + "/" + name);
        expect_same_geometry(ply, obj, name);
        ASSERT_EQ(ply.materials.size(), 1u); // the default grey
        EXPECT_EQ(ply.soup.material[0], 0);
        for (size_t i = 0; i < ply.soup.normals.size(); ++i) // geometric normals, as the OBJ's
            EXPECT_LT(glm::length(ply.soup.normals[i] - obj.soup.normals[i]), 1e-5f) << name;
    }
    // The transform and an override material apply as for OBJ.
    const glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3)) *
                        glm::scale(glm::mat4(1.0f), glm::vec3(2.0f));
    const Loaded ply = load(dir + "/le.ply", m, 2);
    expect_same_geometry(ply, load(dir + "/tet.obj", m), "transformed");
    EXPECT_EQ(ply.materials.size(), 3u);
    for (int mat : ply.soup.material)
        EXPECT_EQ(mat, 2);
}

TEST_F(MeshFormats, PlyPolygonsFanNormalsAndUvs) {
    // A 2 x 3 quad as one polygon with normals and s/t, and a degenerate triangle.
    write_file(dir + "/quad.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
                                  "property double y\nproperty double z\nproperty float nx\n"
                                  "property float ny\nproperty float nz\nproperty float s\n"
                                  "property float t\nelement face 2\n"
                                  "property list uchar int vertex_index\nend_header\n"
                                  "0 0 0 0 2 0 0 0\n0 0 3 0 1 0 0 1\n2 0 3 0 1 0 1 1\n"
                                  "2 0 0 0 1 0 1 0\n4 0 1 2 3\n3 0 0 1\n");
    ett::WarningCapture warnings;
    const Loaded q = load(dir + "/quad.ply");
    ASSERT_EQ(q.soup.size(), 2u);
    float area = 0.0f;
    for (size_t t = 0; t < 2; ++t) {
        const auto& p = q.soup.positions;
        area += 0.5f * glm::length(glm::cross(p[3 * t + 1] - p[3 * t], p[3 * t + 2] - p[3 * t]));
    }
    EXPECT_NEAR(area, 6.0f, 1e-5f);
    EXPECT_EQ(q.soup.normals[0], glm::vec3(0, 1, 0)); // normalized from (0, 2, 0)
    EXPECT_EQ(q.soup.uvs[1], glm::vec2(0, 1));
    EXPECT_EQ(q.soup.uvs[2], glm::vec2(1, 1));
    EXPECT_EQ(warnings.count_containing("1 of 3 triangles skipped (degenerate"), 1u);
}

TEST_F(MeshFormats, PlyHostileFilesAreErrors) {
    const std::string le = tet_ply_binary(false);
    expect_error("trunc.ply", le.substr(0, le.size() - 3), "truncated");
    expect_error("header.ply", "ply\nformat ascii 1.0\nelement vertex 4\n", "end_header");
    expect_error("count.ply", tet_ply_binary(false, 1000000000), "beyond the limit");
    expect_error("count2.ply", tet_ply_binary(false, 100000), "more than the");
    std::string bad = tet_ply_ascii();
    bad.replace(bad.rfind("3 1 2 3"), 7, "3 1 2 9");
    expect_error("index.ply", bad, "vertex index 9 is out of range");
    std::string nan = tet_ply_ascii();
    nan.replace(nan.find("end_header\n") + 11, 8, "nan"); // the first x, "0.000000"
    expect_error("nan.ply", nan, "coordinate x (nan) is not a finite float");
    std::string big = tet_ply_ascii(); // finite in the file, beyond a float
    big.replace(big.find("end_header\n") + 11, 8, "1e300");
    expect_error("big.ply", big, "coordinate x (1e+300) is not a finite float");
    expect_error("notply.ply", "solid cube\n", "not a PLY file");
    expect_error("fmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown format");
    std::string word = tet_ply_ascii();
    word.replace(word.find("end_header\n") + 11, 1, "x");
    expect_error("word.ply", word, "not a number");
    EXPECT_THROW(load(dir + "/missing.ply"), et::Error);
    std::filesystem::create_directories(dir + "/folder.ply");
    expect_not_regular("folder.ply", "a folder");
    ASSERT_EQ(mkfifo((dir + "/fifo.ply").c_str(), 0600), 0);
    expect_not_regular("fifo.ply", "a FIFO");
}

TEST_F(MeshFormats, PlyErrorsNameThePlace) {
    // ASCII: the line; the header ends on line 10, the vertices are lines 11-14.
    std::string bad = tet_ply_ascii();
    bad.replace(bad.rfind("3 1 2 3"), 7, "3 1 2 9");
    expect_error("index.ply", bad, "line 18: face 3: vertex index 9 is out of range (4 vertices)");
    // Binary: the byte offset. Rows: 13 bytes a vertex, 17 a face (count, 3 indices, flags);
    // cut inside the last face's flags, which start 4 bytes before the end.
    const std::string le = tet_ply_binary(false);
    expect_error("trunc.ply", le.substr(0, le.size() - 3),
                 "byte " + std::to_string(le.size() - 4) + ": truncated: the file ends inside");
    // A list count that runs past the end of the file (255 corners of 4 bytes).
    std::string big = le;
    big[le.size() - 4 * 17] = char(0xff); // the first face's uchar count
    expect_error("big.ply", big, "runs past the end of the file");
    expect_error("twice.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                 "element vertex 1\nproperty float x\nend_header\n0\n0\n",
                 "header line 5: a second 'vertex' element");
    expect_error("nofaces.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "property float z\nend_header\n0 0 0\n",
                 "no face element");
    std::string corners = tet_ply_ascii();
    corners.replace(corners.rfind("3 1 2 3"), 7, "70000 1 2 3");
    expect_error("corners.ply", corners, "list count 70000 is out of range");
    // ASCII rows are lines: a value too many or too few on one is an error there, not a shift of
    // every row after it (which rendered the wrong triangles without a word).
    const size_t first_vertex_end = tet_ply_ascii().find('\n', tet_ply_ascii().find("end_header"));
    std::string extra = tet_ply_ascii();
    extra.insert(extra.find('\n', first_vertex_end + 1), " 5");
    expect_error("extra.ply", extra,
                 "line 11: element 'vertex' row 0: more values on the line than the header "
                 "declares");
    std::string fewer = tet_ply_ascii();
    const size_t line_end = fewer.find('\n', first_vertex_end + 1);
    fewer.erase(fewer.rfind(' ', line_end), line_end - fewer.rfind(' ', line_end)); // its z
    expect_error("fewer.ply", fewer, "line 11: the line ends before a vertex or element value");
}

TEST_F(MeshFormats, GltfAndGlbMatchObj) {
    write_file(dir + "/tet.gltf", tet_gltf(data_uri(tet_buffer())));
    write_file(dir + "/tet.bin", tet_buffer());
    write_file(dir + "/ext.gltf", tet_gltf("tet.bin"));
    write_file(dir + "/tet.glb", glb(tet_gltf(""), tet_buffer()));
    for (const char* name : {"tet.gltf", "ext.gltf", "tet.glb"}) {
        const Loaded g = load(dir + "/" + name);
        expect_same_geometry(g, obj, name);
        for (size_t i = 0; i < g.soup.normals.size(); ++i)
            EXPECT_LT(glm::length(g.soup.normals[i] - obj.soup.normals[i]), 1e-5f) << name;
    }
}

TEST_F(MeshFormats, GltfNodeTransformsApply) {
    // Parent: translation (1, 2, 3); child: a quarter turn about +Y and scale 2 (TRS), and a
    // second child with the same as a column-major matrix and a mirror in x, whose winding is
    // flipped back so normals still point out.
    const std::string nodes =
        R"([{"translation": [1, 2, 3], "children": [1, 2]},
            {"mesh": 0, "rotation": [0, 0.70710678, 0, 0.70710678], "scale": [2, 2, 2]},
            {"mesh": 0, "matrix": [-1,0,0,0, 0,1,0,0, 0,0,1,0, 5,0,0,1]}])";
    write_file(dir + "/nodes.gltf", tet_gltf(data_uri(tet_buffer()), nodes));
    const glm::mat4 outer = glm::translate(glm::mat4(1.0f), glm::vec3(0, -1, 0));
    const Loaded g = load(dir + "/nodes.gltf", outer);
    ASSERT_EQ(g.soup.size(), 8u);
    const glm::mat4 parent = outer * glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3));
    const glm::mat4 a = parent *
                        glm::rotate(glm::mat4(1.0f), glm::radians(90.0f), glm::vec3(0, 1, 0)) *
                        glm::scale(glm::mat4(1.0f), glm::vec3(2.0f));
    Loaded expect = load(dir + "/tet.obj", a);
    const glm::mat4 b = parent * glm::translate(glm::mat4(1.0f), glm::vec3(5, 0, 0)) *
                        glm::scale(glm::mat4(1.0f), glm::vec3(-1, 1, 1));
    const Loaded mirrored = load(dir + "/tet.obj", b);
    // The OBJ loader keeps the mirrored winding; the glTF loader flips it (glTF's rule), so
    // compare the mirrored half by corner sets and check its normals point away from the centre.
    const size_t half = 4;
    Loaded first, second;
    first.soup.positions.assign(g.soup.positions.begin(), g.soup.positions.begin() + 3 * half);
    first.soup.material.assign(half, 0);
    second.soup.positions.assign(g.soup.positions.begin() + 3 * half, g.soup.positions.end());
    second.soup.material.assign(half, 0);
    expect_same_geometry(first, expect, "TRS child");
    auto corner_sets = [](const et::TriangleSoup& s) {
        auto t = triangles(s);
        for (auto& tri : t)
            std::sort(tri.begin(), tri.end());
        std::sort(t.begin(), t.end());
        return t;
    };
    EXPECT_EQ(corner_sets(second.soup), corner_sets(mirrored.soup));
    glm::vec3 centre(0.0f);
    for (size_t i = 3 * half; i < 6 * half; ++i)
        centre += g.soup.positions[i] / float(3 * half);
    for (size_t t = half; t < 2 * half; ++t) {
        const glm::vec3 c =
            (g.soup.positions[3 * t] + g.soup.positions[3 * t + 1] + g.soup.positions[3 * t + 2]) /
            3.0f;
        EXPECT_GT(glm::dot(g.soup.normals[3 * t], c - centre), 0.0f) << "triangle " << t;
    }
}

TEST_F(MeshFormats, GltfMaterialsMapAndOverride) {
    const std::string metal =
        R"({"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.3, 1],
            "metallicFactor": 1, "roughnessFactor": 0.5}})";
    write_file(dir + "/metal.gltf",
               tet_gltf(data_uri(tet_buffer()), R"([{"mesh": 0}])", "[0]", 4, metal));
    Loaded g = load(dir + "/metal.gltf");
    ASSERT_EQ(g.materials.size(), 1u);
    EXPECT_EQ(g.materials[0].name, "gold");
    EXPECT_EQ(g.materials[0].type, ETK_MAT_MICROFACET);
    EXPECT_EQ(g.materials[0].specular, glm::vec3(0.9f, 0.6f, 0.3f));
    EXPECT_EQ(g.materials[0].albedo, glm::vec3(0.0f));
    EXPECT_FLOAT_EQ(g.materials[0].roughness, 0.25f);
    const std::string plastic =
        R"({"pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.2, 0.7, 1],
            "metallicFactor": 0, "roughnessFactor": 0.2},
            "normalTexture": {"index": 0}})";
    write_file(dir + "/plastic.gltf",
               tet_gltf(data_uri(tet_buffer()), R"([{"mesh": 0}])", "[0]", 4, plastic));
    {
        ett::WarningCapture warnings;
        g = load(dir + "/plastic.gltf");
        EXPECT_EQ(warnings.count_containing("textures are not read"), 1u);
    }
    ASSERT_EQ(g.materials.size(), 1u);
    EXPECT_EQ(g.materials[0].albedo, glm::vec3(0.1f, 0.2f, 0.7f));
    EXPECT_EQ(g.materials[0].specular, glm::vec3(0.04f));
    EXPECT_NEAR(g.materials[0].roughness, 0.04f, 1e-6f);
    // Between the two, F0 and the Lambertian base are blended by metallic.
    const std::string half =
        R"({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 1, 0, 1], "metallicFactor": 0.25}})";
    write_file(dir + "/half.gltf",
               tet_gltf(data_uri(tet_buffer()), R"([{"mesh": 0}])", "[0]", 4, half));
    g = load(dir + "/half.gltf");
    ASSERT_EQ(g.materials.size(), 1u);
    EXPECT_NEAR(g.materials[0].specular.x, 0.75f * 0.04f + 0.25f * 0.5f, 1e-6f);
    EXPECT_NEAR(g.materials[0].specular.y, 0.75f * 0.04f + 0.25f * 1.0f, 1e-6f);
    EXPECT_NEAR(g.materials[0].specular.z, 0.75f * 0.04f, 1e-6f);
    EXPECT_NEAR(g.materials[0].albedo.x, 0.375f, 1e-6f);
    EXPECT_NEAR(g.materials[0].albedo.y, 0.75f, 1e-6f);
    EXPECT_FLOAT_EQ(g.materials[0].roughness, 1.0f); // glTF's default roughness, 1
    g = load(dir + "/metal.gltf", glm::mat4(1.0f), 3);
    EXPECT_EQ(g.materials.size(), 4u);
    for (int m : g.soup.material)
        EXPECT_EQ(m, 3);
}

TEST_F(MeshFormats, GltfHostileFilesAreErrors) {
    const std::string uri = data_uri(tet_buffer());
    expect_error("count.gltf", tet_gltf(uri, R"([{"mesh": 0}])", "[0]", 1000), "run past the end");
    expect_error("index.gltf", tet_gltf(data_uri(tet_buffer(7))), "index 7 is out of range");
    expect_error("cycle.gltf",
                 tet_gltf(uri, R"([{"mesh": 0, "children": [1]}, {"children": [0]}])"),
                 "not a tree");
    expect_error("nonode.gltf", tet_gltf(uri, R"([{"mesh": 0}])", "[5]"), "node 5 does not exist");
    expect_error("nobin.gltf", tet_gltf("absent.bin"), "cannot read glTF");
    // Offsets, counts and indices that tinygltf would read as 0 or truncate without a word.
    std::string offset = tet_gltf(uri);
    offset.replace(offset.find("\"byteOffset\": 48"), 16, "\"byteOffset\": -4");
    expect_error("offset.gltf", offset,
                 "bufferViews[1].byteOffset: expected a whole number >= 0, got -4");
    std::string fraction = tet_gltf(uri);
    fraction.replace(fraction.find("\"count\": 12"), 11, "\"count\": 11.5");
    expect_error("fraction.gltf", fraction, "accessors[1].count: expected a whole number >= 0");
    expect_error("negnode.gltf", tet_gltf(uri, R"([{"mesh": -1}])"),
                 "nodes[0].mesh: expected a whole number >= 0, got -1");
    std::string attribute = tet_gltf(uri);
    attribute.replace(attribute.find("\"POSITION\": 0"), 13, "\"POSITION\": \"0\"");
    expect_error("attribute.gltf", attribute,
                 "meshes[0].primitives[0].attributes.POSITION: expected a whole number >= 0");
    expect_error("json.gltf", tet_gltf(uri).substr(0, 100), ":1:101: malformed JSON");
    const std::string g = glb(tet_gltf(""), tet_buffer());
    expect_error("trunc.glb", g.substr(0, g.size() - 30), "truncated");
    expect_error("header.glb", g.substr(0, 10), "shorter than the 20-byte header");
    std::string nan = tet_buffer();
    const float q = std::nanf("");
    std::memcpy(&nan[4], &q, 4);
    expect_error("nan.gltf", tet_gltf(data_uri(nan)), "not finite");
    EXPECT_THROW(load(dir + "/missing.glb"), et::Error);
    std::filesystem::create_directories(dir + "/folder.gltf");
    expect_not_regular("folder.gltf", "a folder");
    ASSERT_EQ(mkfifo((dir + "/fifo.glb").c_str(), 0600), 0);
    expect_not_regular("fifo.glb", "a FIFO");
    // An external buffer goes through the same check: a FIFO is refused, not read.
    ASSERT_EQ(mkfifo((dir + "/fifo.bin").c_str(), 0600), 0);
    expect_error("fifobuf.gltf", tet_gltf("fifo.bin"), "a FIFO (named pipe), not a regular file");
    std::string draco = tet_gltf(uri);
    draco.insert(1, R"("extensionsRequired": ["KHR_draco_mesh_compression"], )");
    expect_error("draco.gltf", draco, "requires the extension 'KHR_draco_mesh_compression'");
    std::string quantized = tet_gltf(uri);
    quantized.insert(1, R"("extensionsRequired": ["KHR_mesh_quantization"], )");
    write_file(dir + "/quantized.gltf", quantized);
    EXPECT_EQ(load(dir + "/quantized.gltf").soup.size(), 4u);
    // An external buffer is looked for beside the glTF only, not in the working folder.
    std::filesystem::create_directories(dir + "/sub");
    write_file(dir + "/cwd.bin", tet_buffer());
    write_file(dir + "/sub/cwd.gltf", tet_gltf("cwd.bin"));
    const auto cwd = std::filesystem::current_path();
    std::filesystem::current_path(dir);
    EXPECT_THROW(load(dir + "/sub/cwd.gltf"), et::Error);
    std::filesystem::current_path(cwd);
    write_file(dir + "/sub/cwd.bin", tet_buffer()); // beside it: found
    EXPECT_EQ(load(dir + "/sub/cwd.gltf").soup.size(), 4u);
    // Declared buffer sizes beyond the cap are refused before tinygltf allocates anything.
    std::string huge = tet_gltf(uri);
    huge.replace(huge.find("\"byteLength\": 72"), 16, "\"byteLength\": 3e9");
    expect_error("huge.gltf", huge, "the buffers declare");
    std::string many = glb(tet_gltf(""), tet_buffer());
    expect_error("glbver.glb", many.substr(0, 4) + std::string("\1\0\0\0", 4) + many.substr(8),
                 "GLB: version 1, not 2");
    // Attributes of the wrong type or component type, read as floats, made garbage geometry
    // without a word; a material index past the end fell back to grey.
    std::string vec2 = tet_gltf(uri);
    vec2.replace(vec2.find("\"type\": \"VEC3\""), 14, "\"type\": \"VEC2\"");
    expect_error("vec2.gltf", vec2, "POSITION: accessor 0 is a VEC2, not a VEC3");
    std::string ints = tet_gltf(uri);
    ints.replace(ints.find("\"componentType\": 5126"), 21, "\"componentType\": 5125");
    expect_error("ints.gltf", ints, "POSITION: accessor 0 has componentType 5125");
    std::string material = tet_gltf(uri, R"([{"mesh": 0}])", "[0]", 4, "{}");
    material.replace(material.find("\"material\": 0"), 13, "\"material\": 9");
    expect_error("material.gltf", material,
                 "mesh 0 primitive 0: material 9 does not exist (1 materials)");
    // Under KHR_mesh_quantization the positions may be shorts (normalized or not): read (here
    // the float bytes as shorts make degenerate triangles, a different error).
    std::string shorts = ints;
    shorts.replace(shorts.find("5125"), 4, "5122");
    shorts.insert(1, R"("extensionsUsed": ["KHR_mesh_quantization"], )");
    write_file(dir + "/shorts.gltf", shorts);
    try {
        ett::WarningCapture quiet;
        load(dir + "/shorts.gltf");
    } catch (const et::Error& e) {
        EXPECT_EQ(std::string(e.what()).find("componentType"), std::string::npos) << e.what();
    }
    std::string deep = tet_gltf(uri);
    deep.insert(deep.size() - 1, ", \"extras\": " + std::string(100, '[') + std::string(100, ']'));
    expect_error("deep.gltf", deep, "nested deeper than");
}

TEST_F(MeshFormats, GltfImagesAreNotRead) {
    // The texture's image is a FIFO: were tinygltf to open it, the regular-file check would
    // refuse it with a warning naming it (and a reader without the check would hang).
    ASSERT_EQ(mkfifo((dir + "/tex.png").c_str(), 0600), 0);
    const std::string material =
        R"({"name": "textured", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})";
    std::string g = tet_gltf(data_uri(tet_buffer()), R"([{"mesh": 0}])", "[0]", 4, material);
    g.replace(g.find("\"buffers\""), 0,
              R"("images": [{"uri": "tex.png"}], "textures": [{"source": 0}], )");
    write_file(dir + "/img.gltf", g);
    ett::WarningCapture warnings;
    const Loaded l = load(dir + "/img.gltf");
    expect_same_geometry(l, obj, "img.gltf");
    EXPECT_EQ(warnings.count_containing("textures are not read"), 1u);
    EXPECT_EQ(warnings.count_containing("tex.png"), 0u);
    // The same in a GLB.
    std::string bin_json = tet_gltf("", R"([{"mesh": 0}])", "[0]", 4, material);
    bin_json.replace(bin_json.find("\"buffers\""), 0,
                     R"("images": [{"uri": "tex.png"}], "textures": [{"source": 0}], )");
    write_file(dir + "/img.glb", glb(bin_json, tet_buffer()));
    const Loaded b = load(dir + "/img.glb");
    expect_same_geometry(b, obj, "img.glb");
    EXPECT_EQ(warnings.count_containing("tex.png"), 0u);
}

TEST_F(MeshFormats, SceneLoadsEachFormat) {
    write_file(dir + "/tet.ply", tet_ply_ascii());
    write_file(dir + "/tet.glb", glb(tet_gltf(""), tet_buffer()));
    write_file(dir + "/scene.json",
               R"({"environment": {"sky": {"resolution": [16, 8]}},
                   "shapes": [{"type": "mesh", "file": "tet.obj"}, {"type": "mesh", "file": "tet.ply"},
                   {"type": "mesh", "file": "tet.glb", "transform": {"translate": [3, 0, 0]}}]})");
    const et::Scene s = et::load_scene(dir + "/scene.json");
    EXPECT_EQ(s.triangles.size(), 12u);
    float max_x = -1e9f;
    for (const auto& p : s.triangles.positions)
        max_x = std::max(max_x, p.x);
    EXPECT_FLOAT_EQ(max_x, 4.0f);
}

// Damaged files, many of them: each either loads or is refused with an et::Error naming it; a
// crash, a hang, a huge allocation (std::bad_alloc) or any other exception fails the test. Digits
// are changed into longer numbers (counts, offsets, indices past everything), bytes overwritten,
// files cut short. Fixed seed.
TEST_F(MeshFormats, DamagedFilesLoadOrAreRefused) {
    const std::vector<std::pair<std::string, std::string>> seeds = {
        {"d.ply", tet_ply_ascii()},
        {"d.ply", tet_ply_binary(false)},
        {"d.ply", tet_ply_binary(true)},
        {"d.gltf", tet_gltf(data_uri(tet_buffer()))},
        {"d.glb", glb(tet_gltf(""), tet_buffer())}};
    std::mt19937 rng(14);
    ett::WarningCapture quiet;
    size_t loaded = 0, refused = 0;
    for (const auto& [name, seed] : seeds)
        for (int i = 0; i < 300; ++i) {
            std::string b = seed;
            for (int k = 1 + rng() % 3; k > 0 && !b.empty(); --k) {
                const size_t at = rng() % b.size();
                switch (rng() % 4) {
                case 0: // a number grows: "4" -> "4999999999"
                    if (std::isdigit(static_cast<unsigned char>(b[at])))
                        b.insert(at, std::string(1 + rng() % 12, char('0' + rng() % 10)));
                    break;
                case 1:
                    b[at] = char(rng());
                    break;
                case 2:
                    b[at] = char(rng() % 2 ? 0xff : 0x7f);
                    break;
                default:
                    b.resize(at);
                }
            }
            const std::string p = dir + "/" + name;
            write_file(p, b);
            try {
                load(p);
                ++loaded;
            } catch (const et::Error& e) {
                ++refused;
                EXPECT_EQ(std::string(e.what()).rfind(p, 0), 0u) << e.what();
            }
        }
    EXPECT_GT(loaded, 0u);
    EXPECT_GT(refused, 0u);
}

// The shipped scenes/mesh_formats.json: a PLY octahedron (8 faces) and a glTF gold cube (12
// triangles, rotated by its node) on a floor quad (2).
TEST(MeshFormatsScene, ShippedSceneLoads) {
    ett::WarningCapture warnings;
    const et::Scene s =
        et::load_scene(std::string(ENVTRACE_SOURCE_DIR) + "/scenes/mesh_formats.json");
    EXPECT_EQ(s.triangles.size(), 2u + 8u + 12u);
    EXPECT_TRUE(warnings.messages().empty()) << warnings.messages().front();
    bool gold = false;
    for (const auto& m : s.materials)
        if (m.name == "gold") {
            gold = true;
            EXPECT_EQ(m.type, ETK_MAT_MICROFACET);
            EXPECT_EQ(m.specular, glm::vec3(1.0f, 0.78f, 0.34f));
        }
    EXPECT_TRUE(gold);
}

} // namespace
