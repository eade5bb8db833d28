// `envtrace render` under interruption and resumption, from the command line: SIGINT / SIGTERM
// keep the samples so far (exit 130 / 143, metadata saying so), and they and the time limit
// abandon a pass in flight; a render killed with SIGKILL and
// resumed from its state equals the uninterrupted render bit for bit; a state of another render
// is refused; a time limit shorter than a pass still renders a sample; no output replaces an
// input of the run; an interrupted render leaves a state without --checkpoint; the film size and
// the preview's exposure from the command line; the default output folder.
#include "cli_run.h"
#include "deep_scene.h"
#include "image/image_io.h"
#include "render/render_state.h"
#include "util/output_batch.h"
#include "test_data.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

void write_file(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}
std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// DIR/maps/NAME (a small sky, brighter towards +Y) and DIR/s.json rendering a sphere under it.
std::string write_scene(const std::string& dir, const std::string& map_name = "sky.exr") {
    fs::create_directories(dir + "/maps");
    std::vector<float> sky(32 * 16 * 3);
    for (size_t i = 0; i < sky.size(); ++i)
        sky[i] = 0.2f + 2.0f * float(16 - (i / 3) / 32) / 16.0f;
    et::write_image(dir + "/maps/" + map_name, 32, 16, 3, sky);
    write_file(dir + "/s.json", R"({
  "camera": {"eye": [0, 1, 4], "target": [0, 0.3, 0], "fov": 40},
  "film": {"width": 16, "height": 12},
  "environment": {"map": ")" + dir + "/maps/" +
                                    map_name +
                                    R"("},
  "materials": {"m": {"type": "plastic", "albedo": 0.6, "roughness": 0.3}},
  "shapes": [{"type": "sphere", "radius": 0.6, "center": [0, 0.6, 0], "material": "m"},
             {"type": "quad", "center": [0, 0, 0], "size": 6, "material": "m"}],
  "render": {"max_depth": 4}
}
)");
    return dir + "/s.json";
}

std::vector<std::string> args(const std::string& scene, const std::string& out,
                              std::vector<std::string> more) {
    std::vector<std::string> a = {"render", scene, "--backend", "cpu", "--threads", "2", "-o", out};
    a.insert(a.end(), more.begin(), more.end());
    return a;
}

// The image's envtrace:KEY metadata, or "" when absent.
std::string metadata(const std::string& exr, const std::string& key) {
    auto in = OIIO::ImageInput::open(exr);
    if (!in)
        return "";
    return in->spec().get_string_attribute("envtrace:" + key);
}

// Waits (up to 60 s) until `path` exists.
bool wait_for(const std::string& path) {
    for (int i = 0; i < 12000; ++i) {
        if (fs::exists(path))
            return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
}

// Names in dir that look like temporaries (".NAME.tmpPID.EXT").
std::vector<std::string> temporaries_in(const std::string& dir) {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) {
        const std::string n = e.path().filename().string();
        if (n[0] == '.' && n.find(".tmp") != std::string::npos)
            out.push_back(n);
    }
    return out;
}

// Two images' pixels bit for bit (float == would call NaN unequal and -0 equal).
void expect_same_image(const std::string& a, const std::string& b) {
    const et::RgbImage x = et::read_rgb_image(a), y = et::read_rgb_image(b);
    ASSERT_EQ(x.rgb.size(), y.rgb.size()) << a << " and " << b;
    EXPECT_EQ(std::memcmp(x.rgb.data(), y.rgb.data(), x.rgb.size() * sizeof(float)), 0)
        << a << " and " << b << " differ";
}

void expect_exit(const ett::CliRun& r, int code) {
    ASSERT_FALSE(r.timed_out) << "hung";
    ASSERT_TRUE(r.exited()) << "killed by signal " << WTERMSIG(r.status) << "; stderr: " << r.err;
    ASSERT_EQ(r.code(), code) << r.err;
}

