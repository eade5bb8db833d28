// Running build/envtrace as a child process: exit status, stderr, and a time limit that turns a
// hang into a failure instead of a stuck suite.
#pragma once
#include <string>
#include <sys/types.h>
#include <vector>

namespace ett {

struct CliRun {
    int status = 0; // as from waitpid
    bool timed_out = false;
    std::string err; // everything written to stderr
    bool exited() const;
    int code() const;
};

// A started run, to be signalled or waited for.
struct CliProcess {
    pid_t pid = -1;
    std::string err_file;
};

// Starts envtrace with `args`; stderr goes to DIR/stderr.txt, stdout is dropped.
CliProcess start_envtrace(const std::vector<std::string>& args, const std::string& dir);
// Waits for it to end (SIGKILL after `timeout_seconds`) and reads its stderr back.
CliRun finish_envtrace(const CliProcess& p, int timeout_seconds = 60);

// Both: runs envtrace to the end.
CliRun run_envtrace(const std::vector<std::string>& args, const std::string& dir,
                    int timeout_seconds = 60);

} // namespace ett
