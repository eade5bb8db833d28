// The resumable render state (host/lib/render/render_state.h): a round trip keeps every film
// value bit for bit; a truncated, corrupted or foreign file is refused with a message naming it;
// the key changes with anything a sample depends on and not with what it does not.
#include "render/render_state.h"
#include "render_util.h"
#include "test_data.h"
#include "util/error.h"

#include <gtest/gtest.h>
#include <xxhash.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace fs = std::filesystem;

namespace {

et::Scene small_scene() {
    et::Scene s =
        ett::base_scene(12, 8, et::make_envmap("sky", ett::constant_image(32, 16, 1.0f), {}));
    s.camera.eye = {0, 1, 3};
    s.materials.push_back(ett::diffuse(0.5f));
    const glm::vec3 p[3] = {{-2, 0, -2}, {2, 0, -2}, {0, 0, 2}};
    const glm::vec3 n[3] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    et::add_triangle(s.triangles, p, n, 0);
    s.settings.max_depth = 3;
    s.settings.backend = et::Backend::cpu;
    return s;
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

// The error thrown by reading `path`, or "" if it was read.
std::string read_error(const std::string& path) {
    try {
        et::read_render_state(path);
    } catch (const et::Error& e) {
        return e.what();
    }
    return "";
}

TEST(RenderState, RoundTripIsBitExact) {
    const std::string dir = ett::scratch_dir("render_state_roundtrip");
    const et::Scene s = small_scene();
    const et::DeviceScene ds = et::prepare_device_scene(s, s.settings);
    auto r = et::make_renderer(ds);
    for (int i = 0; i < 5; ++i)
        r->render_sample(i);
    et::RenderState st{et::render_key(ds), 5, 0, r->sums()};
    et::write_render_state(dir + "/a.envtrace-state", st);
    const et::RenderState back = et::read_render_state(dir + "/a.envtrace-state");
    EXPECT_EQ(back.key, st.key);
    EXPECT_EQ(back.spp, 5);
    EXPECT_EQ(back.first, 0);
    ASSERT_EQ(back.sums.width(), 12);
    ASSERT_EQ(back.sums.height(), 8);
    EXPECT_TRUE(back.sums == st.sums);
    EXPECT_NO_THROW(et::check_render_state(back, ds, "a"));
    // Nothing but the state itself is left in the folder (no temporary).
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(RenderState, DamagedFilesAreRefusedByName) {
    const std::string dir = ett::scratch_dir("render_state_damaged");
    const et::Scene s = small_scene();
    const et::DeviceScene ds = et::prepare_device_scene(s, s.settings);
    et::RenderState st{et::render_key(ds), 3, 0, et::FilmSums(12, 8)};
    st.sums.data()[7].sum[1] = et::film_fixed_point(2.0f);
    st.sums.data()[7].count = 3;
    const std::string good = dir + "/good.envtrace-state";
    et::write_render_state(good, st);
    const std::string bytes = read_bytes(good);
    ASSERT_GT(bytes.size(), 100u);

    const std::string p = dir + "/bad.envtrace-state";
    // Every truncation, from empty to one byte short.
    for (size_t n :
         {size_t(0), size_t(5), size_t(16), size_t(40), bytes.size() / 2, bytes.size() - 1}) {
        write_bytes(p, bytes.substr(0, n));
        const std::string e = read_error(p);
        EXPECT_NE(e.find(p), std::string::npos) << n << ": " << e;
    }
    // One flipped bit anywhere: in the header, in the film, in the checksum.
    for (size_t at : {size_t(0), size_t(20), bytes.size() / 2, bytes.size() - 1}) {
        std::string b = bytes;
        b[at] = static_cast<char>(b[at] ^ 0x10);
        write_bytes(p, b);
        const std::string e = read_error(p);
        EXPECT_NE(e.find(p), std::string::npos) << at << ": " << e;
    }
    // Trailing bytes, another file type, a missing file.
    write_bytes(p, bytes + "x");
    EXPECT_NE(read_error(p).find(p), std::string::npos);
    write_bytes(p, "P3\n1 1\n255\n0 0 0\n");
    EXPECT_NE(read_error(p).find(p), std::string::npos);
    EXPECT_NE(read_error(dir + "/missing").find("missing"), std::string::npos);
    EXPECT_EQ(read_error(good), "");
}

TEST(RenderState, KeyFollowsWhatSamplesDependOn) {
    const et::Scene s = small_scene();
    const uint64_t base = et::render_key(et::prepare_device_scene(s, s.settings));
    EXPECT_EQ(base, et::render_key(et::prepare_device_scene(s, s.settings)));

    auto key_with = [&](auto change) {
        et::Scene c = s;
        change(c, c.settings);
        return et::render_key(et::prepare_device_scene(c, c.settings));
    };
    // Not: the target spp, the time limit, paths in flight, threads, where the map samples are
    // drawn (--light-batch: the same bits, Backends.BatchedLightSamplesGiveTheSameBits).
    EXPECT_EQ(base, key_with([](et::Scene&, et::RenderSettings& st) {
                  st.spp = 999;
                  st.time_limit = 3;
                  st.paths = 17;
                  st.threads = 1;
              }));
    for (et::LightBatch b : {et::LightBatch::off, et::LightBatch::on, et::LightBatch::automatic})
        EXPECT_EQ(base, key_with([b](et::Scene&, et::RenderSettings& st) { st.light_batch = b; }));
    // But: the seed, the depth, the strategy, the sampler, the camera, a material, geometry, the
    // map's texels, the back end.
    EXPECT_NE(base, key_with([](et::Scene&, et::RenderSettings& st) { st.seed += 1; }));
    EXPECT_NE(base, key_with([](et::Scene&, et::RenderSettings& st) { st.max_depth = 2; }));
    EXPECT_NE(base, key_with([](et::Scene&, et::RenderSettings& st) { st.rr_depth = 2; }));
    EXPECT_NE(base, key_with([](et::Scene&, et::RenderSettings& st) {
                  st.strategy = et::Strategy::bsdf;
              }));
    EXPECT_NE(base, key_with([](et::Scene&, et::RenderSettings& st) {
                  st.sampler = st.sampler == et::SamplerKind::random ? et::SamplerKind::sobol
                                                                     : et::SamplerKind::random;
              }));
    EXPECT_NE(base, key_with([](et::Scene& c, et::RenderSettings&) { c.camera.eye.x += 1e-3f; }));
    EXPECT_NE(base, key_with([](et::Scene& c, et::RenderSettings&) {
                  c.materials[0] = ett::diffuse(0.51f);
              }));
    EXPECT_NE(base, key_with([](et::Scene& c, et::RenderSettings&) {
                  const glm::vec3 p[3] = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
                  const glm::vec3 n[3] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
                  et::add_triangle(c.triangles, p, n, 0);
              }));
    EXPECT_NE(base, key_with([](et::Scene& c, et::RenderSettings&) {
                  c.env = et::make_envmap("sky", ett::constant_image(32, 16, 1.5f), {});
              }));
    EXPECT_NE(base, key_with([](et::Scene&, et::RenderSettings& st) {
                  st.backend = et::Backend::opencl;
              }));
    // The visibility strategy's verdict, which the host schedules: on or off, and its cost.
    et::Scene v = s;
    v.settings.strategy = et::Strategy::visibility;
    const et::DeviceScene with = et::prepare_device_scene(v, v.settings);
    et::RenderSettings off = v.settings;
    off.guide_verdict = false;
    EXPECT_NE(et::render_key(with), et::render_key(et::prepare_device_scene(v, off)));
    et::DeviceScene dearer = et::prepare_device_scene(v, v.settings);
    dearer.guide_options.verdict_cost *= 2.0;
    dearer.guide_options.verdict_cost_guided *= 2.0;
    EXPECT_NE(et::render_key(with), et::render_key(dearer));
}

TEST(RenderState, ForeignStateIsRefused) {
    const et::Scene s = small_scene();
    const et::DeviceScene ds = et::prepare_device_scene(s, s.settings);
    et::RenderSettings other = s.settings;
    other.seed += 1;
    const et::DeviceScene ds2 = et::prepare_device_scene(s, other);
    et::RenderState st{et::render_key(ds2), 3, 0, et::FilmSums(12, 8)};
    try {
        et::check_render_state(st, ds, "x.envtrace-state");
        FAIL() << "accepted a state of another seed";
    } catch (const et::Error& e) {
        EXPECT_NE(std::string(e.what()).find("x.envtrace-state"), std::string::npos) << e.what();
    }
}

} // namespace

namespace {

// A state of the previous format (2: no AOV flag or sums) is refused with both versions named,
// not misread.
TEST(RenderState, OlderFormatIsRefusedWithItsVersion) {
    const std::string dir = ett::scratch_dir("render_state_v2");
    et::RenderState st{1234, 1, 0, et::FilmSums(4, 2)};
    const std::string good = dir + "/good.envtrace-state";
    et::write_render_state(good, st);
    std::string bytes = read_bytes(good);
    ASSERT_GT(bytes.size(), 20u);
    bytes[16] = 2; // the version, after the 16-byte magic (little-endian)
    bytes[17] = bytes[18] = bytes[19] = 0;
    const std::string p = dir + "/v2.envtrace-state";
    write_bytes(p, bytes);
    const std::string e = read_error(p);
    EXPECT_NE(e.find("format version 2, this envtrace reads 3 to 4"), std::string::npos) << e;
}

// `bytes` with its trailing XXH3 checksum made right again.
std::string with_checksum(std::string bytes) {
    const uint64_t sum = XXH3_64bits(bytes.data(), bytes.size() - sizeof sum);
    std::memcpy(&bytes[bytes.size() - sizeof sum], &sum, sizeof sum);
    return bytes;
}

// Version 4 keeps the whole render's samples (`total`, merge's check) in version 3's reserved
// field: a version 3 state still reads (total 0: unknown), a version 3 state with the field set
// does not, nor a total short of the samples the state holds.
TEST(RenderState, TotalSamplesAndTheFormatBeforeThem) {
    const std::string dir = ett::scratch_dir("render_state_total");
    et::RenderState st{1234, 3, 2, et::FilmSums(4, 2), 8};
    const std::string path = dir + "/s.envtrace-state";
    et::write_render_state(path, st);
    EXPECT_EQ(et::read_render_state(path).total, 8);
    const size_t total_at =
        16 + 4 + 4 + 8 + 4 * 4 + 4; // magic, version, order, key, w h spp first, aovs
    std::string bytes = read_bytes(path);
    int32_t total = 0;
    std::memcpy(&total, &bytes[total_at], sizeof total);
    ASSERT_EQ(total, 8) << "the header layout changed";
    bytes[16] = 3;
    write_bytes(path, with_checksum(bytes));
    EXPECT_NE(read_error(path).find("header does not match"), std::string::npos)
        << read_error(path);
    std::memset(&bytes[total_at], 0, 4);
    write_bytes(path, with_checksum(bytes));
    EXPECT_EQ(read_error(path), "");
    EXPECT_EQ(et::read_render_state(path).total, 0);
    bytes[16] = 4;
    total = 4; // first 2 + spp 3 = 5 samples reached: a total of 4 cannot be
    std::memcpy(&bytes[total_at], &total, sizeof total);
    write_bytes(path, with_checksum(bytes));
    EXPECT_NE(read_error(path).find("header does not match"), std::string::npos)
        << read_error(path);
}

} // namespace
