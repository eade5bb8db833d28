// Options and inputs at their edges, through the command line (host/cli): values a range check
// must refuse (NaN, zero split counts, empty names), options that would be silently dropped,
// documented limits written in decimal, a light set `lights` wrote read back by `render`, files
// that are not meshes, output names near the file system's limit, and a reader of stdout that
// goes away.
#include "cli_run.h"
#include "image/image_io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

void write_file(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}

// DIR/sky.pfm (a small map, brighter towards +Y, one bright texel) and DIR/s.json, a sphere on
// a quad under it; `env_extra` is added to the environment object.
std::string write_scene(const std::string& dir, const std::string& env_extra = "") {
    std::vector<float> sky(16 * 8 * 3);
    for (size_t i = 0; i < sky.size(); ++i)
        sky[i] = 0.2f + float(8 - (i / 3) / 16) / 8.0f;
    sky[3 * (2 * 16 + 5)] = 400.0f;
    et::write_image(dir + "/sky.pfm", 16, 8, 3, sky);
    write_file(dir + "/s.json", R"({
  "camera": {"eye": [0, 1, 4], "target": [0, 0.3, 0], "fov": 40},
  "film": {"width": 8, "height": 6},
  "environment": {"map": ")" + dir + R"(/sky.pfm")" +
                                    env_extra + R"(},
  "shapes": [{"type": "sphere", "radius": 0.6, "center": [0, 0.6, 0]},
             {"type": "quad", "center": [0, 0, 0], "size": 6}],
  "render": {"spp": 2, "max_depth": 2}
}
)");
    return dir + "/s.json";
}

std::vector<std::string> render(const std::string& scene, const std::string& out,
                                std::vector<std::string> more = {}) {
    std::vector<std::string> a = {"render", scene, "--backend", "cpu", "--threads", "1", "-o", out};
    a.insert(a.end(), more.begin(), more.end());
    return a;
}

void expect_error(const ett::CliRun& r, const std::string& must_say) {
    ASSERT_FALSE(r.timed_out) << "hung";
    ASSERT_TRUE(r.exited()) << "signal " << WTERMSIG(r.status) << ": " << r.err;
    EXPECT_NE(r.code(), 0) << r.err;
    EXPECT_NE(r.err.find(must_say), std::string::npos) << r.err;
}

void expect_ok(const ett::CliRun& r) {
    ASSERT_FALSE(r.timed_out) << "hung";
    ASSERT_TRUE(r.exited()) << "signal " << WTERMSIG(r.status) << ": " << r.err;
    EXPECT_EQ(r.code(), 0) << r.err;
}

TEST(CliOptions, NotANumberIsRefusedLikeAnyValueOutOfRange) {
    const std::string dir = ett::scratch_dir("cli-opt-nan");
    const std::string scene = write_scene(dir), out = dir + "/o.exr";
    for (const char* opt : {"--time-limit", "--noise-target", "--checkpoint"})
        for (const char* v : {"nan", "-nan", "NaN"}) {
            SCOPED_TRACE(std::string(opt) + " " + v);
            expect_error(ett::run_envtrace(render(scene, out, {opt, v}), dir), "not a finite");
            EXPECT_FALSE(fs::exists(out));
        }
    expect_error(ett::run_envtrace({"bench", scene, "--target-seconds", "nan", "--runs", "1"}, dir),
                 "not a finite");
    expect_error(ett::run_envtrace(
                     {"lights", dir + "/sky.pfm", "--blur", "nan", "-o", dir + "/l.json"}, dir),
                 "not a finite");
    // Finite values inside the range still pass.
    expect_ok(ett::run_envtrace(render(scene, out, {"--time-limit", "0.01"}), dir));
}

TEST(CliOptions, EveryGivenSplitCountIsChecked) {
    const std::string dir = ett::scratch_dir("cli-opt-split");
    const std::string scene = write_scene(dir), out = dir + "/o.exr";
    for (const char* opt : {"--light-samples", "--bsdf-samples"})
        for (const char* v : {"0", "-2", "-64", "3", "128"}) {
            SCOPED_TRACE(std::string(opt) + " " + v);
            expect_error(ett::run_envtrace(render(scene, out, {opt, v}), dir),
                         "must be a power of two from 1 to 64");
        }
    expect_ok(
        ett::run_envtrace(render(scene, out, {"--strategy", "mis", "--light-samples", "2"}), dir));
    // The default strategy takes one sample of each: the error says what splits.
    expect_error(ett::run_envtrace(render(scene, out, {"--light-samples", "2"}), dir),
                 "name the strategy mis to split");
}

