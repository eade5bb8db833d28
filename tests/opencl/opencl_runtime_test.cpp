// Build errors that name kernels/FILE:LINE, every program building without a warning, and the
// on-disk program-binary cache (keyed by source and options; a corrupt entry is rebuilt).
#include "opencl/kernel_sources.h"
#include "opencl/opencl_runtime.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>

namespace fs = std::filesystem;

namespace {

// Points ENVTRACE_CACHE_DIR at a fresh folder for the test's lifetime.
class ScopedCacheDir {
  public:
    explicit ScopedCacheDir(const std::string& name) : dir_(ett::scratch_dir(name)) {
        const char* old = std::getenv("ENVTRACE_CACHE_DIR");
        had_ = old != nullptr;
        if (had_)
            old_ = old;
        setenv("ENVTRACE_CACHE_DIR", dir_.c_str(), 1);
    }
    ~ScopedCacheDir() {
        if (had_)
            setenv("ENVTRACE_CACHE_DIR", old_.c_str(), 1);
        else
            unsetenv("ENVTRACE_CACHE_DIR");
    }
    const std::string& dir() const { return dir_; }

  private:
    std::string dir_, old_;
    bool had_ = false;
};

const char* kGood = "#line 1 \"kernels/probe.cl\"\n"
                    "__kernel void probe(__global float* x) { x[get_global_id(0)] *= 2.0f; }\n";

} // namespace

TEST(OpenClRuntime, BuildErrorNamesKernelFileAndLine) {
    ScopedCacheDir cache("cl-build-error");
    const std::string broken = "#line 1 \"kernels/broken.cl\"\n"
                               "__kernel void k(__global float* x) {\n"
                               "    x[0] = undefined_identifier;\n"
                               "}\n";
    try {
        ett::runtime().build_source("broken.cl", broken);
        FAIL() << "a broken program built";
    } catch (const et::Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("kernels/broken.cl failed to build"), std::string::npos) << msg;
        // The log's format is the driver's own: accept the usual spellings of "file, line 2"
        // (clang-based drivers: "kernels/broken.cl:2:5:"; others "(2)" or ", line 2").
        EXPECT_TRUE(std::regex_search(msg, std::regex(R"(kernels/broken\.cl(:| ?\(|, line )2\b)")))
            << "the compiler log should point at line 2 of kernels/broken.cl:\n"
            << msg;
    }
    EXPECT_TRUE(fs::is_empty(cache.dir())) << "a failed build must not leave a cache entry";
}

TEST(OpenClRuntime, EveryProgramBuildsWithoutWarnings) {
    // The device compiler's own headers may define what the kernels define (PoCL's made 'dot' and
    // 'length' macros, and every build warned); its log of a clean build holds no warning.
    ScopedCacheDir cache("cl-build-warnings");
    int programs = 0;
    for (const auto& [name, text] : et::embedded_kernel_sources()) {
        if (fs::path(name).extension() != ".cl")
            continue;
        et::ProgramBuildInfo info;
        ett::runtime().build(name, "", &info);
        ASSERT_FALSE(info.from_cache) << name;
        EXPECT_EQ(info.log.find("warning"), std::string::npos) << name << ":\n" << info.log;
        ++programs;
    }
    EXPECT_GE(programs, 5);
}

TEST(OpenClRuntime, BinaryCacheIsKeyedBySourceAndOptionsAndSurvivesCorruption) {
    ScopedCacheDir cache("cl-cache");
    et::ClRuntime& rt = ett::runtime();
    et::ProgramBuildInfo cold, warm, other_options, other_source, after_corruption;
    rt.build_source("probe.cl", kGood, "", &cold);
    EXPECT_FALSE(cold.from_cache);
    ASSERT_TRUE(fs::exists(cold.cache_file)) << cold.cache_file;

    rt.build_source("probe.cl", kGood, "", &warm);
    EXPECT_TRUE(warm.from_cache);
    EXPECT_EQ(warm.cache_file, cold.cache_file);

    rt.build_source("probe.cl", kGood, "-DSOMETHING=1", &other_options);
    EXPECT_FALSE(other_options.from_cache);
    EXPECT_NE(other_options.cache_file, cold.cache_file);

    rt.build_source("probe.cl", std::string(kGood) + "\n// changed\n", "", &other_source);
    EXPECT_FALSE(other_source.from_cache);
    EXPECT_NE(other_source.cache_file, cold.cache_file);

    // Garbage in the cache: rebuilt from source, and the program still runs.
    {
        std::ofstream f(cold.cache_file, std::ios::binary | std::ios::trunc);
        f << "not a program binary";
    }
    cl::Program p = rt.build_source("probe.cl", kGood, "", &after_corruption);
    EXPECT_FALSE(after_corruption.from_cache);
    cl::Kernel k(p, "probe");
    float v[4] = {1, 2, 3, 4};
    cl::Buffer b(rt.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof v, v);
    k.setArg(0, b);
    rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(4));
    rt.queue().enqueueReadBuffer(b, CL_TRUE, 0, sizeof v, v);
    EXPECT_EQ(v[3], 8.0f);
}
