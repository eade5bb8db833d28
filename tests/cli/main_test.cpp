// How `envtrace` (host/cli/main.cpp) ends on hostile input: the fuzz findings' reproducers
// (tools/fuzz/findings, all fixed in the loaders or masked in their harness) through the command
// line end in exactly one "envtrace: error: " line that names the file, and exit status 1, never
// in std::terminate, a signal, raw library text or an output file.
#include "cli_run.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

void expect_one_error_line(const ett::CliRun& r, const std::string& must_name,
                           const std::string& out) {
    ASSERT_FALSE(r.timed_out) << "hung";
    ASSERT_TRUE(r.exited()) << "killed by signal " << WTERMSIG(r.status) << "; stderr: " << r.err;
    EXPECT_EQ(r.code(), 1) << r.err;
    const size_t at = r.err.find("envtrace: error: ");
    ASSERT_NE(at, std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("envtrace: error: ", at + 1), std::string::npos) << r.err;
    const std::string line = r.err.substr(at, r.err.find('\n', at) - at);
    EXPECT_NE(line.find(must_name), std::string::npos) << line;
    for (const char* raw : {"terminate called", "json.exception", "unexpected exception"})
        EXPECT_EQ(r.err.find(raw), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << out << " written";
}

std::vector<std::string> findings(const std::string& suffix) {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(ENVTRACE_FUZZ_FINDINGS_DIR)) {
        const std::string n = e.path().filename().string();
        if (n.size() > suffix.size() &&
            n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0)
            out.push_back(e.path().string());
    }
    return out;
}

TEST(CliErrors, FuzzFindingScenesEndInOneErrorLine) {
    const std::string dir = ett::scratch_dir("cli-findings-scenes");
    const std::vector<std::string> scenes = findings(".scene.json");
    ASSERT_FALSE(scenes.empty()) << "no *.scene.json in " << ENVTRACE_FUZZ_FINDINGS_DIR;
    for (const std::string& scene : scenes) {
        SCOPED_TRACE(scene);
        const std::string out = dir + "/out.exr";
        expect_one_error_line(ett::run_envtrace({"render", scene, "-o", out}, dir),
                              fs::path(scene).filename().string() + ":", out);
    }
}

TEST(CliErrors, FuzzFindingLightSetsEndInOneErrorLine) {
    const std::string dir = ett::scratch_dir("cli-findings-lights");
    const std::string scene = dir + "/sky.json";
    std::ofstream(scene) << R"({"environment": {"sky": {"resolution": [8, 4]}},
                               "film": {"width": 4, "height": 2},
                               "render": {"spp": 1, "max_depth": 1}})";
    const std::vector<std::string> sets = findings(".lights.json");
    ASSERT_FALSE(sets.empty()) << "no *.lights.json in " << ENVTRACE_FUZZ_FINDINGS_DIR;
    for (const std::string& lights : sets) {
        SCOPED_TRACE(lights);
        const std::string out = dir + "/out.exr";
        expect_one_error_line(
            ett::run_envtrace({"render", scene, "--lights", lights, "-o", out}, dir),
            fs::path(lights).filename().string() + ":", out);
    }
}

} // namespace
