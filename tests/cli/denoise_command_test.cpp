// `envtrace render --denoise` and `--live-preview` from the command line: at 16 spp the denoised
// image is closer to a converged reference than the noisy one (fixed seeds; skipped where Open
// Image Denoise is not installed); without the denoiser the render fails up front, naming how to
// install it, and writes nothing; a live preview leaves whole images and no temporaries.
#include "cli_run.h"
#include "image/denoise.h"
#include "image/image_io.h"
#include "image/image_metrics.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

namespace fs = std::filesystem;

namespace {

// DIR/s.json: a glossy sphere on a diffuse floor under a small sky brighter towards +Y, whose
// soft shadow and glossy highlight are what 16 spp leaves noisy.
std::string write_scene(const std::string& dir) {
    fs::create_directories(dir);
    std::vector<float> sky(32 * 16 * 3);
    for (size_t i = 0; i < sky.size(); ++i)
        sky[i] = 0.2f + 4.0f * float(16 - (i / 3) / 32) / 16.0f;
    et::write_image(dir + "/sky.exr", 32, 16, 3, sky);
    std::ofstream(dir + "/s.json") << R"({
  "camera": {"eye": [0, 1.2, 3.5], "target": [0, 0.4, 0], "fov": 40},
  "film": {"width": 48, "height": 36},
  "environment": {"map": ")" + dir + R"(/sky.exr"},
  "materials": {"floor": {"type": "diffuse", "albedo": [0.7, 0.6, 0.5]},
                "ball": {"type": "plastic", "albedo": [0.2, 0.4, 0.8], "roughness": 0.3}},
  "shapes": [{"type": "sphere", "radius": 0.6, "center": [0, 0.6, 0], "material": "ball"},
             {"type": "quad", "center": [0, 0, 0], "size": 8, "material": "floor"}],
  "render": {"max_depth": 4}
}
)";
    return dir + "/s.json";
}

std::vector<std::string> render_args(const std::string& scene, const std::string& out,
                                     std::vector<std::string> more) {
    std::vector<std::string> a = {"render", scene, "--backend", "cpu", "--threads", "2", "-o", out};
    a.insert(a.end(), more.begin(), more.end());
    return a;
}

std::string read_text(const std::string& path) {
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(DenoiseCommand, LowersTheErrorAt16Spp) {
    const std::string why = ett::error_of([] { et::check_denoiser(); });
    if (!why.empty())
        GTEST_SKIP() << why;
    const std::string dir = ett::scratch_dir("denoise_command");
    const std::string scene = write_scene(dir);
    const ett::CliRun ref = ett::run_envtrace(
        render_args(scene, dir + "/ref.exr", {"--spp", "1024", "--seed", "7"}), dir, 240);
    ASSERT_EQ(ref.code(), 0) << ref.err;
    const ett::CliRun run = ett::run_envtrace(
        render_args(scene, dir + "/out.exr",
                    {"--spp", "16", "--seed", "1", "--denoise", "--stats", dir + "/stats.json"}),
        dir);
    ASSERT_EQ(run.code(), 0) << run.err;
    const et::RgbImage reference = et::read_rgb_image(dir + "/ref.exr");
    const double noisy =
        et::compare_images(et::read_rgb_image(dir + "/out.exr"), reference).rel_mse;
    const double denoised =
        et::compare_images(et::read_rgb_image(dir + "/out.denoised.exr"), reference).rel_mse;
    // The reference's own error is 1/64 of the noisy image's; the denoiser's gain is far larger
    // than that margin.
    EXPECT_LT(denoised, 0.5 * noisy)
        << "relative MSE: noisy " << noisy << ", denoised " << denoised;
    EXPECT_TRUE(fs::exists(dir + "/out.png"));
    EXPECT_NE(read_text(dir + "/stats.json").find("\"denoiser\""), std::string::npos);
}

// An interrupted render's outputs are denoised too: SIGINT once the live preview shows that
// rendering runs; the image and its denoised twin hold the same samples.
TEST(DenoiseCommand, InterruptedRenderIsDenoisedToo) {
    const std::string why = ett::error_of([] { et::check_denoiser(); });
    if (!why.empty())
        GTEST_SKIP() << why;
    const std::string dir = ett::scratch_dir("denoise_interrupted");
    const std::string scene = write_scene(dir);
    const std::string out = dir + "/out";
    fs::create_directories(out);
    const ett::CliProcess p =
        ett::start_envtrace(render_args(scene, out + "/r.exr",
                                        {"--spp", "16000000", "--denoise", "--live-preview", "0"}),
                            dir);
    for (int i = 0; i < 12000 && !fs::exists(out + "/r.png"); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ASSERT_TRUE(fs::exists(out + "/r.png")) << "no live preview within 60 s";
    kill(p.pid, SIGINT);
    const ett::CliRun r = ett::finish_envtrace(p, 120);
    ASSERT_TRUE(r.exited() && r.code() == 128 + SIGINT) << r.err;
    const et::RgbImage noisy = et::read_rgb_image(out + "/r.exr");
    const et::RgbImage denoised = et::read_rgb_image(out + "/r.denoised.exr");
    EXPECT_EQ(denoised.width, noisy.width);
    EXPECT_NE(denoised.rgb, noisy.rgb);
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(out))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names,
              (std::vector<std::string>{"r.denoised.exr", "r.envtrace-state", "r.exr", "r.png"}));
}

