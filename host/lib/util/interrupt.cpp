#include "util/interrupt.h"
#include "util/signal_cleanup.h"

#include <atomic>
#include <csignal>
#include <cstring>
#include <unistd.h>

namespace et {
namespace {

std::atomic<int> g_first{0};
struct sigaction g_old_int, g_old_term;

void on_signal(int sig) {
    int expected = 0;
    if (g_first.compare_exchange_strong(expected, sig))
        return;
    // The second signal: only async-signal-safe calls from here. During the renames of a set
    // of outputs it waits for them (they land whole), then ends the process.
    if (ending_signal_deferred(sig))
        return;
    remove_registered_temporaries();
    const char msg[] = "\nenvtrace: interrupted again: stopping now, nothing more is written\n";
    ssize_t ignored = ::write(2, msg, sizeof msg - 1);
    (void)ignored;
    ::_exit(128 + sig);
}

} // namespace

InterruptHandler::InterruptHandler() {
    g_first = 0;
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    sigaction(SIGINT, &sa, &g_old_int);
    sigaction(SIGTERM, &sa, &g_old_term);
}

InterruptHandler::~InterruptHandler() {
    sigaction(SIGINT, &g_old_int, nullptr);
    sigaction(SIGTERM, &g_old_term, nullptr);
}

int InterruptHandler::signal() {
    return g_first.load();
}

const char* signal_name(int sig) {
    switch (sig) {
    case SIGINT:
        return "SIGINT";
    case SIGTERM:
        return "SIGTERM";
    case SIGHUP:
        return "SIGHUP";
    default:
        return "a signal";
    }
}

} // namespace et
