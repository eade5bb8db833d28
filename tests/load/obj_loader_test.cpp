// load_obj (host/lib/load/obj_loader.cpp): polygons triangulated, the transform applied to
// positions and (inverse-transposed) to normals, per-vertex normals used when the OBJ has them and
// the geometric normal otherwise, MTL materials mapped as docs/scene-format.md documents (Kd ->
// albedo, Ks -> specular, Ns -> roughness = sqrt(2 / (Ns + 2))), override_material, and dropped
// degenerate triangles.
#include "load/scene.h"
#include "kernels/bsdf.h"
#include "util/error.h"
#include "test_data.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace {

void write_file(const std::string& path, const std::string& text) {
    std::ofstream(path) << text;
}

struct Loaded {
    std::vector<et::Material> materials;
    et::TriangleSoup soup;
};

Loaded load(const std::string& path, const glm::mat4& m = glm::mat4(1.0f),
            int override_material = -1, int existing_materials = 0) {
    Loaded l;
    for (int i = 0; i < existing_materials; ++i)
        l.materials.push_back({"existing" + std::to_string(i), ETK_MAT_DIFFUSE, glm::vec3(0.5f),
                               glm::vec3(0.0f), 0.5f});
    et::load_obj(path, m, override_material, l.materials, l.soup);
    return l;
}

glm::vec3 corner(const et::TriangleSoup& s, size_t tri, int k) {
    return s.positions[3 * tri + k];
}

glm::vec3 geometric_normal(const et::TriangleSoup& s, size_t tri) {
    return glm::normalize(
        glm::cross(corner(s, tri, 1) - corner(s, tri, 0), corner(s, tri, 2) - corner(s, tri, 0)));
}

float area(const et::TriangleSoup& s, size_t tri) {
    return 0.5f * glm::length(glm::cross(corner(s, tri, 1) - corner(s, tri, 0),
                                         corner(s, tri, 2) - corner(s, tri, 0)));
}

void expect_vec_near(glm::vec3 a, glm::vec3 b, float tol, const std::string& what = "") {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}

// A 2 x 3 quad in the y = 0 plane, counter-clockwise seen from +Y.
const char* kQuad = "v 0 0 0\nv 0 0 3\nv 2 0 3\nv 2 0 0\nf 1 2 3 4\n";

TEST(ObjLoader, QuadBecomesTwoTrianglesCoveringIt) {
    const std::string dir = ett::scratch_dir("obj-quad");
    write_file(dir + "/quad.obj", kQuad);
    const Loaded l = load(dir + "/quad.obj");
    ASSERT_EQ(l.soup.size(), 2u);
    ASSERT_EQ(l.soup.positions.size(), 6u);
    ASSERT_EQ(l.soup.normals.size(), 6u);
    // Each triangle has non-zero area, together they cover the quad once.
    EXPECT_GT(area(l.soup, 0), 0.0f);
    EXPECT_GT(area(l.soup, 1), 0.0f);
    EXPECT_NEAR(area(l.soup, 0) + area(l.soup, 1), 6.0f, 1e-5f);
    // Every corner is a vertex of the quad and all four are used; orientation is kept (+Y).
    const glm::vec3 quad[4] = {{0, 0, 0}, {0, 0, 3}, {2, 0, 3}, {2, 0, 0}};
    bool used[4] = {false, false, false, false};
    for (const glm::vec3& p : l.soup.positions) {
        int match = -1;
        for (int q = 0; q < 4; ++q)
            if (glm::length(p - quad[q]) < 1e-6f)
                match = q;
        ASSERT_GE(match, 0) << "corner not on the quad";
        used[match] = true;
    }
    for (bool u : used)
        EXPECT_TRUE(u);
    for (size_t t = 0; t < 2; ++t)
        expect_vec_near(geometric_normal(l.soup, t), glm::vec3(0, 1, 0), 1e-6f);
    // No normals in the file: every corner carries the geometric normal.
    for (const glm::vec3& n : l.soup.normals)
        expect_vec_near(n, glm::vec3(0, 1, 0), 1e-6f);
    // No MTL: one default material appended, used by both triangles.
    ASSERT_EQ(l.materials.size(), 1u);
    EXPECT_EQ(l.soup.material, (std::vector<int>{0, 0}));
}

