// SIGINT / SIGTERM handling (host/lib/util/interrupt.h), in child processes: the first signal is
// recorded and the process goes on; a second ends it at once with 128 + signal; the previous
// handlers come back when the handler object goes.
#include "util/interrupt.h"

#include <gtest/gtest.h>

#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

namespace {

// Runs `body` in a child; returns its waitpid status.
template <class F> int in_child(F body) {
    const pid_t pid = fork();
    if (pid == 0) {
        body();
        _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return status;
}

TEST(Interrupt, FirstSignalIsRecordedSecondEndsAtOnce) {
    for (const int sig : {SIGINT, SIGTERM}) {
        // One signal: recorded, execution goes on.
        int status = in_child([sig] {
            et::InterruptHandler h;
            if (et::InterruptHandler::signal() != 0)
                _exit(10);
            raise(sig);
            _exit(et::InterruptHandler::signal() == sig ? 42 : 11);
        });
        ASSERT_TRUE(WIFEXITED(status));
        EXPECT_EQ(WEXITSTATUS(status), 42);
        // Two: the second ends the process with 128 + the second signal's number.
        status = in_child([sig] {
            et::InterruptHandler h;
            raise(sig);
            raise(SIGINT);
            _exit(12); // not reached
        });
        ASSERT_TRUE(WIFEXITED(status));
        EXPECT_EQ(WEXITSTATUS(status), 128 + SIGINT);
    }
}

TEST(Interrupt, PreviousHandlersComeBack) {
    const int status = in_child([] {
        { et::InterruptHandler h; }
        raise(SIGTERM); // the default action again: killed by the signal
        _exit(13);
    });
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
    EXPECT_STREQ(et::signal_name(SIGINT), "SIGINT");
    EXPECT_STREQ(et::signal_name(SIGTERM), "SIGTERM");
}

} // namespace
