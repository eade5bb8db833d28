// run_on_threads: every part runs exactly once, even when the system refuses threads, and an
// exception in a part comes back to the caller instead of ending the process.
#include "util/error.h"
#include "util/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <pthread.h>
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

#if defined(__SANITIZE_ADDRESS__)
#define ET_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ET_TEST_ASAN 1
#endif
#endif

// Makes the system refuse threads. An address-space limit of 1 GiB holds ~100 stacks of 8 MiB,
// so thread creation fails part way. Under AddressSanitizer no such limit can be set (its shadow
// memory reserves terabytes of address space, so ASan's own next mmap fails and it aborts); there
// a default thread stack larger than the address space refuses every thread instead.
void refuse_threads() {
#ifdef ET_TEST_ASAN
    pthread_attr_t attr;
    pthread_attr_init(&attr);
    pthread_attr_setstacksize(&attr, size_t(1) << 47);
    pthread_setattr_default_np(&attr);
    pthread_attr_destroy(&attr);
#else
    rlimit lim{};
    getrlimit(RLIMIT_AS, &lim);
    lim.rlim_cur = rlim_t(1) << 30;
    setrlimit(RLIMIT_AS, &lim);
#endif
}

// 1024 threads when the system refuses some or all of them: thread creation fails
// (std::system_error), which used to end in std::terminate.
TEST(RunOnThreadsDeathTest, RefusedThreadsRunOnFewer) {
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_EXIT(
        {
            static std::atomic<int> warnings{0};
            et::set_warning_sink([](const std::string&) { ++warnings; });
            refuse_threads();
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