TEST(ObjLoader, PentagonIsTriangulatedToo) {
    const std::string dir = ett::scratch_dir("obj-pentagon");
    // A convex pentagon of area 1 + 1/2 (unit square with a roof of height 1 over x in [0, 1]).
    write_file(dir + "/penta.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 2 0\nv 0 1 0\nf 1 2 3 4 5\n");
    const Loaded l = load(dir + "/penta.obj");
    ASSERT_EQ(l.soup.size(), 3u);
    float sum = 0.0f;
    for (size_t t = 0; t < 3; ++t) {
        sum += area(l.soup, t);
        expect_vec_near(geometric_normal(l.soup, t), glm::vec3(0, 0, 1), 1e-6f);
    }
    EXPECT_NEAR(sum, 1.5f, 1e-5f);
}

TEST(ObjLoader, TransformAppliesToPositionsAndNormals) {
    const std::string dir = ett::scratch_dir("obj-transform");
    // One triangle with a deliberately non-unit, tilted normal at each corner.
    write_file(dir + "/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                 "vn 1 1 0\nvn 1 0 2\nvn 0 1 1\n"
                                 "f 1//1 2//2 3//3\n");
    const glm::vec3 v[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const glm::vec3 vn[3] = {{1, 1, 0}, {1, 0, 2}, {0, 1, 1}};
    // Scale, then rotate, then translate, as the scene format composes them.
    const glm::mat4 m =
        glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3)) *
        glm::rotate(glm::mat4(1.0f), glm::radians(30.0f), glm::normalize(glm::vec3(1, 2, 0.5f))) *
        glm::scale(glm::mat4(1.0f), glm::vec3(2.0f, 1.0f, 0.5f));
    const Loaded l = load(dir + "/tri.obj", m);
    ASSERT_EQ(l.soup.size(), 1u);
    const glm::mat3 nm = glm::transpose(glm::inverse(glm::mat3(m)));
    for (int k = 0; k < 3; ++k) {
        expect_vec_near(corner(l.soup, 0, k), glm::vec3(m * glm::vec4(v[k], 1.0f)), 1e-5f,
                        "position " + std::to_string(k));
        const glm::vec3 want = glm::normalize(nm * vn[k]);
        expect_vec_near(l.soup.normals[k], want, 1e-5f, "normal " + std::to_string(k));
        // Transforming normals like positions would be wrong under non-uniform scale.
        EXPECT_GT(glm::length(glm::normalize(glm::mat3(m) * vn[k]) - want), 0.05f) << k;
    }
}

TEST(ObjLoader, TransformAppliesToGeometricNormals) {
    const std::string dir = ett::scratch_dir("obj-transform-geo");
    write_file(dir + "/quad.obj", kQuad);
    // Rotate the +Y quad by 90 degrees about +Z: it faces -X. Then a translation.
    const glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(5, 0, 0)) *
                        glm::rotate(glm::mat4(1.0f), glm::radians(90.0f), glm::vec3(0, 0, 1));
    const Loaded l = load(dir + "/quad.obj", m);
    ASSERT_EQ(l.soup.size(), 2u);
    for (const glm::vec3& p : l.soup.positions)
        EXPECT_NEAR(p.x, 5.0f, 1e-5f);
    for (const glm::vec3& n : l.soup.normals)
        expect_vec_near(n, glm::vec3(-1, 0, 0), 1e-5f);
}