TEST(CliOptions, OptionsThatWouldBeDroppedAreRefusedOrWarned) {
    const std::string dir = ett::scratch_dir("cli-opt-dropped");
    const std::string scene = write_scene(dir), out = dir + "/o.exr";
    expect_error(ett::run_envtrace(render(scene, "", {}), dir), "--output is empty");
    for (const std::string& folder : {dir + "/", dir + "/.", dir})
        expect_error(ett::run_envtrace(render(scene, folder, {}), dir), "is a folder");
    expect_error(ett::run_envtrace(render(scene, out, {"--stats", ""}), dir), "--stats is empty");
    const std::string lights = dir + "/l.json";
    expect_ok(ett::run_envtrace({"lights", dir + "/sky.pfm", "-n", "4", "-o", lights}, dir));
    expect_error(
        ett::run_envtrace(render(scene, out, {"--lights", lights, "--strategy", "mis"}), dir),
        "excludes --strategy mis");
    expect_ok(ett::run_envtrace(render(scene, out, {"--lights", lights}), dir));
    ett::CliRun r = ett::run_envtrace(render(scene, out, {"--sis-samples", "4"}), dir);
    expect_ok(r);
    EXPECT_NE(r.err.find("--sis-samples applies to --strategy sis only"), std::string::npos)
        << r.err;
    r = ett::run_envtrace(render(scene, out, {"--paths", "64"}), dir);
    expect_ok(r);
    EXPECT_NE(r.err.find("--paths"), std::string::npos) << r.err;
    std::vector<std::string> with_device = render(scene, out);
    with_device.insert(with_device.begin(), {"--device", "3"});
    r = ett::run_envtrace(with_device, dir);
    expect_ok(r);
    EXPECT_NE(r.err.find("--device picks an OpenCL device"), std::string::npos) << r.err;
}

TEST(CliOptions, SppCapsATimeLimitedRender) {
    const std::string dir = ett::scratch_dir("cli-opt-cap");
    const std::string scene = write_scene(dir), out = dir + "/o.exr", stats = dir + "/s.json.out";
    expect_ok(ett::run_envtrace(
        render(scene, out, {"--time-limit", "30", "--spp", "3", "--stats", stats}), dir, 120));
    std::ifstream in(stats);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    EXPECT_NE(text.find("\"spp\": 3,"), std::string::npos) << text;
}

TEST(CliOptions, DocumentedLimitsWrittenInDecimalAreInside) {
    const std::string dir = ett::scratch_dir("cli-opt-limits");
    const std::string out = dir + "/o.exr";
    // 0.05 and 1e12 as a user writes them: the limits are the floats nearest to them.
    expect_ok(ett::run_envtrace(render(write_scene(dir, R"(, "distribution_exponent": 0.05)"), out),
                                dir));
    write_file(dir + "/sky.json", R"({"environment": {"sky": {"resolution": [16, 8],
        "sun_radiance": 1e12, "sky_radiance": 1e12}}, "film": {"width": 4, "height": 2},
        "render": {"spp": 1, "max_depth": 1}})");
    expect_ok(ett::run_envtrace(render(dir + "/sky.json", out), dir));
    // Beyond them, the message shows digits that differ from the limit's.
    expect_error(ett::run_envtrace(
                     render(write_scene(dir, R"(, "distribution_exponent": 0.0499)"), out), dir),
                 "expected a number in [0.05, 1], got 0.0499");
}

// A light set whose one light's cell is the whole sphere (solid angle 4 pi, summed in double):
// what `lights` writes, `render --lights` reads.
TEST(CliOptions, LightSetsRoundTripThroughTheCommandLine) {
    const std::string dir = ett::scratch_dir("cli-opt-lights");
    const std::string scene = write_scene(dir), lights = dir + "/one.json";
    for (const char* n : {"1", "3"}) {
        SCOPED_TRACE(n);
        expect_ok(ett::run_envtrace(
            {"lights", dir + "/sky.pfm", "-n", n, "--power", "voronoi", "-o", lights}, dir));
        expect_ok(ett::run_envtrace(render(scene, dir + "/o.exr", {"--lights", lights}), dir));
    }
}

