// A render's progress on stderr: a bar on a terminal, every tenth otherwise (logs stay short).
#pragma once

namespace et::cli {

class Progress {
  public:
    // `total` samples, or a time `limit` in seconds (> 0) that the bar follows instead.
    Progress(int total, double limit);
    // A noise target without --spp: progress towards the next check.
    void set_total(int total);
    void update(int done, double elapsed);
    void finish();

  private:
    int total_;
    double limit_;
    bool tty_;
    int last_decile_ = 0;
};

} // namespace et::cli