TEST(ObjLoader, VertexNormalsUsedWhenPresentGeometricOtherwise) {
    const std::string dir = ett::scratch_dir("obj-normals");
    // Two triangles of the same plane (normal +Z): the first with smooth normals, the second
    // without, a third with a zero-length normal at one corner.
    write_file(dir + "/n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                               "vn 0.3 0 1\nvn 0 -0.4 1\nvn 0.1 0.1 1\nvn 0 0 0\n"
                               "f 1//1 2//2 3//3\n"
                               "f 2 4 3\n"
                               "f 2//4 4//1 3//2\n");
    const Loaded l = load(dir + "/n.obj");
    ASSERT_EQ(l.soup.size(), 3u);
    expect_vec_near(l.soup.normals[0], glm::normalize(glm::vec3(0.3f, 0, 1)), 1e-6f, "smooth 0");
    expect_vec_near(l.soup.normals[1], glm::normalize(glm::vec3(0, -0.4f, 1)), 1e-6f, "smooth 1");
    expect_vec_near(l.soup.normals[2], glm::normalize(glm::vec3(0.1f, 0.1f, 1)), 1e-6f, "smooth 2");
    for (int k = 3; k < 6; ++k)
        expect_vec_near(l.soup.normals[k], glm::vec3(0, 0, 1), 1e-6f, "flat " + std::to_string(k));
    // A zero normal cannot be normalised: that corner falls back to the geometric normal.
    expect_vec_near(l.soup.normals[6], glm::vec3(0, 0, 1), 1e-6f, "zero");
    expect_vec_near(l.soup.normals[7], glm::normalize(glm::vec3(0.3f, 0, 1)), 1e-6f);
    for (const glm::vec3& n : l.soup.normals)
        EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f);
}

