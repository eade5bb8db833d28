// Reading JSON input: positions for what the parser cannot bound (depth, 1e999), short messages
// whatever the size of the offending value, and typed access with key paths.
#include "util/error.h"
#include "util/json_file.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <fstream>

namespace {

using json = nlohmann::json;

std::string error_of_file(const std::string& path) {
    try {
        et::read_json_file(path);
    } catch (const et::Error& e) {
        return e.what();
    }
    return "(no error)";
}

std::string write(const std::string& name, const std::string& text) {
    const std::string path = ett::scratch_dir("json-" + name) + "/" + name + ".json";
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

TEST(JsonFile, DeepNestingIsAnErrorWithPosition) {
    const std::string path =
        write("deep", "{\"spp\":\n  " + std::string(100000, '[') + std::string(100000, ']') + "}");
    const std::string m = error_of_file(path);
    EXPECT_EQ(m.rfind(path + ":2:", 0), 0u) << m;
    EXPECT_NE(m.find("nested deeper than 64"), std::string::npos) << m;
    EXPECT_LT(m.size(), path.size() + 100);
    // 64 levels are fine.
    const std::string ok = write("deep-ok", std::string(64, '[') + std::string(64, ']'));
    EXPECT_NO_THROW(et::read_json_file(ok));
}

TEST(JsonFile, NumbersBeyondADoubleAreAnErrorWithPosition) {
    for (const std::string& number :
         {std::string("1e999"), std::string("-1e400"), std::string(400, '9')}) {
        const std::string path = write("huge", "{\n  \"a\": [1, " + number + "]\n}");
        const std::string m = error_of_file(path);
        EXPECT_EQ(m.rfind(path + ":2:12: number ", 0), 0u) << m;
        EXPECT_NE(m.find("out of range"), std::string::npos) << m;
        EXPECT_EQ(m.find("json.exception"), std::string::npos) << m;
        EXPECT_LT(m.size(), path.size() + 150) << m;
    }
    // Inside strings, nothing is a number.
    EXPECT_NO_THROW(et::read_json_file(write("str", "{\"a\": \"1e999 [[[[\"}")));
}

TEST(JsonFile, DuplicateKeysAreAnErrorWithBothPositions) {
    const std::string path =
        write("dup", "{\"render\": {\"spp\": 2,\n  \"spp\" : 3}, \"film\": {\"spp\": 1}}");
    const std::string m = error_of_file(path);
    EXPECT_EQ(m.rfind(path + ":2:3: duplicate key \"spp\"", 0), 0u) << m;
    EXPECT_NE(m.find("first at " + path + ":1:13"), std::string::npos) << m;
    // The same key in different objects, in arrays of objects, and as a string value: fine.
    EXPECT_NO_THROW(et::read_json_file(
        write("nodup",
              "{\"a\": {\"a\": \"a\"}, \"l\": [{\"k\": 1}, {\"k\": 2}], \"b\": [\"b\", \"b\"]}")));
}

TEST(JsonFile, MalformedMessagesStayShort) {
    // An unterminated 10 MB string: the parser's message quotes the token it read.
    const std::string path = write("long", "{\"a\": \"" + std::string(10 << 20, 'x'));
    const std::string m = error_of_file(path);
    EXPECT_EQ(m.rfind(path + ":1:", 0), 0u) << m.substr(0, 300);
    EXPECT_LT(m.size(), path.size() + 250) << m.substr(0, 300);
}

TEST(JsonExcerpt, ShortWhateverTheValue) {
    EXPECT_EQ(et::json_excerpt(json(5)), "5");
    EXPECT_EQ(et::json_excerpt(json(1.5)), "1.5");
    EXPECT_EQ(et::json_excerpt(json("big")), "\"big\"");
    EXPECT_EQ(et::json_excerpt(json::array({1, 2})), "an array of 2 elements");
    EXPECT_EQ(et::json_excerpt(json::object()), "an object of 0 keys");
    const std::string e = et::json_excerpt(json(std::string(10 << 20, 'y')));
    EXPECT_LT(e.size(), 70u);
    EXPECT_EQ(e.substr(e.size() - 3), "...");
    // A cut never splits a UTF-8 character, and invalid UTF-8 does not throw.
    EXPECT_NO_THROW(et::json_excerpt(json(std::string(100, '\xe9'))));
    EXPECT_EQ(et::excerpt(std::string(59, 'a') + "\xc3\xa9" + "bbb", 60),
              std::string(59, 'a') + "...");
    // 100,000 levels of nesting: no recursion, no stack overflow.
    json deep = json::array();
    for (int i = 0; i < 100000; ++i)
        deep = json::array({std::move(deep)});
    EXPECT_EQ(et::json_excerpt(deep), "an array of 1 element");
}

TEST(JsonReader, TypesAndRangesWithKeyPaths) {
    const json j = json::parse(R"({"render": {"spp": 1.5, "n": 64.0, "seed": -1, "big": 1e10,
        "s": 5, "b": "yes", "o": 5}, "camera": 5})");
    const et::JsonReader r("scene.json");
    auto error = [](auto f) -> std::string {
        try {
            f();
        } catch (const et::Error& e) {
            return e.what();
        }
        return "(no error)";
    };
    const et::JsonReader rr = r.at("render");
    const json& s = j["render"];
    EXPECT_EQ(error([&] { rr.integer(s, "spp", 1, 1, 100); }),
              "scene.json: render.spp: expected an integer in [1, 100], got 1.5");
    EXPECT_EQ(rr.integer(s, "n", 1, 1, 100), 64); // an integer written as a float
    EXPECT_EQ(rr.integer(s, "missing", 7, 1, 100), 7);
    EXPECT_NE(error([&] { rr.integer(s, "seed", 0, 0, 4294967295LL); }).find("got -1"),
              std::string::npos);
    EXPECT_NE(error([&] { rr.integer(s, "big", 0, 0, 4294967295LL); }).find("render.big"),
              std::string::npos);
    EXPECT_NE(error([&] { rr.string(s, "s", ""); }).find("render.s: expected a string, got 5"),
              std::string::npos);
    EXPECT_NE(error([&] { rr.boolean(s, "b", true); }).find("expected true or false"),
              std::string::npos);
    EXPECT_NE(error([&] { rr.object(s, "o"); }).find("render.o: expected an object, got 5"),
              std::string::npos);
    EXPECT_NE(error([&] { r.object(j, "camera"); }).find("scene.json: camera: expected an object"),
              std::string::npos);
    EXPECT_NE(error([&] { rr.number(s, "n", 0, 0, 10); }).find("expected a number in [0, 10]"),
              std::string::npos);
    // Float limits: the value written in decimal (0.05, or 4 pi rounded in double) is inside
    // when it equals the limit as a float, and comes back clamped; a value beyond shows digits
    // that differ from the limit's.
    const json f = json::parse(R"({"lo": 0.05, "hi": 12.566370614359966, "out": 0.0499999})");
    EXPECT_EQ(r.number(f, "lo", 1, 0.05f, 1), 0.05f);
    EXPECT_EQ(r.number(f, "hi", 0, 0, 4 * M_PI), 4 * M_PI);
    EXPECT_NE(error([&] {
                  r.number(f, "out", 1, 0.05f, 1);
              }).find("expected a number in [0.05, 1], got 0.0499999"),
              std::string::npos);
    EXPECT_EQ(r.at("shapes").at(size_t(2)).at("transform").where(),
              "scene.json: shapes[2].transform");
}

} // namespace