// SIGINT and SIGTERM while rendering: the image of the samples so far, the status 128 + signal.
TEST(RenderCommand, SignalsKeepTheSamplesSoFar) {
    for (const int sig : {SIGINT, SIGTERM}) {
        const std::string dir = ett::scratch_dir("render_signal_" + std::to_string(sig));
        const std::string scene = write_scene(dir);
        // --checkpoint 0 writes the state after every pass: its appearance says rendering runs.
        const ett::CliProcess p = ett::start_envtrace(
            args(scene, dir + "/out.exr", {"--spp", "16000000", "--checkpoint", "0"}), dir);
        ASSERT_TRUE(wait_for(dir + "/out.envtrace-state"));
        kill(p.pid, sig);
        const ett::CliRun r = ett::finish_envtrace(p, 120);
        expect_exit(r, 128 + sig);
        EXPECT_NE(r.err.find(sig == SIGINT ? "SIGINT" : "SIGTERM"), std::string::npos) << r.err;
        const int spp = std::stoi("0" + metadata(dir + "/out.exr", "spp"));
        EXPECT_GE(spp, 1);
        EXPECT_LT(spp, 16000000);
        EXPECT_EQ(metadata(dir + "/out.exr", "interrupted"), sig == SIGINT ? "SIGINT" : "SIGTERM");
        EXPECT_TRUE(fs::exists(dir + "/out.png"));
        // The state written at the end holds the same samples as the image.
        EXPECT_EQ(et::read_render_state(dir + "/out.envtrace-state").spp, spp);
        EXPECT_TRUE(temporaries_in(dir).empty()) << temporaries_in(dir)[0];
    }
}

// A render killed outright (SIGKILL, nothing caught) and resumed from its last checkpoint equals
// the render that was never interrupted, bit for bit; the killed run's temporaries are removed.
TEST(RenderCommand, KilledRenderResumesBitIdentical) {
    const std::string dir = ett::scratch_dir("render_resume");
    const std::string scene = write_scene(dir);
    const std::string state = dir + "/run.envtrace-state";
    const ett::CliProcess p = ett::start_envtrace(
        args(scene, dir + "/killed.exr",
             {"--spp", "16000000", "--checkpoint", "0", "--state", state, "--seed", "7"}),
        dir);
    ASSERT_TRUE(wait_for(state));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    kill(p.pid, SIGKILL);
    const ett::CliRun killed = ett::finish_envtrace(p, 60);
    ASSERT_TRUE(WIFSIGNALED(killed.status) && WTERMSIG(killed.status) == SIGKILL);
    EXPECT_FALSE(fs::exists(dir + "/killed.exr"));
    const int reached = et::read_render_state(state).spp;
    ASSERT_GE(reached, 1);
    // A temporary as a kill in the middle of a checkpoint leaves it.
    write_file(et::temporary_path(state, 999999), "half a state");

    const int total = reached + 9;
    expect_exit(ett::run_envtrace(args(scene, dir + "/resumed.exr",
                                       {"--spp", std::to_string(total), "--resume", "--state",
                                        state, "--seed", "7"}),
                                  dir, 120),
                0);
    EXPECT_EQ(metadata(dir + "/resumed.exr", "resumed_from_spp"), std::to_string(reached));
    EXPECT_EQ(metadata(dir + "/resumed.exr", "spp"), std::to_string(total));
    EXPECT_EQ(et::read_render_state(state).spp, total);
    EXPECT_TRUE(temporaries_in(dir).empty()) << temporaries_in(dir)[0];

    expect_exit(ett::run_envtrace(args(scene, dir + "/whole.exr",
                                       {"--spp", std::to_string(total), "--seed", "7"}),
                                  dir, 120),
                0);
    expect_same_image(dir + "/resumed.exr", dir + "/whole.exr");
    const et::RgbImage a = et::read_rgb_image(dir + "/resumed.exr");
    double sum = 0;
    for (float v : a.rgb)
        sum += v;
    EXPECT_GT(sum, 0.0);
}

