// Bad input never crashes and never yields NaN: every problem file gives a one-line et::Error
// naming it (or loads with sanitised texels and a warning), in the library and through the CLI.
#include "render/env_sampling.h"
#include "kernels/sampler.h"
#include "cli_run.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

// Loads `path`: an et::Error must be one line naming the file; a loaded map must be valid.
void expect_clean_outcome(const std::string& path) {
    SCOPED_TRACE(path);
    ett::WarningCapture warnings;
    try {
        const et::EnvMap env = et::load_envmap(path, {});
        for (float v : env.image.rgb)
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
        for (float v : env.dist.table)
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
        std::vector<float> u;
        for (int i = 0; i < 1024; ++i) {
            const etk::float2 x = etk::etk_sample_pair(ETK_SAMPLER_SOBOL, 1, 0, i, 0);
            u.push_back(x.x), u.push_back(x.y);
        }
        for (const auto& s : et::sample_env_host(env, u)) {
            ASSERT_TRUE(std::isfinite(s.pdf) && s.pdf >= 0.0f);
            ASSERT_EQ(s.pdf > 0.0f, env.dist.has_light());
            for (int c = 0; c < 3; ++c)
                ASSERT_TRUE(std::isfinite(s.radiance[c]) && std::isfinite(s.dir[c]));
        }
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << "not one line: " << m;
        EXPECT_NE(m.find(path), std::string::npos) << "does not name the file: " << m;
    }
}

void expect_error(const std::string& path, const std::string& what) {
    try {
        et::load_envmap(path, {});
        ADD_FAILURE() << path << ": loaded, expected an error (" << what << ")";
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        EXPECT_NE(m.find(path), std::string::npos) << m;
    }
}

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

TEST(EnvmapBadInput, MissingZeroByteDirectoryCorrupt) {
    const std::string dir = ett::scratch_dir("bad-input");
    expect_error(dir + "/missing.hdr", "missing");
    write_bytes(dir + "/empty.exr", "");
    expect_error(dir + "/empty.exr", "zero bytes");
    fs::create_directories(dir + "/folder.hdr");
    expect_error(dir + "/folder.hdr", "directory");
    std::string garbage;
    for (int i = 0; i < 4096; ++i)
        garbage.push_back(static_cast<char>((i * 2654435761u) >> 13));
    write_bytes(dir + "/garbage.exr", garbage);
    write_bytes(dir + "/garbage.hdr", garbage);
    write_bytes(dir + "/truncated.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 128 +X 256\n");
    expect_error(dir + "/garbage.exr", "corrupt");
    expect_error(dir + "/garbage.hdr", "corrupt");
    expect_error(dir + "/truncated.hdr", "truncated");
}

TEST(EnvmapBadInput, Unreadable) {
    const std::string dir = ett::scratch_dir("unreadable");
    const std::string path = dir + "/locked.exr";
    et::write_image(path, 8, 4, 3, std::vector<float>(8 * 4 * 3, 1.0f));
    ASSERT_EQ(chmod(path.c_str(), 0), 0);
    if (access(path.c_str(), R_OK) == 0) {
        // Root reads anything: the file loads, which is also a clean outcome.
        expect_clean_outcome(path);
        GTEST_SKIP() << "running as root: chmod 000 does not stop reads (clean load checked)";
    }
    expect_error(path, "unreadable");
}

TEST(EnvmapBadInput, NonFiniteAndNegativeTexelsWarnOnce) {
    et::RgbImage img = ett::constant_image(16, 8, 1.0f);
    img.at(1, 1)[0] = NAN;
    img.at(2, 2)[1] = INFINITY;
    img.at(3, 3)[2] = -INFINITY;
    img.at(4, 4)[0] = -5.0f;
    const std::string path = ett::scratch_dir("nan") + "/nan.exr";
    et::write_image(path, 16, 8, 3, img.rgb, {}, /*keep_non_finite=*/true);
    ett::WarningCapture w;
    const et::EnvMap env = et::load_envmap(path, {});
    EXPECT_EQ(w.count_containing("3 non-finite and 1 negative"), 1u);
    EXPECT_EQ(w.messages().size(), 1u);
    expect_clean_outcome(path);
}

TEST(EnvmapBadInput, DwabNegativeRingingWarnsOnceAndSamplesFine) {
    ETT_DATA_FILE(path, "envmaps/esplanade_512_dwab.exr");
    ett::WarningCapture w;
    const et::EnvMap env = et::load_envmap(path, {});
    ASSERT_EQ(w.messages().size(), 1u);
    EXPECT_NE(w.messages()[0].find("negative"), std::string::npos) << w.messages()[0];
    for (float v : env.image.rgb)
        ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
    et::EnvSamplerCL cl(ett::runtime(), env);
    for (const auto& s : cl.sample_sequence(ETK_SAMPLER_SOBOL, 3, 0, 0, 1 << 16)) {
        ASSERT_TRUE(s.pdf > 0.0f && std::isfinite(s.pdf));
        for (int c = 0; c < 3; ++c)
            ASSERT_TRUE(std::isfinite(s.radiance[c]) && s.radiance[c] >= 0.0f);
    }
}