// Farm tasks rendered with --aovs, merged with --denoise: the denoised twin of the merged image.
TEST(DenoiseCommand, MergedFarmTasksAreDenoised) {
    const std::string why = ett::error_of([] { et::check_denoiser(); });
    if (!why.empty())
        GTEST_SKIP() << why;
    const std::string dir = ett::scratch_dir("denoise_merge");
    const std::string scene = write_scene(dir);
    const ett::CliRun task = ett::run_envtrace(
        render_args(scene, dir + "/t.exr", {"--sample-range", "0:4", "--denoise"}), dir);
    EXPECT_EQ(task.code(), 1);
    EXPECT_NE(task.err.find("merge --denoise"), std::string::npos) << task.err;
    for (const std::string range : {"0:4", "4:8"}) {
        const ett::CliRun r = ett::run_envtrace(
            render_args(scene, dir + "/t.exr", {"--sample-range", range, "--aovs"}), dir);
        ASSERT_EQ(r.code(), 0) << r.err;
    }
    const ett::CliRun merge = ett::run_envtrace({"merge", dir + "/t.samples-0-4.envtrace-state",
                                                 dir + "/t.samples-4-8.envtrace-state", "-o",
                                                 dir + "/m.exr", "--denoise"},
                                                dir);
    ASSERT_EQ(merge.code(), 0) << merge.err;
    const et::RgbImage noisy = et::read_rgb_image(dir + "/m.exr");
    const et::RgbImage denoised = et::read_rgb_image(dir + "/m.denoised.exr");
    EXPECT_EQ(denoised.height, noisy.height);
    EXPECT_NE(denoised.rgb, noisy.rgb);
}

// Simulated absence: ENVTRACE_OIDN names a file that is not there.
TEST(DenoiseCommand, WithoutTheDenoiserFailsBeforeRendering) {
    const std::string dir = ett::scratch_dir("denoise_missing");
    const std::string scene = write_scene(dir);
    ::setenv("ENVTRACE_OIDN", (dir + "/no-such-libOpenImageDenoise.so.2").c_str(), 1);
    const ett::CliRun run = ett::run_envtrace(
        render_args(scene, dir + "/out.exr", {"--spp", "1024", "--denoise"}), dir);
    ::unsetenv("ENVTRACE_OIDN");
    EXPECT_EQ(run.code(), 1) << run.err;
    EXPECT_NE(run.err.find("ENVTRACE_OIDN"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("tools/setup"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("pyoidn"), std::string::npos) << run.err;
    EXPECT_FALSE(fs::exists(dir + "/out.exr"));
    EXPECT_FALSE(fs::exists(dir + "/out.png"));
}

// Every pass rewrites the preview and the image; the last writes are the final outputs, whole,
// with no temporary left beside them.
TEST(LivePreviewCommand, LeavesWholeImagesAndNoTemporaries) {
    const std::string dir = ett::scratch_dir("live_preview_command");
    const std::string scene = write_scene(dir);
    const std::string out = dir + "/out";
    fs::create_directories(out);
    const ett::CliRun run = ett::run_envtrace(
        render_args(scene, out + "/r.exr", {"--spp", "6", "--live-preview", "0", "--live-image"}),
        dir);
    ASSERT_EQ(run.code(), 0) << run.err;
    EXPECT_EQ(et::read_rgb_image(out + "/r.png").width, 48);
    EXPECT_EQ(et::read_rgb_image(out + "/r.exr").height, 36);
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(out))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"r.exr", "r.png"}));
}

TEST(LivePreviewCommand, MisusesAreRefused) {
    const std::string dir = ett::scratch_dir("live_preview_misuse");
    const std::string scene = write_scene(dir);
    const ett::CliRun alone =
        ett::run_envtrace(render_args(scene, dir + "/a.exr", {"--live-image"}), dir);
    EXPECT_EQ(alone.code(), 1);
    EXPECT_NE(alone.err.find("--live-preview SECONDS"), std::string::npos) << alone.err;
    const ett::CliRun farm = ett::run_envtrace(
        render_args(scene, dir + "/b.exr", {"--sample-range", "0:4", "--live-preview", "1"}), dir);
    EXPECT_EQ(farm.code(), 1);
    EXPECT_NE(farm.err.find("--sample-range"), std::string::npos) << farm.err;
}

} // namespace
