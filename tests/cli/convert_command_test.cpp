// `envtrace convert`: an HDR image through EXR and back to PFM keeps its floats bit for bit, an
// 8-bit image comes out linear, and a conversion over its own input or from a missing file fails
// with a message naming the file, leaving the input as it was.
#include "image/image_io.h"
#include "test_data.h"
#include "cli_run.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::string bytes_of(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

} // namespace

TEST(ConvertCli, PfmThroughExrAndBackIsBitForBit) {
    const std::string dir = ett::scratch_dir("convert-cli");
    std::vector<float> px(5 * 3 * 3);
    for (size_t i = 0; i < px.size(); ++i)
        px[i] = std::ldexp(1.0f + 0.37f * static_cast<float>(i), static_cast<int>(i % 11) - 5);
    et::write_image(dir + "/a.pfm", 5, 3, 3, px);
    ASSERT_EQ(ett::run_envtrace({"convert", dir + "/a.pfm", dir + "/b.exr"}, dir).code(), 0);
    ASSERT_EQ(ett::run_envtrace({"convert", dir + "/b.exr", dir + "/c.pfm"}, dir).code(), 0);
    EXPECT_EQ(bytes_of(dir + "/a.pfm"), bytes_of(dir + "/c.pfm"));

    // An 8-bit image is decoded from sRGB: 255 -> 1, 0 -> 0, 128 -> 0.2158.
    et::write_image(dir + "/d.png", 3, 1, 3, {1, 1, 1, 0, 0, 0, 0.5f, 0.5f, 0.5f});
    ASSERT_EQ(ett::run_envtrace({"convert", dir + "/d.png", dir + "/d.pfm"}, dir).code(), 0);
    const et::RgbImage d = et::read_rgb_image(dir + "/d.pfm");
    ASSERT_EQ(d.rgb.size(), 9u);
    EXPECT_EQ(d.rgb[0], 1.0f);
    EXPECT_EQ(d.rgb[3], 0.0f);
    EXPECT_NEAR(d.rgb[6], et::srgb_to_linear(128.0f / 255.0f), 1e-6f);
}

// To an 8-bit format the linear values are sRGB-encoded, so that envtrace reads back what it
// wrote (within the 8-bit step), PNG to PNG is a copy, and values beyond [0, 1] are clipped with a
// warning. Linear values were written as they were: 0.5 came back 0.214, and every pass darkened.
TEST(ConvertCli, EightBitOutputsReadBackAsWritten) {
    const std::string dir = ett::scratch_dir("convert-cli-8bit");
    const std::vector<float> linear = {0.5f, 0.5f, 0.5f, 0.02f, 0.2f, 0.9f, 0.0f, 1.0f, 0.25f};
    et::write_image(dir + "/a.pfm", 3, 1, 3, linear);
    ett::CliRun r = ett::run_envtrace({"convert", dir + "/a.pfm", dir + "/a.png"}, dir);
    ASSERT_EQ(r.code(), 0) << r.err;
    EXPECT_EQ(r.err.find("clipped"), std::string::npos) << r.err;
    const et::RgbImage back = et::read_rgb_image(dir + "/a.png");
    ASSERT_EQ(back.rgb.size(), linear.size());
    for (size_t i = 0; i < linear.size(); ++i) // half an 8-bit step of sRGB
        EXPECT_NEAR(back.rgb[i], linear[i], 0.003f + 0.01f * linear[i]) << "value " << i;
    // JPEG (lossy, colour subsampled): a grey 0.5 comes back 0.5, not the 0.214 of 128 decoded.
    et::write_image(dir + "/grey.pfm", 8, 8, 3, std::vector<float>(192, 0.5f));
    r = ett::run_envtrace({"convert", dir + "/grey.pfm", dir + "/grey.jpg"}, dir);
    ASSERT_EQ(r.code(), 0) << r.err;
    for (float v : et::read_rgb_image(dir + "/grey.jpg").rgb)
        ASSERT_NEAR(v, 0.5f, 0.01f);
    ASSERT_EQ(ett::run_envtrace({"convert", dir + "/a.png", dir + "/b.png"}, dir).code(), 0);
    const et::RgbImage a = et::read_rgb_image(dir + "/a.png"),
                       b = et::read_rgb_image(dir + "/b.png");
    EXPECT_EQ(a.rgb, b.rgb) << "PNG to PNG changed the values";

    et::write_image(dir + "/hdr.pfm", 2, 1, 3, {4.0f, 0.5f, -1.0f, 0.5f, 0.5f, 0.5f});
    r = ett::run_envtrace({"convert", dir + "/hdr.pfm", dir + "/hdr.png"}, dir);
    ASSERT_EQ(r.code(), 0) << r.err;
    EXPECT_NE(r.err.find("2 of 6 values outside [0, 1] clipped"), std::string::npos) << r.err;
    EXPECT_EQ(et::read_rgb_image(dir + "/hdr.png").rgb[0], 1.0f);
}

TEST(ConvertCli, RefusesItsOwnInputAndMissingFiles) {
    const std::string dir = ett::scratch_dir("convert-cli-refuse");
    et::write_image(dir + "/a.pfm", 2, 2, 3, std::vector<float>(12, 0.5f));
    const std::string before = bytes_of(dir + "/a.pfm");
    ett::CliRun r = ett::run_envtrace({"convert", dir + "/a.pfm", dir + "/a.pfm"}, dir);
    EXPECT_NE(r.code(), 0);
    EXPECT_NE(r.err.find(dir + "/a.pfm"), std::string::npos) << r.err;
    EXPECT_EQ(bytes_of(dir + "/a.pfm"), before);
    r = ett::run_envtrace({"convert", dir + "/missing.hdr", dir + "/m.pfm"}, dir);
    EXPECT_NE(r.code(), 0);
    EXPECT_NE(r.err.find("missing.hdr: no such file"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir + "/m.pfm"));
}
