// Outputs written all-or-nothing. Each file is first written to a hidden temporary beside its
// target, ".NAME.tmpPID.EXT" (the same folder, so the rename is atomic; the same extension, so
// writers pick the format from it). Only when every file of the batch has been written are they
// renamed into place, with SIGINT, SIGTERM and SIGHUP held back and the targets' folders locked
// (flock: another process's batch of the same names lands whole before or after, never mixed
// with this one); a batch that is abandoned (an error, an exception) removes its temporaries, and
// a run killed outright leaves temporaries that the next batch naming the same targets removes.
#pragma once
#include <functional>
#include <string>
#include <vector>

namespace et {

class OutputBatch {
  public:
    // Reserves the targets. Throws et::Error naming the path unless each can be written: its
    // folder exists, it is not a folder, it is not a file this process read as input (see
    // util/input_files.h) unless listed in `may_replace`, and no two targets are the same file.
    // Removes stale temporaries of the targets left by processes that no longer run.
    explicit OutputBatch(const std::vector<std::string>& targets,
                         const std::vector<std::string>& may_replace = {});
    ~OutputBatch();
    OutputBatch(const OutputBatch&) = delete;
    OutputBatch& operator=(const OutputBatch&) = delete;

    // Writes one target: `writer` receives the temporary's path and writes the whole file there
    // (throwing on failure). The target must be one of those reserved.
    void write(const std::string& target, const std::function<void(const std::string&)>& writer);
    // Renames every written temporary into place. Throws et::Error if a target was not written.
    void commit();

  private:
    struct Entry {
        std::string target, temporary;
        bool written = false;
    };
    std::vector<Entry> entries_;
    bool committed_ = false;
};

// Throws et::Error naming `target` unless its folder exists (and is a folder).
void check_output_folder(const std::string& target);

// The temporary of `target` for process `pid`: "dir/.NAME.tmpPID.EXT".
std::string temporary_path(const std::string& target, long pid);

// Removes "dir/.NAME.tmpPID.EXT" files of `target` whose process is gone; returns how many.
int remove_stale_temporaries(const std::string& target);

} // namespace et
