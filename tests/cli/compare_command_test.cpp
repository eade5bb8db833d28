// `envtrace compare` from the command line: metrics of known images, a non-zero exit with a
// one-line message naming both sizes on a size mismatch, and on a missing file.
#include "image/image_io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

// Runs envtrace with `args`; returns the exit status and fills the combined output.
int run_cli(const std::string& args, std::string& out) {
    const std::string cmd = std::string(ENVTRACE_EXE) + " " + args + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    if (!p)
        return -1;
    char buf[512];
    out.clear();
    while (fgets(buf, sizeof buf, p))
        out += buf;
    const int status = pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(CompareCli, MetricsSizeMismatchAndMissingFile) {
    const std::string dir = ett::scratch_dir("compare_cli");
    et::write_image(dir + "/a.exr", 4, 2, 3, std::vector<float>(24, 2.0f));
    et::write_image(dir + "/b.exr", 4, 2, 3, std::vector<float>(24, 1.0f));
    et::write_image(dir + "/c.exr", 3, 3, 3, std::vector<float>(27, 1.0f));
    std::string out;
    ASSERT_EQ(run_cli("compare " + dir + "/a.exr " + dir + "/b.exr --json " + dir + "/m.json", out),
              0)
        << out;
    EXPECT_NE(out.find("l2 1\n"), std::string::npos) << out;
    EXPECT_NE(out.find("rmse 1\n"), std::string::npos) << out;
    std::ifstream j(dir + "/m.json");
    EXPECT_TRUE(j.good());

    EXPECT_EQ(run_cli("compare " + dir + "/a.exr " + dir + "/c.exr", out), 1);
    EXPECT_NE(out.find("4x2"), std::string::npos) << out;
    EXPECT_NE(out.find("3x3"), std::string::npos) << out;
    EXPECT_EQ(run_cli("compare " + dir + "/a.exr " + dir + "/missing.exr", out), 1);
    EXPECT_NE(out.find("missing.exr"), std::string::npos) << out;
    // --json over an input, or into a missing folder: refused before any metric is printed.
    EXPECT_EQ(run_cli("compare " + dir + "/a.exr " + dir + "/b.exr --json " + dir + "/b.exr", out),
              1);
    EXPECT_NE(out.find("refusing to write an output over"), std::string::npos) << out;
    EXPECT_EQ(out.find("l2"), std::string::npos) << out;
    EXPECT_EQ(
        run_cli("compare " + dir + "/a.exr " + dir + "/b.exr --json " + dir + "/no/m.json", out),
        1);
    EXPECT_EQ(out.find("l2"), std::string::npos) << out;
}

// NaN or Inf in either image: an error naming the file (an all-NaN image compared as 'l2 0').
TEST(CompareCli, NonFiniteImagesAreRefused) {
    const std::string dir = ett::scratch_dir("compare_nan");
    et::write_image(dir + "/ok.exr", 4, 2, 3, std::vector<float>(24, 1.0f));
    ett::write_raw_exr(dir + "/nan.exr", 4, 2, std::vector<float>(24, NAN));
    std::string out;
    EXPECT_EQ(run_cli("compare " + dir + "/nan.exr " + dir + "/ok.exr", out), 1) << out;
    EXPECT_NE(out.find("envtrace: error: " + dir + "/nan.exr: 24 of 24 values are NaN"),
              std::string::npos)
        << out;
    EXPECT_EQ(run_cli("compare " + dir + "/ok.exr " + dir + "/nan.exr", out), 1) << out;
    EXPECT_EQ(out.find("l2"), std::string::npos) << out;
}

// A black reference makes l2 infinite (the JSON wrote "l2": null with exit 0): refused, naming
// the reference and giving the rmse; a black image against a black reference is a match.
TEST(CompareCli, BlackReferenceIsRefused) {
    const std::string dir = ett::scratch_dir("compare_black");
    et::write_image(dir + "/grey.pfm", 4, 2, 3, std::vector<float>(24, 0.5f));
    et::write_image(dir + "/black.pfm", 4, 2, 3, std::vector<float>(24, 0.0f));
    std::string out;
    EXPECT_EQ(
        run_cli("compare " + dir + "/grey.pfm " + dir + "/black.pfm --json " + dir + "/m.json",
                out),
        1)
        << out;
    EXPECT_NE(out.find(dir + "/black.pfm: the reference is black"), std::string::npos) << out;
    EXPECT_NE(out.find("rmse 0.5"), std::string::npos) << out;
    EXPECT_FALSE(std::filesystem::exists(dir + "/m.json"));
    EXPECT_EQ(run_cli("compare " + dir + "/black.pfm " + dir + "/black.pfm", out), 0) << out;
    EXPECT_NE(out.find("l2 0"), std::string::npos) << out;
}

} // namespace
