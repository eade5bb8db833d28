#include "cli_run.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace ett {

bool CliRun::exited() const {
    return !timed_out && WIFEXITED(status);
}
int CliRun::code() const {
    return WEXITSTATUS(status);
}

CliProcess start_envtrace(const std::vector<std::string>& args, const std::string& dir) {
    CliProcess p;
    p.err_file = dir + "/stderr.txt";
    p.pid = fork();
    if (p.pid == 0) {
        std::vector<char*> argv{const_cast<char*>(ENVTRACE_EXE)};
        for (const auto& a : args)
            argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        if (!freopen(p.err_file.c_str(), "w", stderr) || !freopen("/dev/null", "w", stdout))
            _exit(126);
        execv(ENVTRACE_EXE, argv.data());
        _exit(127);
    }
    return p;
}

CliRun finish_envtrace(const CliProcess& p, int timeout_seconds) {
    CliRun r;
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
        if (waitpid(p.pid, &r.status, WNOHANG) == p.pid)
            break;
        if (std::chrono::steady_clock::now() - start > std::chrono::seconds(timeout_seconds)) {
            kill(p.pid, SIGKILL);
            waitpid(p.pid, &r.status, 0);
            r.timed_out = true;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    std::ifstream in(p.err_file);
    r.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return r;
}

CliRun run_envtrace(const std::vector<std::string>& args, const std::string& dir,
                    int timeout_seconds) {
    return finish_envtrace(start_envtrace(args, dir), timeout_seconds);
}

} // namespace ett
