#include "util/signal_cleanup.h"

#include <atomic>
#include <csignal>
#include <pthread.h>
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
std::atomic<int> g_committing{0}, g_deferred{0};

// Ends the process by `sig` as its default action would, the temporaries removed first.
void die_of(int sig) {
    remove_registered_temporaries();
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = SIG_DFL;
    sigemptyset(&sa.sa_mask);
    sigaction(sig, &sa, nullptr);
    // Raised in a handler, it runs once the handler returns (the signal is blocked meanwhile).
    ::raise(sig);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, sig);
    pthread_sigmask(SIG_UNBLOCK, &set, nullptr); // outside a handler: now
}

void on_fatal_signal(int sig) {
    if (!ending_signal_deferred(sig))
        die_of(sig);
}

} // namespace

void install_signal_cleanup() {
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_fatal_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
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

bool ending_signal_deferred(int sig) {
    if (g_committing.load() == 0)
        return false;
    int expected = 0;
    g_deferred.compare_exchange_strong(expected, sig);
    return true;
}

CommitInProgress::CommitInProgress() {
    g_committing.fetch_add(1);
}

CommitInProgress::~CommitInProgress() {
    if (g_committing.fetch_sub(1) == 1) {
        const int sig = g_deferred.exchange(0);
        if (sig != 0)
            die_of(sig);
    }
}

void remove_registered_temporaries() {
    for (Slot& s : g_slots)
        if (s.state.load(std::memory_order_acquire) == 1)
            ::unlink(s.path);
}

} // namespace et