// Face lines as tinyobjloader reads them took 4294967299 as index 3, a 23-digit number as some
// other vertex and "3abc" as 3, without a word; a polygon of 500,000 corners took ~20 minutes to
// triangulate. Each is an error naming its line; the valid forms load.
TEST(ObjLoader, FaceIndicesAndCornersAreChecked) {
    const std::string dir = ett::scratch_dir("obj-face-check");
    const std::string verts = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.5 0.5 -1\nvn 0 0 1\nvt 0 0\n";
    auto error = [&](const std::string& face) {
        write_file(dir + "/f.obj", verts + face + "\n");
        try {
            load(dir + "/f.obj");
        } catch (const et::Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(error("f 1 2 4294967299").find("f.obj: line 7: index 4294967299 of face corner"),
              std::string::npos);
    EXPECT_NE(error("f 1 2 99999999999999999999999").find("is beyond any vertex list"),
              std::string::npos);
    EXPECT_NE(error("f 1 2 3abc").find("line 7: face corner '3abc' is not v, v/vt, v/vt/vn"),
              std::string::npos);
    EXPECT_NE(error("f 1 2 3/1/1/1").find("has more than three indices"), std::string::npos);
    EXPECT_EQ(error("f 1/1/1 2//1 -2"), "");
    std::string big = "f";
    for (int k = 0; k < 16385; ++k)
        big += " " + std::to_string(1 + k % 4);
    EXPECT_NE(error(big).find("a face of more than 16384 corners"), std::string::npos);
}

// A normal need not be unit length in the file; its length in float can under- or overflow
// (1e-30 squared), which dropped it for the geometric normal.
TEST(ObjLoader, NormalsOfAnyLengthAreUsed) {
    const std::string dir = ett::scratch_dir("obj-normal-length");
    write_file(dir + "/n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                               "vn 0 1e-30 1e-30\nvn 0 1e30 1e30\nvn 0 3e-39 0\n"
                               "f 1//1 2//2 3//3\n");
    const Loaded l = load(dir + "/n.obj");
    ASSERT_EQ(l.soup.size(), 1u);
    const glm::vec3 diagonal = glm::normalize(glm::vec3(0, 1, 1));
    expect_vec_near(l.soup.normals[0], diagonal, 1e-6f, "1e-30");
    expect_vec_near(l.soup.normals[1], diagonal, 1e-6f, "1e30");
    expect_vec_near(l.soup.normals[2], glm::vec3(0, 1, 0), 1e-6f, "denormal");
}

// A mirroring transform (negative determinant) turns the winding around, and the winding says
// which side is a dielectric's outside: load_mesh turns it back, so that the front face of every
// triangle is the mirror image of its front face before.
TEST(ObjLoader, MirroringTransformKeepsTheFrontFace) {
    const std::string dir = ett::scratch_dir("obj-mirror");
    write_file(dir + "/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                 "f 1/1 2/2 3/3\n");
    for (const glm::vec3 scale :
         {glm::vec3(-1, 1, 1), glm::vec3(1, 1, -2), glm::vec3(-1, -1, -1), glm::vec3(-1, -1, 1)}) {
        SCOPED_TRACE(std::to_string(scale.x) + " " + std::to_string(scale.y) + " " +
                     std::to_string(scale.z));
        const glm::mat4 m = glm::scale(glm::mat4(1.0f), scale);
        std::vector<et::Material> materials;
        et::TriangleSoup soup;
        et::load_mesh(dir + "/tri.obj", m, -1, materials, soup, nullptr);
        ASSERT_EQ(soup.size(), 1u);
        const glm::vec3 p[3] = {soup.positions[0], soup.positions[1], soup.positions[2]};
        // The front (+z) mirrored: its normal transforms by the inverse transpose.
        const glm::vec3 front =
            glm::normalize(glm::transpose(glm::inverse(glm::mat3(m))) * glm::vec3(0, 0, 1));
        expect_vec_near(et::unit_face_normal(p), front, 1e-6f, "front face");
        // Each corner keeps its texture coordinate.
        for (int k = 0; k < 3; ++k) {
            const glm::vec3 v = glm::vec3(glm::inverse(m) * glm::vec4(p[k], 1.0f));
            EXPECT_EQ(soup.uvs[k], glm::vec2(v.x, v.y)) << k;
        }
    }
}

TEST(ObjLoader, MtlMaterialsMappedAsDocumented) {
    const std::string dir = ett::scratch_dir("obj-mtl");
    write_file(dir + "/m.mtl", "newmtl red\nKd 0.8 0.1 0.1\nKs 0 0 0\nNs 10\n"
                               "newmtl shiny\nKd 0.2 0.4 0.6\nKs 0.5 0.25 0.125\nNs 98\n"
                               "newmtl hot\nKd 2 0.5 -1\nKs 0.04 0.04 0.04\nNs 0\n"
                               "newmtl glass\nKd 0 0 0\nKs 1 1 1\nNs 1000000\n");
    write_file(dir + "/m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                               "f 1 2 3\n"
                               "usemtl shiny\nf 1 2 3\n"
                               "usemtl red\nf 1 2 3\n"
                               "usemtl hot\nf 1 2 3\n"
                               "usemtl glass\nf 1 2 3\n");
    // Two materials already in the scene: the OBJ's are appended after them.
    const Loaded l = load(dir + "/m.obj", glm::mat4(1.0f), -1, 2);
    ASSERT_EQ(l.soup.size(), 5u);
    auto find = [&](const std::string& name) {
        for (size_t i = 0; i < l.materials.size(); ++i)
            if (l.materials[i].name == name)
                return static_cast<int>(i);
        return -1;
    };
    const int red = find("red"), shiny = find("shiny"), hot = find("hot"), glass = find("glass");
    ASSERT_GE(red, 2);
    ASSERT_GE(shiny, 2);
    ASSERT_GE(hot, 2);
    ASSERT_GE(glass, 2);
    EXPECT_EQ(l.materials[0].name, "existing0");
    EXPECT_EQ(l.materials[1].name, "existing1");
    // The face before any usemtl gets a material of its own, not one of the scene's.
    const int first = l.soup.material[0];
    EXPECT_GE(first, 2);
    EXPECT_NE(first, red);
    EXPECT_NE(first, shiny);
    EXPECT_NE(first, hot);
    EXPECT_NE(first, glass);
    EXPECT_EQ(l.soup.material[1], shiny);
    EXPECT_EQ(l.soup.material[2], red);
    EXPECT_EQ(l.soup.material[3], hot);
    EXPECT_EQ(l.soup.material[4], glass);

    const et::Material& r = l.materials[red];
    expect_vec_near(r.albedo, glm::vec3(0.8f, 0.1f, 0.1f), 1e-6f, "red Kd");
    expect_vec_near(r.specular, glm::vec3(0.0f), 1e-6f, "red Ks");
    EXPECT_NEAR(r.roughness, std::sqrt(2.0f / 12.0f), 1e-6f);
    EXPECT_EQ(r.type, ETK_MAT_DIFFUSE);

    const et::Material& s = l.materials[shiny];
    expect_vec_near(s.albedo, glm::vec3(0.2f, 0.4f, 0.6f), 1e-6f, "shiny Kd");
    expect_vec_near(s.specular, glm::vec3(0.5f, 0.25f, 0.125f), 1e-6f, "shiny Ks");
    EXPECT_NEAR(s.roughness, std::sqrt(2.0f / 100.0f), 1e-6f);
    EXPECT_NE(s.type, ETK_MAT_DIFFUSE) << "a specular MTL material must not render as diffuse";

    // Out-of-range Kd is clamped to a physical albedo; Ns 0 is the roughest.
    const et::Material& h = l.materials[hot];
    expect_vec_near(h.albedo, glm::vec3(1.0f, 0.5f, 0.0f), 1e-6f, "hot Kd");
    EXPECT_NEAR(h.roughness, 1.0f, 1e-6f);
    // A huge Ns is near-mirror smooth, not zero (kept a usable GGX roughness).
    const et::Material& g = l.materials[glass];
    EXPECT_GT(g.roughness, 0.0f);
    EXPECT_LE(g.roughness, 0.02f);
}

TEST(ObjLoader, OverrideMaterialIgnoresTheMtl) {
    const std::string dir = ett::scratch_dir("obj-override");
    write_file(dir + "/m.mtl", "newmtl red\nKd 0.8 0.1 0.1\n");
    write_file(dir + "/m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                               "usemtl red\nf 1 2 3\nf 2 4 3\n");
    const Loaded l = load(dir + "/m.obj", glm::mat4(1.0f), 1, 3);
    ASSERT_EQ(l.soup.size(), 2u);
    EXPECT_EQ(l.materials.size(), 3u) << "no materials added under an override";
    EXPECT_EQ(l.soup.material, (std::vector<int>{1, 1}));
}

TEST(ObjLoader, AppendsToWhatIsThere) {
    const std::string dir = ett::scratch_dir("obj-append");
    write_file(dir + "/quad.obj", kQuad);
    Loaded l = load(dir + "/quad.obj");
    const glm::mat4 up = glm::translate(glm::mat4(1.0f), glm::vec3(0, 1, 0));
    et::load_obj(dir + "/quad.obj", up, -1, l.materials, l.soup);
    ASSERT_EQ(l.soup.size(), 4u);
    ASSERT_EQ(l.soup.positions.size(), 12u);
    ASSERT_EQ(l.soup.normals.size(), 12u);
    for (int k = 0; k < 6; ++k)
        EXPECT_EQ(l.soup.positions[k].y, 0.0f);
    for (int k = 6; k < 12; ++k)
        EXPECT_EQ(l.soup.positions[k].y, 1.0f);
    ASSERT_EQ(l.materials.size(), 2u);
    EXPECT_EQ(l.soup.material, (std::vector<int>{0, 0, 1, 1}));
}

TEST(ObjLoader, DegenerateTrianglesAreDroppedWithAWarning) {
    const std::string dir = ett::scratch_dir("obj-degenerate");
    write_file(dir + "/d.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv nan 0 0\nv 0 inf 0\n"
                               "f 1 2 3\n" // good
                               "f 1 2 4\n" // collinear
                               "f 1 1 3\n" // repeated vertex
                               "f 1 5 3\n" // NaN
                               "f 1 2 6\n" // infinite
                               "f 3 2 1\n" // good (flipped)
    );
    ett::WarningCapture warnings;
    const Loaded l = load(dir + "/d.obj");
    ASSERT_EQ(l.soup.size(), 2u);
    expect_vec_near(geometric_normal(l.soup, 0), glm::vec3(0, 0, 1), 1e-6f);
    expect_vec_near(geometric_normal(l.soup, 1), glm::vec3(0, 0, -1), 1e-6f);
    for (const glm::vec3& p : l.soup.positions)
        EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    EXPECT_EQ(warnings.count_containing("4 degenerate"), 1u)
        << (warnings.messages().empty() ? "no warning" : warnings.messages().front());
    EXPECT_EQ(warnings.count_containing(dir + "/d.obj"), warnings.messages().size());

    // A transform that collapses the mesh drops everything.
    write_file(dir + "/quad.obj", kQuad);
    const Loaded flat =
        load(dir + "/quad.obj", glm::scale(glm::mat4(1.0f), glm::vec3(1.0f, 1.0f, 0.0f)));
    EXPECT_EQ(flat.soup.size(), 0u);
    EXPECT_TRUE(flat.soup.positions.empty());
}

// tinyobjloader reads "nan" and a missing coordinate as 0: the vertex moved without a word, and
// "v nan 1 0" made a good triangle at x = 0. Now a non-finite coordinate skips the triangles that
// use the vertex (with the warning), and a word or a missing coordinate is an error at its line.
TEST(ObjLoader, NonFiniteAndMalformedVertices) {
    const std::string dir = ett::scratch_dir("obj-vertices");
    write_file(dir + "/nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 1 1e300\n"
                                 "f 1 2 3\nf 1 2 4\n");
    {
        ett::WarningCapture warnings;
        const Loaded l = load(dir + "/nan.obj");
        EXPECT_EQ(l.soup.size(), 0u);
        EXPECT_EQ(warnings.count_containing("2 degenerate"), 1u)
            << (warnings.messages().empty() ? "no warning" : warnings.messages().front());
    }
    const std::pair<const char*, const char*> bad[] = {
        {"v 0 0 0\nv 1 2\nv 0 1 0\nf 1 2 3\n", "line 2: a vertex needs three coordinates"},
        {"v 0 0 0\n# c\n  v 1 abc 0\nf 1 2 3\n", "line 3: vertex coordinate 'abc' is not a number"},
        {"v 0 0 0\nv\n", "line 2: a vertex needs three coordinates, this one has 0"}};
    for (const auto& [text, message] : bad) {
        write_file(dir + "/bad.obj", text);
        std::vector<et::Material> mats;
        et::TriangleSoup soup;
        try {
            et::load_obj(dir + "/bad.obj", glm::mat4(1.0f), -1, mats, soup);
            ADD_FAILURE() << text << ": no et::Error";
        } catch (const et::Error& e) {
            EXPECT_NE(std::string(e.what()).find(dir + "/bad.obj: " + message), std::string::npos)
                << e.what();
        }
    }
}

TEST(ObjLoader, AddTriangleKeepsSoupConsistent) {
    et::TriangleSoup soup;
    const glm::vec3 p[3] = {{0, 0, 0}, {1, 0, 0}, {0, 0, -1}}; // faces +Y
    EXPECT_TRUE(et::add_triangle(soup, p, nullptr, 7));
    const glm::vec3 line[3] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
    EXPECT_FALSE(et::add_triangle(soup, line, nullptr, 7));
    ASSERT_EQ(soup.size(), 1u);
    EXPECT_EQ(soup.positions.size(), 3u);
    EXPECT_EQ(soup.normals.size(), 3u);
    EXPECT_EQ(soup.material, std::vector<int>{7});
    for (const glm::vec3& n : soup.normals)
        expect_vec_near(n, glm::vec3(0, 1, 0), 1e-6f);
}

TEST(ObjLoader, UnreadablePathsThrowNamingTheFile) {
    const std::string dir = ett::scratch_dir("obj-bad");
    for (const std::string& path : {dir + "/missing.obj", dir}) {
        std::vector<et::Material> mats;
        et::TriangleSoup soup;
        try {
            et::load_obj(path, glm::mat4(1.0f), -1, mats, soup);
            ADD_FAILURE() << path << ": no et::Error";
        } catch (const et::Error& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find(path), std::string::npos) << m;
            EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        }
        EXPECT_EQ(soup.size(), 0u);
    }
}

} // namespace
