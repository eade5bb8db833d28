// Running one function on several threads: the host's only parallel construct.
#pragma once
#include <algorithm>
#include <thread>
#include <vector>

namespace et {

// `requested` threads, or every hardware thread when it is 0 or less.
inline int thread_count(int requested) {
    return requested > 0 ? requested
                         : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// Calls work(t) for t = 0 .. threads-1, t = 0 on the calling thread; returns when all are done.
template <typename F> void run_on_threads(int threads, F&& work) {
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t)
        pool.emplace_back([&work, t] { work(t); });
    work(0);
    for (auto& th : pool)
        th.join();
}

} // namespace et
