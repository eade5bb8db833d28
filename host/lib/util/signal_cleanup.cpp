#include "util/signal_cleanup.h"

#include <atomic>
#include <csignal>
#include <cstring>
#include <unistd.h>

namespace et {
namespace {

// A slot is free (0), being written (2) or holds a path (1); the handler reads only 1s.
struct Slot {
    std::atomic<int> state{0};
    char path[4096];
};
Slot g_slots[kSignalCleanupSlots];

void on_fatal_signal(int sig) {
    remove_registered_temporaries();
    // SA_RESETHAND restored the default action; raised here, it runs once the handler returns
    // (the signal is blocked meanwhile) and ends the process as the signal would have.
    ::raise(sig);
}

} // namespace

void install_signal_cleanup() {
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_fatal_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
        struct sigaction old;
        // A signal ignored when envtrace started (nohup, a shell's background job) stays so.
        if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN)
            continue;
        sigaction(sig, &sa, nullptr);
    }
}

void register_temporary(const std::string& path) {
    if (path.size() >= sizeof g_slots[0].path)
        return;
    for (Slot& s : g_slots) {
        int expected = 0;
        if (s.state.compare_exchange_strong(expected, 2)) {
            std::memcpy(s.path, path.c_str(), path.size() + 1);
            s.state.store(1, std::memory_order_release);
            return;
        }
    }
}

void unregister_temporary(const std::string& path) {
    for (Slot& s : g_slots)
        if (s.state.load(std::memory_order_acquire) == 1 && path == s.path) {
            s.state.store(0, std::memory_order_release);
            return;
        }
}

void remove_registered_temporaries() {
    for (Slot& s : g_slots)
        if (s.state.load(std::memory_order_acquire) == 1)
            ::unlink(s.path);
}

} // namespace et
