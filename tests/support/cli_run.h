// Running build/envtrace as a child process: exit status, stderr, and a time limit that turns a
// hang into a failure instead of a stuck suite.
#pragma once
#include <string>
#include <vector>

namespace ett {

struct CliRun {
    int status = 0; // as from waitpid
    bool timed_out = false;
    std::string err; // everything written to stderr
    bool exited() const;
    int code() const;
};

// Runs envtrace with `args`; stderr goes to DIR/stderr.txt (read back into err), stdout is dropped.
CliRun run_envtrace(const std::vector<std::string>& args, const std::string& dir,
                    int timeout_seconds = 60);

} // namespace ett