// Options and names that would be silently ignored or mislabelled are refused, saying why.
TEST(CliOptions, MisnamedOutputsAndIdleOptionsAreRefused) {
    const std::string dir = ett::scratch_dir("cli-opt-misnamed");
    const std::string scene = write_scene(dir);
    // A light set is JSON, whatever -o is called.
    expect_error(
        ett::run_envtrace({"lights", dir + "/sky.pfm", "-n", "4", "-o", dir + "/l.exr"}, dir),
        "l.exr: the light set is written as JSON");
    EXPECT_FALSE(fs::exists(dir + "/l.exr"));
    // --state without anything that keeps a state.
    expect_error(
        ett::run_envtrace(render(scene, dir + "/o.exr", {"--state", dir + "/x.state"}), dir),
        "this render keeps none");
    EXPECT_FALSE(fs::exists(dir + "/o.exr"));
    // The message for a bad output names the preview formats it takes too.
    expect_error(ett::run_envtrace(render(scene, dir + "/o.txt"), dir), ".png / .jpg");
    // A black map makes no lights by either method.
    et::write_image(dir + "/black.pfm", 8, 4, 3, std::vector<float>(8 * 4 * 3, 0.0f));
    for (const char* method : {"ours", "sis"})
        expect_error(ett::run_envtrace({"lights", dir + "/black.pfm", "-n", "4", "--method", method,
                                        "-o", dir + "/b.json"},
                                       dir),
                     "emits no light");
    EXPECT_FALSE(fs::exists(dir + "/b.json"));
}

TEST(CliOptions, AFailingPlotLeavesNoLightSet) {
    const std::string dir = ett::scratch_dir("cli-opt-plot");
    write_scene(dir);
    const std::string lights = dir + "/l.json";
    expect_error(
        ett::run_envtrace(
            {"lights", dir + "/sky.pfm", "-n", "4", "-o", lights, "--plot", dir + "/p.txt"}, dir),
        "p.txt: unsupported output format");
    EXPECT_FALSE(fs::exists(lights));
    expect_error(ett::run_envtrace({"lights", dir + "/sky.pfm", "-n", "4", "-o", lights, "--plot",
                                    dir + "/gone/p.pfm"},
                                   dir),
                 "does not exist");
    EXPECT_FALSE(fs::exists(lights));
}

TEST(CliOptions, SisStrataBeyondTheTexelsNameTheMapAndTheCounts) {
    const std::string dir = ett::scratch_dir("cli-opt-sis");
    write_scene(dir);
    expect_error(ett::run_envtrace({"lights", dir + "/sky.pfm", "-n", "200", "--method", "sis",
                                    "-o", dir + "/l.json"},
                                   dir),
                 "sky.pfm: SIS asked for 200 strata, but the map has only 128 texels (16x8)");
}

TEST(CliOptions, FilesWithoutFacesAreNotMeshes) {
    const std::string dir = ett::scratch_dir("cli-opt-mesh");
    write_scene(dir);
    const std::vector<std::pair<std::string, std::string>> files = {
        {"text.obj", "this is not an OBJ file\n"},
        {"empty.obj", ""},
        {"points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\nl 1 2\n"},
        {"broken.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"}, // every face degenerate
        {"binary.obj", std::string("\x7f\x45\x4c\x46\x00\x01\x02\xff\xfe", 9)}};
    for (const auto& [name, text] : files) {
        SCOPED_TRACE(name);
        write_file(dir + "/" + name, text);
        write_file(dir + "/m.json", R"({"environment": {"map": ")" + dir +
                                        R"(/sky.pfm"}, "film": {"width": 4, "height": 2},
            "shapes": [{"type": "mesh", "file": ")" +
                                        dir + "/" + name +
                                        R"("}], "render": {"spp": 1, "max_depth": 1}})");
        expect_error(ett::run_envtrace(render(dir + "/m.json", dir + "/o.exr"), dir),
                     name + ": no triangles to render");
        EXPECT_FALSE(fs::exists(dir + "/o.exr"));
    }
}

