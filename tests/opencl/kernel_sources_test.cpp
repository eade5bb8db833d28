// host/lib/opencl/kernel_sources: the embedded sources expanded with #line directives, and build
// logs of compilers that ignore those directives mapped back to kernels/FILE:LINE.
#include "opencl/kernel_sources.h"
#include "util/error.h"
#include "test_kernels.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

TEST(KernelSources, IncludesExpandOnceWithLineMarkers) {
    const std::string src = et::expand_kernel_source("envmap_sample.cl");
    EXPECT_NE(src.find("#line 1 \"kernels/envmap_sample.cl\""), std::string::npos);
    EXPECT_NE(src.find("#line 1 \"kernels/compat.h\""), std::string::npos);
    EXPECT_NE(src.find("#line 1 \"kernels/envmap.h\""), std::string::npos);
    // compat.h is included by several headers but expanded once.
    const std::string marker = "#line 1 \"kernels/compat.h\"";
    EXPECT_EQ(src.find(marker), src.rfind(marker));
    // After an include, the including file's numbering resumes on its next line.
    EXPECT_NE(src.find("#line 4 \"kernels/envmap_sample.cl\""), std::string::npos);
    EXPECT_EQ(src.find("#include \""), std::string::npos) << "an include was left unexpanded";
    EXPECT_THROW(et::expand_kernel_source("no_such_kernel.cl"), et::Error);
}

// Test and benchmark programs are not the product's: the envtrace binary cannot build them, a
// test binary expands its own with the product's headers, each named by its folder.
TEST(KernelSources, TestProgramsAreEmbeddedApartFromTheProduct) {
    for (const char* name : {"bvh_test.cl", "sampler_test.cl", "texture_test.cl"}) {
        SCOPED_TRACE(name);
        EXPECT_EQ(et::embedded_kernel_sources().count(name), 0u);
        EXPECT_THROW(et::expand_kernel_source(name), et::Error);
        ASSERT_EQ(ett::test_kernel_sources().count(name), 1u);
    }
    for (const auto& [name, text] : et::embedded_kernel_sources())
        EXPECT_TRUE(name.find("_test.") == std::string::npos &&
                    name.find("_bench.") == std::string::npos)
            << name << ": a test or benchmark program among the product's kernels";
    const std::string src =
        et::expand_kernel_source("sampler_test.cl", ett::test_kernel_sources(), "tests/kernels/cl");
    EXPECT_NE(src.find("#line 1 \"tests/kernels/cl/sampler_test.cl\""), std::string::npos);
    EXPECT_NE(src.find("#line 1 \"kernels/sampler.h\""), std::string::npos);
    EXPECT_EQ(src.find("#include \""), std::string::npos) << "an include was left unexpanded";
}

TEST(KernelSources, LogLocationsOfTheProgramStringMapToFileAndLine) {
    // What NVIDIA's driver reported for a file whose second line is wrong: the physical line of
    // the expanded source (its first line is the #line directive), under the name "<kernel>".
    const std::string source = "#line 1 \"kernels/broken.cl\"\n"
                               "__kernel void k(__global int* x) {\n"
                               "    x[0] = undefined_identifier;\n"
                               "#line 1 \"kernels/inc.h\"\n"
                               "int f();\n"
                               "#line 3 \"kernels/broken.cl\"\n"
                               "}\n";
    EXPECT_EQ(et::logical_locations("<kernel>:3:12: error: use of undeclared identifier", source),
              "kernels/broken.cl:2:12: error: use of undeclared identifier");
    EXPECT_EQ(et::logical_locations("<kernel>:5:1: error: x\n<kernel>:7:1: note: y", source),
              "kernels/inc.h:1:1: error: x\nkernels/broken.cl:3:1: note: y");
    // Already logical (PoCL, clang), beyond the source, or no number: left as they are.
    for (const char* log : {"kernels/broken.cl:2:12: error", "<kernel>:99:1: error",
                            "<kernel>:0:1: error", "<kernel>: error", "<kernel>:99999999999999:1"})
        EXPECT_EQ(et::logical_locations(log, source), log) << log;
}

TEST(KernelSources, ExpandedSourceLinesMapBackToTheirFiles) {
    // Every physical line of a real expansion maps to the file line it came from: one log line
    // per physical source line, mapped at once.
    const std::string src = et::expand_kernel_source("wavefront.cl");
    std::vector<std::string> lines;
    std::string log;
    {
        std::istringstream in(src);
        std::string line;
        while (std::getline(in, line)) {
            lines.push_back(line);
            log += "<kernel>:" + std::to_string(lines.size()) + ":1\n";
        }
    }
    std::istringstream mapped(et::logical_locations(log, src));
    const auto& files = et::embedded_kernel_sources();
    std::string where;
    int checked = 0;
    for (const std::string& line : lines) {
        ASSERT_TRUE(std::getline(mapped, where));
        if (line.rfind("#line", 0) == 0)
            continue;
        ASSERT_EQ(where.rfind("kernels/", 0), 0u) << where;
        const size_t colon = where.find(':');
        const std::string file = where.substr(8, colon - 8);
        const int number = std::stoi(where.substr(colon + 1));
        std::istringstream original(files.at(file));
        std::string expected;
        for (int i = 0; i < number; ++i)
            std::getline(original, expected);
        ASSERT_EQ(line, expected) << where;
        ++checked;
    }
    EXPECT_GT(checked, 1000);
}
