// Temporaries a signal must not leave (host/lib/util/signal_cleanup.h): a process holding an
// output batch and ended by SIGINT, SIGTERM or SIGHUP dies of that signal, with its temporaries
// removed and no target written; a committed batch's files are no longer registered (a signal
// afterwards removes nothing of them).
#include "util/output_batch.h"
#include "util/signal_cleanup.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

// In a child: a batch for DIR/out.exr written to its temporary, then `sig` (after the commit
// when `commit`). Returns the child's wait status.
int child_signalled(const std::string& dir, int sig, bool commit) {
    const pid_t pid = fork();
    if (pid == 0) {
        et::install_signal_cleanup();
        et::OutputBatch batch({dir + "/out.exr"});
        batch.write(dir + "/out.exr", [](const std::string& t) { std::ofstream(t) << "image"; });
        if (commit) {
            batch.commit();
            // A file where the temporary was: no longer registered, so the signal keeps it.
            std::ofstream(et::temporary_path(dir + "/out.exr", getpid())) << "not ours any more";
        }
        ::raise(sig);
        _exit(0); // not reached: the signal ends the process
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return status;
}

std::vector<std::string> names_in(const std::string& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    return names;
}

} // namespace

TEST(SignalCleanup, ASignalEndingTheProcessRemovesItsTemporaries) {
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
        const std::string dir = ett::scratch_dir("signal_cleanup_" + std::to_string(sig));
        const int status = child_signalled(dir, sig, false);
        ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
        EXPECT_EQ(WTERMSIG(status), sig);
        EXPECT_TRUE(names_in(dir).empty()) << names_in(dir)[0];
    }
}

TEST(SignalCleanup, CommittedOutputsAreKept) {
    const std::string dir = ett::scratch_dir("signal_cleanup_committed");
    const int status = child_signalled(dir, SIGTERM, true);
    ASSERT_TRUE(WIFSIGNALED(status));
    std::vector<std::string> names = names_in(dir);
    std::sort(names.begin(), names.end());
    ASSERT_EQ(names.size(), 2u);
    EXPECT_EQ(names[1], "out.exr");
    EXPECT_EQ(names[0].rfind(".out.tmp", 0), 0u) << names[0];
}

// A signal another thread takes while a batch renames its files (the committing thread blocks
// them; OpenCL's or MPI's threads do not) waits until the renames are done, then ends the
// process: the outputs land whole.
TEST(SignalCleanup, ASignalDuringACommitWaitsForIt) {
    const std::string dir = ett::scratch_dir("signal_cleanup_during_commit");
    const pid_t pid = fork();
    if (pid == 0) {
        et::install_signal_cleanup();
        et::OutputBatch batch({dir + "/a.exr", dir + "/b.exr"});
        for (const char* n : {"/a.exr", "/b.exr"})
            batch.write(dir + n, [](const std::string& t) { std::ofstream(t) << "image"; });
        {
            et::CommitInProgress committing; // as commit() holds it
            ::raise(SIGTERM);                // (this thread: the handler defers it)
            batch.commit();
        }
        _exit(0); // not reached: the deferred signal ends the process
    }
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
    std::vector<std::string> names = names_in(dir);
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"a.exr", "b.exr"}));
}

TEST(SignalCleanup, RegisteredFilesAreRemovedUnregisteredKept) {
    const std::string dir = ett::scratch_dir("signal_cleanup_registry");
    for (const char* n : {"a", "b"})
        std::ofstream(dir + "/" + n) << n;
    et::register_temporary(dir + "/a");
    et::register_temporary(dir + "/b");
    et::unregister_temporary(dir + "/b");
    et::remove_registered_temporaries();
    et::unregister_temporary(dir + "/a");
    EXPECT_EQ(names_in(dir), std::vector<std::string>{"b"});
}
