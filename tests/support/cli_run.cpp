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

CliRun run_envtrace(const std::vector<std::string>& args, const std::string& dir,
                    int timeout_seconds) {
    const std::string err_file = dir + "/stderr.txt";
    const pid_t pid = fork();
    if (pid == 0) {
        std::vector<char*> argv{const_cast<char*>(ENVTRACE_EXE)};
        for (const auto& a : args)
            argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        if (!freopen(err_file.c_str(), "w", stderr) || !freopen("/dev/null", "w", stdout))
            _exit(126);
        execv(ENVTRACE_EXE, argv.data());
        _exit(127);
    }
    CliRun r;
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
        if (waitpid(pid, &r.status, WNOHANG) == pid)
            break;
        if (std::chrono::steady_clock::now() - start > std::chrono::seconds(timeout_seconds)) {
            kill(pid, SIGKILL);
            waitpid(pid, &r.status, 0);
            r.timed_out = true;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    std::ifstream in(err_file);
    r.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return r;
}

} // namespace ett
