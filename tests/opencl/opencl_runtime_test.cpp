// Build errors that name kernels/FILE:LINE, division and sqrt rounding as on the host, every
// program building without a warning, and the on-disk program-binary cache (keyed by source and
// options; a corrupt entry is rebuilt).
#include "opencl/kernel_sources.h"
#include "opencl/opencl_runtime.h"
#include "test_data.h"
#include "test_kernels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstdint>
#include <vector>
#include <random>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

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

TEST(OpenClRuntime, DivisionAndSqrtRoundAsOnTheHost) {
    // Where the device reports CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT, programs are built so that
    // x / y and sqrt(x) equal the host's bit for bit, which is what lets images of the two back
    // ends agree exactly (without the option NVIDIA's driver gave other bits: docs/devices.md).
    et::ClRuntime& rt = ett::runtime();
    if (!rt.limits().correctly_rounded_div_sqrt)
        GTEST_SKIP() << "the device does not report correctly rounded division and sqrt";
    const std::string source =
        "__kernel void div_sqrt(__global const float* a, __global const float* b,\n"
        "                       __global float* q, __global float* r) {\n"
        "    size_t i = get_global_id(0);\n"
        "    q[i] = a[i] / b[i];\n"
        "    r[i] = sqrt(a[i]);\n"
        "}\n";
    cl::Program program = rt.build_source("div_sqrt.cl", source);
    // Random significands over 2^-40 .. 2^40: quotients stay normal, every rounding case occurs.
    const size_t n = size_t(1) << 18;
    std::mt19937 rng(7);
    std::uniform_int_distribution<uint32_t> mantissa(0, (1u << 23) - 1), exponent(87, 167);
    auto draw = [&] {
        const uint32_t bits = exponent(rng) << 23 | mantissa(rng);
        float f;
        std::memcpy(&f, &bits, sizeof f);
        return f;
    };
    std::vector<float> a(n), b(n), q(n), r(n);
    for (size_t i = 0; i < n; ++i) {
        a[i] = draw();
        b[i] = draw();
    }
    cl::Buffer da(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(float),
                  a.data());
    cl::Buffer db(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(float),
                  b.data());
    cl::Buffer dq(rt.context(), CL_MEM_WRITE_ONLY, n * sizeof(float));
    cl::Buffer dr(rt.context(), CL_MEM_WRITE_ONLY, n * sizeof(float));
    cl::Kernel k(program, "div_sqrt");
    k.setArg(0, da);
    k.setArg(1, db);
    k.setArg(2, dq);
    k.setArg(3, dr);
    rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(n));
    rt.queue().enqueueReadBuffer(dq, CL_TRUE, 0, n * sizeof(float), q.data());
    rt.queue().enqueueReadBuffer(dr, CL_TRUE, 0, n * sizeof(float), r.data());
    size_t q_off = 0, r_off = 0;
    for (size_t i = 0; i < n; ++i) {
        q_off += q[i] != a[i] / b[i];
        r_off += r[i] != std::sqrt(a[i]);
    }
    EXPECT_EQ(q_off, 0u) << "quotients differing from the host's, of " << n;
    EXPECT_EQ(r_off, 0u) << "square roots differing from the host's, of " << n;
}

// The lines of a build log that warn about the source, in any case (NVIDIA writes "Warning:"),
// less one line NVIDIA's drivers since 550 write for every kernel of a program, "Warning:
// Function NAME is a kernel, so overriding noinline attribute. The function may be inlined when
// called." (as the H200's driver writes it, after an empty location: "(): Warning: ...") -- about
// the driver's own attribute, with or without any noinline in the source (the
// H200 wrote it for wavefront.cl, whose GPU build has none; pyFAI, John the Ripper and others
// report it with the same words, and no change to their sources silenced it).
static std::string source_warnings(const std::string& log) {
    std::istringstream in(log);
    std::string line, found;
    while (std::getline(in, line)) {
        std::string lower = line;
        std::transform(lower.begin(), lower.end(), lower.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (lower.find("warning") == std::string::npos)
            continue;
        static const std::regex nvidia("^(\\([^)]*\\):\\s*)?warning: function \\w+ is a kernel, so "
                                       "overriding noinline attribute\\.?"
                                       "( the function may be inlined when called\\.)?\\s*$");
        if (!std::regex_match(lower, nvidia))
            found += line + "\n";
    }
    return found;
}

TEST(OpenClRuntime, BuildWarningsAreTheSourcesAlone) {
    EXPECT_EQ(source_warnings(""), "");
    EXPECT_EQ(source_warnings("Warning: Function shade_hits is a kernel, so overriding noinline "
                              "attribute. The function may be inlined when called.\n"),
              "");
    EXPECT_EQ(source_warnings("Warning: Function generate is a kernel, so overriding noinline "
                              "attribute\r\n"),
              "");
    EXPECT_EQ(source_warnings("(): Warning: Function bvh_trace is a kernel, so overriding noinline "
                              "attribute. The function may be inlined when called.\n"),
              "");
    const std::string pocl = "<source>:3:9: warning: 'dot' macro redefined [-Wmacro-redefined]";
    EXPECT_EQ(source_warnings("ok\n" + pocl + "\n"), pocl + "\n");
    const std::string nv = "Warning: Function shade_hits is a kernel, and something else.";
    EXPECT_EQ(source_warnings(nv), nv + "\n");
    const std::string located = "(5): Warning: variable x is unused";
    EXPECT_EQ(source_warnings(located), located + "\n");
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
        EXPECT_EQ(source_warnings(info.log), "") << name << ":\n" << info.log;
        ++programs;
    }
    EXPECT_GE(programs, 2); // wavefront.cl, envmap_sample.cl
    // The tests' own programs (tests/kernels/cl), held apart from the product's.
    for (const auto& [name, text] : ett::test_kernel_sources()) {
        EXPECT_EQ(et::embedded_kernel_sources().count(name), 0u) << name << " is in the product";
        et::ProgramBuildInfo info;
        ett::runtime().build_source(
            name, et::expand_kernel_source(name, ett::test_kernel_sources(), "tests/kernels/cl"),
            "", &info);
        ASSERT_FALSE(info.from_cache) << name;
        EXPECT_EQ(source_warnings(info.log), "") << name << ":\n" << info.log;
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
