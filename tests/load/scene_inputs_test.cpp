// Scenes given in memory and edited in memory (load/scene.h SceneInputs, load/scene_edit.h): the
// same triangles as from a file, and edits that are all or nothing with the loader's messages.
#include "load/scene.h"
#include "load/scene_edit.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

namespace {

using json = nlohmann::json;

// Two triangles over four corners, with normals and uvs; the same as an ASCII PLY.
et::MeshArrays two_triangles() {
    et::MeshArrays m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, -1}, {0, 0.25f, -1}};
    m.normals = {{0, 1, 0}, {0.1f, 1, 0}, {0, 1, 0.2f}, {0, 1, 0}};
    m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

void write_ply(const std::string& path, const et::MeshArrays& m) {
    std::ofstream f(path);
    f << "ply\nformat ascii 1.0\nelement vertex " << m.positions.size() << "\n";
    for (const char* p : {"x", "y", "z", "nx", "ny", "nz", "u", "v"})
        f << "property float " << p << "\n";
    f << "element face " << m.indices.size() / 3 << "\nproperty list uchar int vertex_indices\n";
    f << "end_header\n";
    f.precision(9);
    for (size_t i = 0; i < m.positions.size(); ++i) {
        const auto &p = m.positions[i], &n = m.normals[i];
        f << p.x << " " << p.y << " " << p.z << " " << n.x << " " << n.y << " " << n.z << " "
          << m.uvs[i].x << " " << m.uvs[i].y << "\n";
    }
    for (size_t t = 0; t < m.indices.size(); t += 3)
        f << "3 " << m.indices[t] << " " << m.indices[t + 1] << " " << m.indices[t + 2] << "\n";
}

json scene_with(const json& mesh) {
    json shape = {{"type", "mesh"}, {"transform", {{"rotate", {0, 1, 0, 30}}, {"scale", -2}}}};
    shape.update(mesh);
    return {{"environment", {{"arrays", "sky"}}}, {"shapes", json::array({shape})}};
}

et::SceneInputs inputs() {
    et::SceneInputs in;
    in.meshes["quad"] = two_triangles();
    in.maps["sky"] = ett::constant_image(16, 8, 0.5f);
    return in;
}

template <class T> bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(SceneInputs, MeshArraysGiveTheTrianglesOfTheSameDataAsAFile) {
    const std::string dir = ett::scratch_dir("scene_inputs");
    write_ply(dir + "/quad.ply", two_triangles());
    const et::Scene a = et::load_scene_json(scene_with({{"file", "quad.ply"}}), "a", dir, inputs());
    const et::Scene b = et::load_scene_json(scene_with({{"arrays", "quad"}}), "b", dir, inputs());
    ASSERT_EQ(a.triangles.size(), 2u);
    EXPECT_TRUE(same_bits(a.triangles.positions, b.triangles.positions));
    EXPECT_TRUE(same_bits(a.triangles.normals, b.triangles.normals));
    EXPECT_TRUE(same_bits(a.triangles.uvs, b.triangles.uvs));
    EXPECT_EQ(a.triangles.material, b.triangles.material);
    EXPECT_TRUE(same_bits(b.env.image.rgb, ett::constant_image(16, 8, 0.5f).rgb));
}

TEST(SceneInputs, BadArraysAreNamed) {
    et::SceneInputs in = inputs();
    in.meshes["quad"].indices[4] = 7;
    EXPECT_EQ(ett::error_of([&] {
                  et::load_scene_json(scene_with({{"arrays", "quad"}}), "s", "", in);
              }),
              "s: shapes[0]: triangle 1: vertex index 7 is out of range (4 vertices)");
    EXPECT_EQ(ett::error_of([&] {
                  et::load_scene_json(scene_with({{"arrays", "box"}}), "s", "", in);
              }),
              "s: shapes[0].arrays: names no mesh given in memory with the scene");
    const json both = scene_with({{"arrays", "quad"}, {"file", "quad.ply"}});
    EXPECT_EQ(ett::error_of([&] { et::load_scene_json(both, "s", "", in); }),
              "s: shapes[0]: has both \"file\" and \"arrays\": give one");
}

TEST(SceneEdit, ChangesWhatItNamesAndNothingElse) {
    et::Scene s = et::load_scene_json(scene_with({{"arrays", "quad"}}), "s", "", inputs());
    const et::Scene before = s;
    et::edit_scene(s, {{"environment", {{"rotation", 90}}}, {"camera", {{"fov", 20}}}}, "edit", "");
    EXPECT_EQ(s.env.rotation_degrees, 90.0f);
    EXPECT_EQ(s.env.scale, before.env.scale);
    EXPECT_EQ(s.camera.fov_deg, 20.0f);
    EXPECT_EQ(s.camera.eye, before.camera.eye);
    EXPECT_TRUE(same_bits(s.env.image.rgb, before.env.image.rgb));
    EXPECT_TRUE(same_bits(s.triangles.positions, before.triangles.positions));
}

TEST(SceneEdit, AFailedEditLeavesTheSceneAsItWas) {
    et::Scene s = et::load_scene_json(scene_with({{"arrays", "quad"}}), "s", "", inputs());
    const json bad = {{"camera", {{"fov", 30}}}, {"render", {{"max_depth", 0}}}};
    EXPECT_NE(
        ett::error_of([&] { et::edit_scene(s, bad, "edit", ""); }).find("edit: render.max_depth"),
        std::string::npos);
    EXPECT_EQ(s.camera.fov_deg, et::Camera{}.fov_deg);
    EXPECT_EQ(ett::error_of([&] {
                  et::edit_scene(s, {{"environment", {{"map", "x.exr"}}}}, "edit", "");
              }),
              "edit: environment.map: changes the map or its distribution: load the scene again "
              "with it (an edit changes \"intensity\", \"rotation\" and \"convention\")");
    EXPECT_EQ(ett::error_of([&] {
                  et::edit_scene(s, {{"materials", {{"gold", json::object()}}}}, "edit", "");
              }),
              "edit: materials.gold: the scene has no material of this name (it has: s: "
              "shapes[0]:default)");
}

} // namespace