TEST(CliOptions, OutputNamesNearTheFileSystemLimitAreWritten) {
    const std::string dir = ett::scratch_dir("cli-opt-long");
    const std::string scene = write_scene(dir);
    // 251 bytes: a valid name, whose hidden temporary would not be if named in full.
    const std::string out = dir + "/" + std::string(247, 'a') + ".pfm";
    expect_ok(ett::run_envtrace(render(scene, out), dir));
    EXPECT_TRUE(fs::exists(out));
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

// `envtrace render ... | head -1`: the reader is gone before the render ends; the image is
// still written and the status is the render's.
TEST(CliOptions, AClosedStdoutDoesNotKillARender) {
    const std::string dir = ett::scratch_dir("cli-opt-pipe");
    const std::string scene = write_scene(dir), out = dir + "/o.pfm";
    write_file(dir + "/pipe.sh", "'" + std::string(ENVTRACE_EXE) + "' render '" + scene +
                                     "' --backend cpu --threads 1 --spp 64 -o '" + out +
                                     "' 2>/dev/null | true\necho ${PIPESTATUS[0]}\n");
    FILE* p = ::popen(("bash '" + dir + "/pipe.sh'").c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[32] = {};
    const bool read = std::fgets(buf, sizeof buf, p) != nullptr;
    ::pclose(p);
    ASSERT_TRUE(read);
    EXPECT_EQ(std::string(buf), "0\n");
    EXPECT_TRUE(fs::exists(out));
}

TEST(CliOptions, RadianceHdrKeepsValuesBeyondItsRangeAsItsLargest) {
    if (!et::have_image_library())
        GTEST_SKIP() << "no OpenImageIO: .hdr is not written";
    const std::string dir = ett::scratch_dir("cli-opt-rgbe");
    // RGBE shares one exponent per pixel: the huge pixel alone, an ordinary one beside it.
    et::write_image(dir + "/big.pfm", 2, 1, 3, {3e38f, 3e38f, 3e38f, 1.0f, 2.0f, 0.5f});
    const ett::CliRun r = ett::run_envtrace({"convert", dir + "/big.pfm", dir + "/big.hdr"}, dir);
    expect_ok(r);
    EXPECT_NE(r.err.find("beyond Radiance RGBE's range"), std::string::npos) << r.err;
    const et::RgbImage im = et::read_rgb_image(dir + "/big.hdr");
    ASSERT_EQ(im.rgb.size(), 6u);
    for (int c = 0; c < 3; ++c)
        EXPECT_GT(im.rgb[c], 1e38f) << c; // not wrapped to 0
    EXPECT_NEAR(im.rgb[3], 1.0f, 0.01f);
    EXPECT_NEAR(im.rgb[4], 2.0f, 0.02f);
}

TEST(CliOptions, MemoryLimitsFromTheEnvironmentAreDigitsOnly) {
    const std::string dir = ett::scratch_dir("cli-opt-env");
    const std::string scene = write_scene(dir);
    for (const char* v : {"-5", "abc", "1e9", "99999999999999999999999"}) {
        SCOPED_TRACE(v);
        ::setenv("ENVTRACE_CL_GLOBAL_MEM", v, 1);
        const ett::CliRun r = ett::run_envtrace(
            {"render", scene, "--backend", "opencl", "-o", dir + "/o.exr"}, dir, 120);
        ::unsetenv("ENVTRACE_CL_GLOBAL_MEM");
        expect_error(r, "ENVTRACE_CL_GLOBAL_MEM: expected a positive number of bytes");
    }
}

TEST(CliOptions, CommandLinesThatDoNotParseAreOneErrorLineAndStatusOne) {
    const std::string dir = ett::scratch_dir("cli-opt-parse");
    const std::string scene = write_scene(dir), out = dir + "/o.exr";
    for (const std::vector<std::string>& more : {std::vector<std::string>{"--spp", "0"},
                                                 {"--bogus"},
                                                 {"--spp", "2", "--spp", "3"},
                                                 {"--strategy", "foo"}}) {
        SCOPED_TRACE(more[0]);
        const ett::CliRun r = ett::run_envtrace(render(scene, out, more), dir);
        ASSERT_TRUE(r.exited());
        EXPECT_EQ(r.code(), 1) << r.err;
        EXPECT_EQ(r.err.rfind("envtrace: error: ", 0), 0u) << r.err;
    }
    const ett::CliRun help = ett::run_envtrace({"render", "--help"}, dir);
    EXPECT_EQ(help.code(), 0) << help.err;
}

// The help text as a string: stdout of `envtrace ARGS` (run_envtrace keeps stderr only).
std::string help_text(const std::vector<std::string>& args, const std::string& dir) {
    std::string command = ENVTRACE_EXE;
    for (const std::string& a : args)
        command += " " + a;
    command += " > " + dir + "/help.txt";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    std::ifstream in(dir + "/help.txt");
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// `render --help` lists what a user chooses, with defaults, and points at the scene format; the
// internal knobs are listed by --help-expert only, and still work.
TEST(CliOptions, RenderHelpShowsUserOptionsAndDefaultsExpertKnobsApart) {
    const std::string dir = ett::scratch_dir("cli-opt-help");
    const std::string help = help_text({"render", "--help"}, dir);
    for (const char* shown :
         {"--spp", "--time-limit", "--noise-target", "--max-depth", "--strategy", "--seed",
          "--backend", "--threads", "--aovs", "--checkpoint", "--resume", "--sample-range",
          "--width", "--height", "--exposure", "--help-expert", "docs/scene-format.md", "else 16",
          "=opencl"})
        EXPECT_NE(help.find(shown), std::string::npos) << shown << "\n" << help;
    const char* expert[] = {"--light-batch",   "--paths",        "--guide-verdict",
                            "--light-samples", "--bsdf-samples", "--mis-heuristic",
                            "--bsdf-sampling", "--rr-depth"};
    for (const char* hidden : expert)
        EXPECT_EQ(help.find(hidden), std::string::npos) << hidden;
    const std::string all = help_text({"render", "--help-expert"}, dir);
    // Retired: the adaptive strategy, its light share and the mixed GGX sampling.
    for (const char* gone : {"--light-share", "adaptive", "mix"}) {
        EXPECT_EQ(help.find(gone), std::string::npos) << gone;
        EXPECT_EQ(all.find(gone), std::string::npos) << gone;
    }
    for (const char* listed : expert)
        EXPECT_NE(all.find(listed), std::string::npos) << listed;
    EXPECT_NE(all.find("--spp"), std::string::npos);
    // An expert knob still renders (and is checked) though --help does not list it.
    const std::string scene = write_scene(dir);
    const ett::CliRun r = ett::run_envtrace(
        render(scene, dir + "/o.exr", {"--spp", "1", "--rr-depth", "2", "--light-batch", "off"}),
        dir);
    EXPECT_EQ(r.code(), 0) << r.err;
    expect_error(ett::run_envtrace(render(scene, dir + "/o.exr", {"--light-share", "0.5"}), dir),
                 "--light-share");
}

// Empty values are refused by the option's name (`compare --json ""` wrote nothing, status 0;
// `compare "" b` said ": no such file"); an output under a file says it is not a folder; a
// negative --device is one short line (CLI11's NonNegativeNumber printed ~300 digits of a range);
// `devices` with a --device that does not exist says so (it was ignored).
TEST(CliOptions, EmptyValuesFilesAsFoldersAndDevicesAreNamed) {
    const std::string dir = ett::scratch_dir("cli-opt-empty");
    const std::string scene = write_scene(dir);
    expect_error(ett::run_envtrace({"compare", "", dir + "/sky.pfm"}, dir),
                 "the argument 'image' is empty");
    expect_error(
        ett::run_envtrace({"compare", dir + "/sky.pfm", dir + "/sky.pfm", "--json", ""}, dir),
        "--json is empty");
    expect_error(ett::run_envtrace({"convert", dir + "/sky.pfm", dir + "/sky.pfm/x.exr"}, dir),
                 "'" + dir + "/sky.pfm' is not a folder");
    const ett::CliRun r = ett::run_envtrace({"--device", "-1", "devices"}, dir);
    expect_error(r, "--device: Value -1 not in range 0 to 65535");
    EXPECT_LT(r.err.size(), 120u) << r.err;
    expect_error(ett::run_envtrace({"--device", "999", "devices"}, dir),
                 "--device 999 does not exist");
}

// An 8 x 6 sphere under write_scene's map (written first), with the given render block.
std::string write_sphere_scene(const std::string& dir, const std::string& name,
                               const std::string& render) {
    write_scene(dir);
    const std::string path = dir + "/" + name;
    write_file(path, R"({"environment": {"map": ")" + dir + R"(/sky.pfm"},
        "film": {"width": 8, "height": 6}, "camera": {"eye": [0, 0, 4], "target": [0, 0, 0]},
        "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}], "render": )" +
                         render + "}");
    return path;
}

TEST(CliOptions, BenchBuildsTheStrataOfAnSisScene) {
    const std::string dir = ett::scratch_dir("cli-opt-bench-sis");
    const std::string scene =
        write_sphere_scene(dir, "sis.json", R"({"spp": 64, "max_depth": 1, "strategy": "sis"})");
    expect_ok(ett::run_envtrace({"bench", scene, "--runs", "1", "--spp", "64", "--threads", "1"},
                                dir, 120));
}

// bench --strategy overrides the scene's (throughput across versions is of one estimator), and
// an unknown name is refused.
TEST(CliOptions, BenchTakesAStrategyOverTheScenes) {
    const std::string dir = ett::scratch_dir("cli-opt-bench-strategy");
    const std::string scene = write_sphere_scene(
        dir, "vis.json", R"({"spp": 4, "max_depth": 1, "strategy": "visibility"})");
    const std::string json = dir + "/bench.json";
    expect_ok(ett::run_envtrace({"bench", scene, "--strategy", "mis", "--runs", "1", "--spp", "4",
                                 "--threads", "1", "--json", json},
                                dir, 120));
    std::ifstream in(json);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t at = text.find("\"strategy\"");
    ASSERT_NE(at, std::string::npos) << text;
    const size_t open = text.find('"', text.find(':', at));
    EXPECT_EQ(text.substr(open, 5), "\"mis\"") << text.substr(at, 40);
    expect_error(ett::run_envtrace({"bench", scene, "--strategy", "best"}, dir), "--strategy");
}

TEST(CliOptions, CompareRefusesAMaskThatSelectsNothing) {
    const std::string dir = ett::scratch_dir("cli-opt-mask");
    et::write_image(dir + "/a.pfm", 2, 1, 3, {1, 1, 1, 2, 2, 2});
    et::write_image(dir + "/b.pfm", 2, 1, 3, {1, 1, 1, 3, 3, 3});
    et::write_image(dir + "/none.pfm", 2, 1, 3, {0.5f, 1, 1, -1, 0, 0});
    et::write_image(dir + "/one.pfm", 2, 1, 3, {0, 0, 0, 1, 0, 0});
    expect_error(ett::run_envtrace(
                     {"compare", dir + "/a.pfm", dir + "/b.pfm", "--mask", dir + "/none.pfm"}, dir),
                 "none.pfm: the mask selects no pixel");
    expect_ok(ett::run_envtrace(
        {"compare", dir + "/a.pfm", dir + "/b.pfm", "--mask", dir + "/one.pfm"}, dir));
}

// Where the map samples are drawn (--light-batch) changes no bit: a render resumes across it.
TEST(CliOptions, ResumeAcrossALightBatchChange) {
    const std::string dir = ett::scratch_dir("cli-opt-resume-batch");
    const std::string scene = write_scene(dir), out = dir + "/o.exr";
    expect_ok(ett::run_envtrace(
        render(scene, out, {"--spp", "2", "--checkpoint", "0", "--light-batch", "on"}), dir));
    expect_ok(ett::run_envtrace(
        render(scene, out, {"--spp", "4", "--resume", "--checkpoint", "0", "--light-batch", "off"}),
        dir));
}

TEST(CliOptions, PlyWarningsCountLikeWithLike) {
    const std::string dir = ett::scratch_dir("cli-opt-ply");
    write_scene(dir);
    // A pentagon fanned into three triangles, one of them degenerate (corners 0, 2, 3 on a
    // line), and a face of two corners.
    write_file(dir + "/p.ply", "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 2\n"
                               "property list uchar int vertex_indices\nend_header\n"
                               "0 0 0\n1 0 0\n1 0 1\n2 0 2\n0 0 1\n5 0 1 2 3 4\n2 0 1\n");
    write_file(dir + "/m.json", R"({"environment": {"map": ")" + dir +
                                    R"(/sky.pfm"}, "film": {"width": 4, "height": 2},
        "shapes": [{"type": "mesh", "file": ")" +
                                    dir + R"(/p.ply"}], "render": {"spp": 1, "max_depth": 1}})");
    const ett::CliRun r = ett::run_envtrace(render(dir + "/m.json", dir + "/o.exr"), dir);
    expect_ok(r);
    EXPECT_NE(r.err.find("1 faces of fewer than three corners skipped"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("1 of 3 triangles skipped"), std::string::npos) << r.err;
}

} // namespace
