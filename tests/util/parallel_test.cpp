// run_on_threads: every part runs exactly once, even when the system refuses threads, and an
// exception in a part comes back to the caller instead of ending the process.
#include "util/error.h"
#include "util/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <sys/resource.h>
#include <vector>

namespace {

TEST(RunOnThreads, EveryPartOnce) {
    std::vector<std::atomic<int>> runs(8);
    et::run_on_threads(8, [&](int t) { runs[t]++; });
    for (auto& r : runs)
        EXPECT_EQ(r.load(), 1);
}

TEST(RunOnThreads, ExceptionsReachTheCaller) {
    std::atomic<int> done{0};
    EXPECT_THROW(et::run_on_threads(4,
                                    [&](int t) {
                                        ++done;
                                        if (t == 2)
                                            throw et::Error("part 2 failed");
                                    }),
                 et::Error);
    EXPECT_EQ(done.load(), 4);
}

// 1024 threads under an address-space limit that cannot hold their stacks: thread creation
// fails part way (std::system_error), which used to end in std::terminate.
TEST(RunOnThreadsDeathTest, RefusedThreadsRunOnFewer) {
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_EXIT(
        {
            static std::atomic<int> warnings{0};
            et::set_warning_sink([](const std::string&) { ++warnings; });
            rlimit lim{};
            getrlimit(RLIMIT_AS, &lim);
            lim.rlim_cur = rlim_t(1) << 30; // 1 GiB: room for ~100 stacks of 8 MiB
            setrlimit(RLIMIT_AS, &lim);
            std::vector<std::atomic<int>> runs(1024);
            et::run_on_threads(1024, [&](int t) { runs[t]++; });
            for (auto& r : runs)
                if (r.load() != 1)
                    std::_Exit(2);
            std::_Exit(warnings.load() == 1 ? 0 : 3); // 3: the limit did not refuse a thread
        },
        ::testing::ExitedWithCode(0), "");
}

} // namespace
