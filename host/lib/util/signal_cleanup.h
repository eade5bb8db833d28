// Temporaries that a signal ending the process must not leave behind. OutputBatch registers its
// temporaries here while it holds them; SIGINT, SIGTERM or SIGHUP ending the process (their
// default action, or `render`'s second signal, util/interrupt.h) removes them first. SIGKILL
// cannot be caught: the next run naming the same outputs removes what it leaves
// (util/output_batch.h).
#pragma once
#include <string>

namespace et {

// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove the registered files and then
// end the process by the signal, as its default action would (status 128 + signal).
void install_signal_cleanup();

// At most kSignalCleanupSlots files at once (a path of up to 4095 bytes); beyond, a file is
// left for the next run to remove.
constexpr int kSignalCleanupSlots = 64;
void register_temporary(const std::string& path);
void unregister_temporary(const std::string& path);

// Removes every registered file; async-signal-safe (unlink only).
void remove_registered_temporaries();

// Held over an output batch's renames (OutputBatch::commit). The committing thread blocks the
// signals, but another thread of the process (OpenCL's, MPI's) may take one: a signal that would
// end the process then waits until the renames are done, so that a set of outputs lands whole,
// and ends it there (ending_signal_deferred).
class CommitInProgress {
  public:
    CommitInProgress();
    ~CommitInProgress(); // ends the process by a signal that arrived meanwhile
    CommitInProgress(const CommitInProgress&) = delete;
    CommitInProgress& operator=(const CommitInProgress&) = delete;
};

// For a handler about to end the process by `sig`: true where a commit is in progress, which
// then ends it by that signal once its renames are done (async-signal-safe).
bool ending_signal_deferred(int sig);

} // namespace et
