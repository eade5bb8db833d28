// Running one function on several threads: the host's only parallel construct.
#pragma once
#include "util/error.h"

#include <algorithm>
#include <exception>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

namespace et {

// `requested` threads, or every hardware thread when it is 0 or less.
inline int thread_count(int requested) {
    return requested > 0 ? requested
                         : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// Calls work(t) exactly once for each t = 0 .. threads-1, t = 0 on the calling thread; returns
// when all are done. When the system refuses a thread (limits on threads or memory), the parts
// it would have run are run on the calling thread after its own, with one warning: fewer threads,
// the same result. The first exception thrown by any part is rethrown here, after every thread
// has been joined (never std::terminate).
template <typename F> void run_on_threads(int threads, F&& work) {
    std::vector<std::thread> pool;
    std::exception_ptr failure;
    std::mutex failure_mutex;
    auto guarded = [&](int t) {
        try {
            work(t);
        } catch (...) {
            std::lock_guard<std::mutex> lock(failure_mutex);
            if (!failure)
                failure = std::current_exception();
        }
    };
    int started = 1;
    try {
        pool.reserve(static_cast<size_t>(std::max(0, threads - 1)));
        for (; started < threads; ++started)
            pool.emplace_back([&guarded, t = started] { guarded(t); });
    } catch (const std::system_error&) {
        warn("could start only " + std::to_string(started) + " of " + std::to_string(threads) +
             " threads; running the rest on fewer threads");
    } catch (const std::bad_alloc&) {
        warn("could start only " + std::to_string(started) + " of " + std::to_string(threads) +
             " threads (out of memory); running the rest on fewer threads");
    }
    guarded(0);
    for (int t = started; t < threads; ++t)
        guarded(t);
    for (auto& th : pool)
        th.join();
    if (failure)
        std::rethrow_exception(failure);
}

} // namespace et