TEST(EnvmapBadInput, AllBlackMapIsValidNoLight) {
    ett::WarningCapture w;
    const et::EnvMap env = et::make_envmap("black", ett::constant_image(32, 16, 0.0f), {});
    EXPECT_FALSE(env.dist.has_light());
    EXPECT_EQ(w.count_containing("black everywhere"), 1u);
    for (float v : env.dist.table)
        ASSERT_TRUE(std::isfinite(v));
    et::EnvSamplerCL cl(ett::runtime(), env);
    for (const auto& s : cl.sample_sequence(ETK_SAMPLER_RANDOM, 3, 0, 0, 4096)) {
        ASSERT_EQ(s.pdf, 0.0f);
        for (int c = 0; c < 3; ++c) {
            ASSERT_EQ(s.radiance[c], 0.0f);
            ASSERT_TRUE(std::isfinite(s.dir[c]));
        }
        EXPECT_EQ(etk::etk_env_pdf(env.dist.table.data(), env.desc(),
                                   etk::make_float3(s.dir[0], s.dir[1], s.dir[2])),
                  0.0f);
    }
}

TEST(EnvmapBadInput, OneByOneAndNon2to1WarnAndWork) {
    const std::string dir = ett::scratch_dir("shapes");
    et::write_image(dir + "/one.exr", 1, 1, 3, {2.0f, 1.0f, 0.5f});
    et::write_image(dir + "/square.hdr", 8, 8, 3, std::vector<float>(8 * 8 * 3, 0.3f));
    for (const char* name : {"/one.exr", "/square.hdr"}) {
        ett::WarningCapture w;
        const et::EnvMap env = et::load_envmap(dir + name, {});
        EXPECT_EQ(w.count_containing("not a 2:1"), 1u) << name;
        EXPECT_TRUE(env.dist.has_light());
        expect_clean_outcome(dir + name);
    }
}

TEST(EnvmapBadInput, EveryEdgeCaseImage) {
    const std::string dir = ett::data_file("edge-cases/images");
    if (dir.empty())
        GTEST_SKIP() << "edge-cases/images not found: set ENVTRACE_DATA to ../shared/data";
    int n = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        expect_clean_outcome(entry.path().string());
        ++n;
    }
    EXPECT_GT(n, 5);
}

// Runs build/envtrace with `args`; returns its wait status, stderr in `err`.
int run_cli(const std::vector<std::string>& args, std::string& err) {
    const ett::CliRun r = ett::run_envtrace(args, ett::scratch_dir("cli-err"));
    err = r.err;
    return r.status;
}

TEST(EnvmapBadInput, CliRejectsBadMapsWithOneLine) {
    const std::string dir = ett::scratch_dir("cli");
    write_bytes(dir + "/garbage.hdr", std::string(1000, '\x7f'));
    write_bytes(dir + "/empty.exr", "");
    fs::create_directories(dir + "/folder.exr");
    for (const std::string& bad :
         {dir + "/missing.exr", dir + "/garbage.hdr", dir + "/empty.exr", dir + "/folder.exr"}) {
        const std::string out = dir + "/points.png";
        std::string err;
        const int status = run_cli({"sample", bad, "-n", "16", "-o", out}, err);
        ASSERT_TRUE(WIFEXITED(status)) << bad << ": killed by signal " << WTERMSIG(status);
        EXPECT_NE(WEXITSTATUS(status), 0) << bad;
        EXPECT_EQ(err.rfind("envtrace: error: ", 0), 0u) << err;
        EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
        EXPECT_NE(err.find(bad), std::string::npos) << err;
        EXPECT_FALSE(fs::exists(out)) << bad;
        for (const auto& e : fs::directory_iterator(dir))
            EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
    }
}

TEST(EnvmapBadInput, CliSamplesDwabMapWithOneWarning) {
    ETT_DATA_FILE(path, "envmaps/esplanade_512_dwab.exr");
    const std::string out = ett::scratch_dir("cli-dwab") + "/points.png";
    std::string err;
    const int status = run_cli({"sample", path, "-n", "64", "-o", out}, err);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << err;
    EXPECT_EQ(err.rfind("envtrace: warning: ", 0), 0u) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_TRUE(fs::exists(out));
}

} // namespace