namespace {

std::string rejection(const json& object, const std::vector<std::string>& known) {
    try {
        et::JsonReader("scene.json").at("materials").at(2).reject_unknown_keys(object, known);
    } catch (const et::Error& e) {
        return e.what();
    }
    return "(no error)";
}

} // namespace

// A key nearly like a known one (a letter missing, added, changed, two swapped, another case) is
// suggested; one far from all of them, or a short one with every letter different, is not.
TEST(JsonReader, ClosestKeySuggestsOnlyNearOnes) {
    const std::vector<std::string> known = {"type", "albedo", "roughness", "ior", "k", "eta"};
    EXPECT_EQ(et::closest_key("roughnes", known), "roughness");
    EXPECT_EQ(et::closest_key("roughnesss", known), "roughness");
    EXPECT_EQ(et::closest_key("rougness", known), "roughness");
    EXPECT_EQ(et::closest_key("albdeo", known), "albedo");
    EXPECT_EQ(et::closest_key("Albedo", known), "albedo");
    EXPECT_EQ(et::closest_key("typo", known), "type");
    EXPECT_EQ(et::closest_key("colour", known), "");
    EXPECT_EQ(et::closest_key("x", known), "");
    EXPECT_EQ(et::closest_key("transmission", known), "");
    EXPECT_EQ(et::closest_key("roughness", {}), "");
}

TEST(JsonReader, UnknownKeysAreErrorsNamingThePath) {
    const std::vector<std::string> known = {"type", "albedo", "roughness"};
    EXPECT_EQ(rejection(json::parse(R"({"type": "plastic", "roughness": 0.2})"), known),
              "(no error)");
    EXPECT_EQ(rejection(json::parse(R"({"type": "plastic", "roughnes": 0.2})"), known),
              "scene.json: materials[2].roughnes: unknown key; did you mean \"roughness\"?");
    EXPECT_EQ(rejection(json::parse(R"({"colour": [1, 0, 0]})"), known),
              "scene.json: materials[2].colour: unknown key (known here: type, albedo, "
              "roughness)");
    // Not an object: the caller's type check reports it.
    EXPECT_EQ(rejection(json::parse("[1]"), known), "(no error)");
}
