#include "progress.h"

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace et::cli {

Progress::Progress(int total, double limit)
    : total_(std::max(1, total)), limit_(limit), tty_(isatty(2)) {}

void Progress::set_total(int total) {
    total_ = std::max(1, total);
}

void Progress::update(int done, double elapsed) {
    const double frac = limit_ > 0 ? std::min(1.0, elapsed / limit_) : double(done) / total_;
    if (tty_) {
        const int width = 30, fill = static_cast<int>(frac * width);
        const double eta = frac > 0 ? elapsed * (1 - frac) / frac : 0;
        std::fprintf(stderr, "\r[%.*s%*s] %3d%%  %d spp  %.1fs  ETA %.1fs ", fill,
                     "##############################", width - fill, "", int(frac * 100), done,
                     elapsed, eta);
    } else if (int(frac * 10) > last_decile_) {
        last_decile_ = int(frac * 10);
        std::fprintf(stderr, "envtrace: %d%% (%d spp, %.1f s)\n", last_decile_ * 10, done, elapsed);
    }
}

void Progress::finish() {
    if (tty_)
        std::fprintf(stderr, "\n");
}

} // namespace et::cli
