// SIGINT and SIGTERM while a render runs. The first asks it to stop: the render abandons the
// pass in flight at its next bounce (but for the first, finished so that there is an image) and
// writes the whole passes it has. A second one (of either) ends the process at once with
// status 128 + signal, writing nothing more; outputs are written all-or-nothing
// (util/output_batch.h), so none is ever left half-written.
#pragma once

namespace et {

class InterruptHandler {
  public:
    // Installs the handlers (SIGINT, SIGTERM); the destructor restores the previous ones.
    InterruptHandler();
    ~InterruptHandler();
    InterruptHandler(const InterruptHandler&) = delete;
    InterruptHandler& operator=(const InterruptHandler&) = delete;

    // The first signal received since the handlers were installed, or 0.
    static int signal();
};

// "SIGINT", "SIGTERM", ...
const char* signal_name(int sig);

} // namespace et
