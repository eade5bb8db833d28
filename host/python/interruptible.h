// Long library calls with the GIL released and Ctrl-C kept working: Python runs its signal
// handlers on the main thread only when that thread checks for them, so the work runs on a
// thread of its own while the caller's thread checks every few milliseconds.
#pragma once
#include "bindings.h"

#include <chrono>
#include <future>

namespace et::py_bind {

// Runs `work` on a new thread with the GIL released, checking for signals meanwhile. A pending
// KeyboardInterrupt (or any exception a handler raises) calls `stop`, waits for `work` to
// return and is raised then; `work`'s own exception is rethrown here.
template <class Work, class Stop> void run_interruptible(Work&& work, Stop&& stop) {
    std::future<void> done;
    {
        py::gil_scoped_release free;
        done = std::async(std::launch::async, std::forward<Work>(work));
    }
    for (;;) {
        {
            py::gil_scoped_release free;
            if (done.wait_for(std::chrono::milliseconds(20)) == std::future_status::ready)
                break;
        }
        if (PyErr_CheckSignals() != 0) { // the handler raised: stop, keep the film, re-raise
            py::error_already_set raised;
            stop();
            {
                py::gil_scoped_release free;
                done.wait();
            }
            throw raised;
        }
    }
    done.get();
}

} // namespace et::py_bind