// A state that does not continue this render (another seed, another scene, more samples than
// asked for, a damaged file) is refused by name, and left as it was.
TEST(RenderCommand, ForeignStatesAreRefused) {
    const std::string dir = ett::scratch_dir("render_foreign_state");
    const std::string scene = write_scene(dir);
    const std::string state = dir + "/out.envtrace-state";
    expect_exit(ett::run_envtrace(args(scene, dir + "/out.exr",
                                       {"--spp", "4", "--checkpoint", "1000", "--seed", "1"}),
                                  dir),
                0);
    const std::string bytes = read_file(state);
    ASSERT_FALSE(bytes.empty());
    auto refused = [&](std::vector<std::string> more, const std::string& words) {
        more.push_back("--resume");
        const ett::CliRun r = ett::run_envtrace(args(scene, dir + "/out.exr", more), dir);
        expect_exit(r, 1);
        EXPECT_NE(r.err.find("envtrace: error: "), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(state), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
        EXPECT_TRUE(read_file(state) == bytes) << "the state was changed";
    };
    refused({"--spp", "8", "--seed", "2"}, "of another render");
    refused({"--spp", "8", "--seed", "1", "--max-depth", "2"}, "of another render");
    refused({"--spp", "2", "--seed", "1"}, "more than");
    // The right state resumes.
    expect_exit(ett::run_envtrace(
                    args(scene, dir + "/out.exr", {"--spp", "8", "--seed", "1", "--resume"}), dir),
                0);
    // The scene's spp is no cap on a render to a noise target or a time limit without --spp
    // (the render itself ignores it then): its state resumes; a plain render refuses it.
    std::string text = read_file(scene);
    const size_t at = text.find("\"max_depth\": 4");
    ASSERT_NE(at, std::string::npos);
    text.insert(at, "\"spp\": 2, ");
    std::ofstream(scene) << text;
    const std::string saved = read_file(state);
    const ett::CliRun capped =
        ett::run_envtrace(args(scene, dir + "/out.exr", {"--seed", "1", "--resume"}), dir);
    expect_exit(capped, 1);
    EXPECT_NE(capped.err.find("more than the 2 of the scene's render.spp"), std::string::npos)
        << capped.err;
    expect_exit(ett::run_envtrace(args(scene, dir + "/out.exr",
                                       {"--seed", "1", "--resume", "--noise-target", "0.9"}),
                                  dir),
                0);
    std::ofstream(state, std::ios::binary) << saved;
    expect_exit(ett::run_envtrace(args(scene, dir + "/out.exr",
                                       {"--seed", "1", "--resume", "--time-limit", "0.01"}),
                                  dir),
                0);
    const std::string missing = dir + "/none.envtrace-state";
    const ett::CliRun r = ett::run_envtrace(
        args(scene, dir + "/out.exr", {"--spp", "8", "--resume", "--state", missing}), dir);
    expect_exit(r, 1);
    EXPECT_NE(r.err.find(missing), std::string::npos) << r.err;
}

// A time limit shorter than one pass renders one sample (never a black image with exit 0).
TEST(RenderCommand, TinyTimeLimitStillRendersASample) {
    const std::string dir = ett::scratch_dir("render_time_limit");
    const std::string scene = write_scene(dir);
    expect_exit(ett::run_envtrace(args(scene, dir + "/out.exr", {"--time-limit", "1e-9"}), dir), 0);
    EXPECT_EQ(metadata(dir + "/out.exr", "spp"), "1");
    const et::RgbImage img = et::read_rgb_image(dir + "/out.exr");
    double sum = 0;
    for (float v : img.rgb)
        sum += v;
    EXPECT_GT(sum, 0.0);
}

// A signal inside a pass that takes seconds (1000 mirror bounces a path) stops at the pass's next
// bounce: the image holds the passes before it (the pass in flight would have made 2 spp).
TEST(RenderCommand, SignalAbandonsThePassInFlight) {
    const std::string dir = ett::scratch_dir("render_signal_mid_pass");
    const std::string scene = ett::write_deep_scene(dir, 64);
    const ett::CliProcess p = ett::start_envtrace(
        args(scene, dir + "/out.exr",
             {"--spp", "1000", "--checkpoint", "0", "--stats", dir + "/stats.json"}),
        dir);
    ASSERT_TRUE(wait_for(dir + "/out.envtrace-state")); // the first pass is whole
    kill(p.pid, SIGINT);
    const ett::CliRun r = ett::finish_envtrace(p, 120);
    expect_exit(r, 130);
    EXPECT_EQ(metadata(dir + "/out.exr", "spp"), "1") << r.err;
    EXPECT_EQ(metadata(dir + "/out.exr", "interrupted"), "SIGINT");
    EXPECT_EQ(et::read_render_state(dir + "/out.envtrace-state").spp, 1);
    EXPECT_NE(read_file(dir + "/stats.json").find("\"stopped_inside_a_pass\": true"),
              std::string::npos);
    EXPECT_TRUE(temporaries_in(dir).empty()) << temporaries_in(dir)[0];
}

// --time-limit stops inside a pass too, dropping it: with a limit of 2.5 passes (measured
// first; the margin is for a loaded machine) the deadline falls inside one, which is dropped;
// the image is the whole passes before it, the same pixels as a render of that many samples.
TEST(RenderCommand, TimeLimitAbandonsThePassInFlight) {
    const std::string dir = ett::scratch_dir("render_time_limit_mid_pass");
    const std::string scene = ett::write_deep_scene(dir, 64);
    const std::string stats = dir + "/stats.json";
    expect_exit(ett::run_envtrace(args(scene, dir + "/ref.exr", {"--spp", "1", "--stats", stats}),
                                  dir, 120),
                0);
    const std::string text = read_file(stats);
    const size_t at = text.find("\"render_seconds\": ");
    ASSERT_NE(at, std::string::npos) << text;
    const double pass = std::stod(text.substr(at + 18));
    const ett::CliRun r =
        ett::run_envtrace(args(scene, dir + "/out.exr",
                               {"--time-limit", std::to_string(2.5 * pass), "--stats", stats}),
                          dir, 120);
    expect_exit(r, 0);
    const bool inside = r.err.find("reached inside a pass") != std::string::npos;
    EXPECT_EQ(read_file(stats).find("\"stopped_inside_a_pass\": true") != std::string::npos,
              inside);
    const std::string spp = metadata(dir + "/out.exr", "spp");
    ASSERT_GE(std::stoi("0" + spp), 1);
    if (!inside) { // a machine 2.5x slower than when measured: the first pass (always finished)
        EXPECT_EQ(spp, "1") << r.err; // outlasted the limit, and the render stopped after it
    }
    if (spp != "1")
        expect_exit(ett::run_envtrace(args(scene, dir + "/ref.exr", {"--spp", spp}), dir, 120), 0);
    expect_same_image(dir + "/ref.exr", dir + "/out.exr");
}

// A resumed render with a time limit shorter than a pass still adds a round: the limit never
// abandons a run's first round (a loop of time-limited resumes got no further, each dropping it).
TEST(RenderCommand, ResumeUnderATinyTimeLimitStillAddsASample) {
    const std::string dir = ett::scratch_dir("render_resume_time_limit");
    const std::string scene = write_scene(dir);
    const std::string state = dir + "/s.envtrace-state";
    expect_exit(ett::run_envtrace(args(scene, dir + "/a.exr",
                                       {"--spp", "1", "--checkpoint", "0", "--state", state}),
                                  dir),
                0);
    ASSERT_EQ(et::read_render_state(state).spp, 1);
    for (int expected : {2, 3}) {
        expect_exit(ett::run_envtrace(args(scene, dir + "/a.exr",
                                           {"--time-limit", "1e-9", "--resume", "--state", state}),
                                      dir),
                    0);
        EXPECT_EQ(et::read_render_state(state).spp, expected);
    }
}

// The roulette's depth: the scene's unless --rr-depth gives one (0 included), in the image's
// metadata and the stats; a negative one is refused.
TEST(RenderCommand, RouletteDepthFromSceneOrCommandLine) {
    const std::string dir = ett::scratch_dir("render_rr_depth");
    const std::string scene = write_scene(dir);
    const std::string out = dir + "/out.exr";
    expect_exit(ett::run_envtrace(args(scene, out, {"--spp", "1"}), dir), 0);
    EXPECT_EQ(metadata(out, "rr_depth"), "5");
    expect_exit(
        ett::run_envtrace(
            args(scene, out, {"--spp", "1", "--rr-depth", "0", "--stats", dir + "/stats.json"}),
            dir),
        0);
    EXPECT_EQ(metadata(out, "rr_depth"), "0");
    EXPECT_NE(read_file(dir + "/stats.json").find("\"rr_depth\": 0"), std::string::npos);
    expect_exit(ett::run_envtrace(args(scene, out, {"--spp", "1", "--rr-depth", "-1"}), dir), 1);
}

// A film the machine cannot hold is refused up front, naming its size, with nothing written
// (it grew to 17 GB over 40 s before "out of memory", or met the OOM killer). Skipped on a
// machine that could hold a 16384 x 16384 film (about 56 GB).
TEST(RenderCommand, FilmBeyondTheMachinesMemoryIsRefusedUpFront) {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    if (pages > 0 && page > 0 && double(pages) * double(page) > 50e9)
        GTEST_SKIP() << "this machine could hold the film";
    const std::string dir = ett::scratch_dir("render_huge_film");
    write_file(dir + "/s.json", R"({"environment": {"sky": {"resolution": [64, 32]}},
  "film": {"width": 16384, "height": 16384}, "shapes": [{"type": "sphere"}]})");
    const ett::CliRun r = ett::run_envtrace(args(dir + "/s.json", dir + "/out.exr", {}), dir);
    expect_exit(r, 1);
    EXPECT_NE(r.err.find("film 16384 x 16384 (film.width, film.height) needs about"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(dir + "/out.exr"));
}

// No output (the image, its PNG or EXR twin, --stats, the state) may be an input of the run:
// refused before rendering, the input unchanged, nothing written.
TEST(RenderCommand, OutputsNeverReplaceInputs) {
    const std::string dir = ett::scratch_dir("render_inputs");
    for (const std::string map_name : {"s.exr", "s.png"}) {
        const std::string scene = write_scene(dir, map_name);
        const std::string map = dir + "/maps/" + map_name, map_bytes = read_file(map);
        const std::string scene_bytes = read_file(scene);
        auto refused = [&](const std::string& out, std::vector<std::string> more) {
            more.insert(more.end(), {"--spp", "1"});
            const ett::CliRun r = ett::run_envtrace(args(scene, out, more), dir);
            expect_exit(r, 1);
            EXPECT_NE(r.err.find("an input of this run"), std::string::npos) << r.err;
            EXPECT_TRUE(read_file(map) == map_bytes) << "the map was changed";
            EXPECT_TRUE(read_file(scene) == scene_bytes) << "the scene was changed";
            EXPECT_TRUE(temporaries_in(dir).empty());
            EXPECT_TRUE(temporaries_in(dir + "/maps").empty());
        };
        refused(map, {}); // -o the map itself
        // Outputs whose EXR or PNG twin is the map.
        const std::vector<std::string> twins =
            map_name == "s.exr" ? std::vector<std::string>{"s.png", "s.jpg"}
                                : std::vector<std::string>{"s.exr", "./s.pfm", "s.hdr"};
        for (const auto& t : twins)
            refused(dir + "/maps/" + t, {});
        refused(dir + "/out.exr", {"--stats", scene});                    // --stats over the scene
        refused(dir + "/out.exr", {"--checkpoint", "1", "--state", map}); // the state
        EXPECT_FALSE(fs::exists(dir + "/out.exr"));
    }
}

// Waits (up to 60 s) until `path` holds `text`.
bool wait_for_text(const std::string& path, const std::string& text) {
    for (int i = 0; i < 12000; ++i) {
        if (read_file(path).find(text) != std::string::npos)
            return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
}

// SIGINT on a render without --checkpoint still leaves a state (it said "no such file" to
// --resume before), named on stderr, and the resumed render equals the uninterrupted one.
TEST(RenderCommand, InterruptedRenderLeavesAStateThatResumesBitIdentical) {
    const std::string dir = ett::scratch_dir("render_interrupt_state");
    const std::string scene = write_scene(dir);
    const std::string state = dir + "/out.envtrace-state";
    // The noise check's line on stderr says the render loop runs (the handler is in place); a
    // target never met keeps it running.
    const ett::CliProcess p =
        ett::start_envtrace(args(scene, dir + "/out.exr",
                                 {"--spp", "16000000", "--noise-target", "1e-6", "--seed", "7"}),
                            dir);
    ASSERT_TRUE(wait_for_text(p.err_file, "noise check at"));
    EXPECT_FALSE(fs::exists(state));
    kill(p.pid, SIGINT);
    const ett::CliRun r = ett::finish_envtrace(p, 120);
    expect_exit(r, 128 + SIGINT);
    EXPECT_NE(r.err.find("the state " + state), std::string::npos) << r.err;
    const int reached = std::stoi("0" + metadata(dir + "/out.exr", "spp"));
    ASSERT_GE(reached, 1);
    ASSERT_TRUE(fs::exists(state));
    EXPECT_EQ(et::read_render_state(state).spp, reached);
    EXPECT_TRUE(temporaries_in(dir).empty()) << temporaries_in(dir)[0];

    const int total = reached + 5;
    expect_exit(ett::run_envtrace(args(scene, dir + "/out.exr",
                                       {"--spp", std::to_string(total), "--resume", "--seed", "7"}),
                                  dir, 120),
                0);
    EXPECT_EQ(metadata(dir + "/out.exr", "resumed_from_spp"), std::to_string(reached));
    expect_exit(ett::run_envtrace(args(scene, dir + "/whole.exr",
                                       {"--spp", std::to_string(total), "--seed", "7"}),
                                  dir, 120),
                0);
    expect_same_image(dir + "/out.exr", dir + "/whole.exr");
    // A render that ends on its own keeps no state it was not asked for.
    expect_exit(ett::run_envtrace(args(scene, dir + "/plain.exr", {"--spp", "2"}), dir), 0);
    EXPECT_FALSE(fs::exists(dir + "/plain.envtrace-state"));
}

// --width and --height replace the scene's film size (16 x 12): the image, the stats and the
// state say the same size.
TEST(RenderCommand, FilmSizeFromTheCommandLine) {
    const std::string dir = ett::scratch_dir("render_film_size");
    const std::string scene = write_scene(dir);
    expect_exit(
        ett::run_envtrace(
            args(scene, dir + "/out.exr", {"--spp", "1", "--width", "20", "--height", "7"}), dir),
        0);
    const et::RgbImage img = et::read_rgb_image(dir + "/out.exr");
    EXPECT_EQ(img.width, 20);
    EXPECT_EQ(img.height, 7);
    const et::RgbImage preview = et::read_rgb_image(dir + "/out.png");
    EXPECT_EQ(preview.width, 20);
    EXPECT_EQ(preview.height, 7);
    // Only --width: the scene's height stays.
    expect_exit(ett::run_envtrace(args(scene, dir + "/w.exr", {"--spp", "1", "--width", "9"}), dir),
                0);
    const et::RgbImage w = et::read_rgb_image(dir + "/w.exr");
    EXPECT_EQ(w.width, 9);
    EXPECT_EQ(w.height, 12);
    expect_exit(ett::run_envtrace(args(scene, dir + "/z.exr", {"--width", "0"}), dir), 1);
}

// --exposure EV scales the preview's radiance by 2^EV before its tone curve: +2 EV is brighter,
// -2 EV darker, and the linear image is the same bits whatever the exposure.
TEST(RenderCommand, ExposureChangesOnlyThePreview) {
    const std::string dir = ett::scratch_dir("render_exposure");
    const std::string scene = write_scene(dir);
    auto render_at = [&](const std::string& name, const std::string& ev) {
        expect_exit(
            ett::run_envtrace(
                args(scene, dir + "/" + name + ".exr", {"--spp", "2", "--exposure", ev}), dir),
            0);
        double sum = 0;
        for (float v : et::read_rgb_image(dir + "/" + name + ".png").rgb)
            sum += v;
        return sum;
    };
    const double dark = render_at("dark", "-2"), plain = render_at("plain", "0");
    const double bright = render_at("bright", "2");
    EXPECT_LT(dark, plain);
    EXPECT_LT(plain, bright);
    expect_same_image(dir + "/dark.exr", dir + "/bright.exr");
    expect_exit(ett::run_envtrace(args(scene, dir + "/x.exr", {"--exposure", "nan"}), dir), 1);
}

// Without -o the image goes under renders/ in the current folder (created), named by the
// scene's "output", else after the scene file: never among a checkout's sources.
TEST(RenderCommand, DefaultOutputGoesUnderRenders) {
    const std::string dir = ett::scratch_dir("render_default_output");
    const std::string scene = write_scene(dir);
    const std::vector<std::string> a = {"render",    scene, "--backend", "cpu",
                                        "--threads", "2",   "--spp",     "1"};
    // envtrace runs in the test's folder: this one, for the render.
    const fs::path here = fs::current_path();
    fs::current_path(dir);
    const ett::CliRun r = ett::run_envtrace(a, dir);
    fs::current_path(here);
    expect_exit(r, 0);
    EXPECT_TRUE(fs::exists(dir + "/renders/s.exr"));
    EXPECT_TRUE(fs::exists(dir + "/renders/s.png"));
    EXPECT_FALSE(fs::exists(dir + "/s.exr"));
}

// The stats JSON and the image's metadata come from one description: the facts both carry agree.
TEST(RenderCommand, StatsAndMetadataAgree) {
    const std::string dir = ett::scratch_dir("render_report");
    const std::string scene = write_scene(dir);
    expect_exit(
        ett::run_envtrace(
            args(scene, dir + "/out.exr", {"--spp", "3", "--stats", dir + "/stats.json"}), dir),
        0);
    const std::string json = read_file(dir + "/stats.json");
    for (const auto& [key, value] :
         std::vector<std::pair<std::string, std::string>>{{"spp", "3"},
                                                          {"max_depth", "4"},
                                                          {"resumed_from_spp", "0"},
                                                          {"strategy", "\"auto\""},
                                                          {"interrupted", "\"no\""}}) {
        EXPECT_NE(json.find("\"" + key + "\": " + value), std::string::npos) << key << json;
        const std::string unquoted = value[0] == '"' ? value.substr(1, value.size() - 2) : value;
        EXPECT_EQ(metadata(dir + "/out.exr", key), unquoted) << key;
    }
    EXPECT_NE(json.find("\"summary\": \"learning: "), std::string::npos) << json;
    EXPECT_EQ(metadata(dir + "/out.exr", "noise_target"), "none");
    EXPECT_EQ(metadata(dir + "/out.exr", "light_share"), "");
    EXPECT_EQ(json.find("noise_target"), std::string::npos);
}

} // namespace
