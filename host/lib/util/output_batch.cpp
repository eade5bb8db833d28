#include "util/output_batch.h"

#include "util/error.h"
#include "util/input_files.h"
#include "util/signal_cleanup.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cerrno>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <pthread.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>
#include <xxhash.h>

namespace fs = std::filesystem;

namespace et {
namespace {

std::string folder_of(const std::string& target) {
    const fs::path dir = fs::path(target).parent_path();
    return dir.empty() ? std::string(".") : dir.string();
}

bool same_file(const std::string& a, const std::string& b) {
    struct stat sa, sb;
    if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0)
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    // Neither exists yet: compare the names with the folders resolved.
    std::error_code ec1, ec2;
    const fs::path ca = fs::weakly_canonical(a, ec1), cb = fs::weakly_canonical(b, ec2);
    return !ec1 && !ec2 && ca == cb;
}

// Holds SIGINT, SIGTERM and SIGHUP back while the renames run (they arrive afterwards).
class SignalHold {
  public:
    SignalHold() {
        sigset_t set;
        sigemptyset(&set);
        sigaddset(&set, SIGINT);
        sigaddset(&set, SIGTERM);
        sigaddset(&set, SIGHUP);
        pthread_sigmask(SIG_BLOCK, &set, &old_);
    }
    ~SignalHold() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }

  private:
    sigset_t old_;
};

} // namespace

namespace {

// ".NAME.tmp" of a target: NAME is cut short (at a UTF-8 character's start) when the
// temporary's file name, with up to 10 digits of a process id and the extension, would pass the
// 255 bytes a file name can have: a target whose own name fits always gets a temporary.
std::string temporary_prefix(const fs::path& p) {
    std::string stem = p.stem().string();
    const size_t room = 255 - std::min<size_t>(255, 1 + 4 + 10 + p.extension().string().size());
    if (stem.size() > room) {
        // Cut names end with 8 hex digits of the whole name's hash: two targets that differ
        // only past the cut had one temporary, and one output's bytes went to the other.
        char tag[10];
        std::snprintf(tag, sizeof tag, "~%08x",
                      static_cast<unsigned>(XXH3_64bits(stem.data(), stem.size())));
        size_t cut = room > 9 ? room - 9 : 0;
        while (cut > 0 && (static_cast<unsigned char>(stem[cut]) & 0xC0) == 0x80)
            --cut;
        stem.resize(cut);
        stem += tag;
    }
    return "." + stem + ".tmp";
}

// Exclusive flock()s on the folders of a batch's targets, taken in one order (device, inode) and
// held while the batch renames its files into place: another envtrace committing outputs of the
// same names waits, so that each set lands whole -- two renders to one name leave one render's
// image, preview, stats and state, never a mix. Best effort: a folder that cannot be opened or
// locked (a file system without flock) is renamed into without.
class FolderLocks {
  public:
    template <class Entries> explicit FolderLocks(const Entries& entries) {
        std::vector<std::pair<std::pair<dev_t, ino_t>, std::string>> folders;
        for (const auto& e : entries) {
            const std::string dir = folder_of(e.target);
            struct stat st {};
            if (::stat(dir.c_str(), &st) == 0)
                folders.push_back({{st.st_dev, st.st_ino}, dir});
        }
        std::sort(folders.begin(), folders.end());
        folders.erase(std::unique(folders.begin(), folders.end(),
                                  [](const auto& a, const auto& b) { return a.first == b.first; }),
                      folders.end());
        for (const auto& f : folders) {
            const int fd = ::open(f.second.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
            if (fd < 0)
                continue;
            int r;
            do
                r = ::flock(fd, LOCK_EX);
            while (r != 0 && errno == EINTR);
            if (r != 0) {
                ::close(fd);
                continue;
            }
            fds_.push_back(fd);
        }
    }
    ~FolderLocks() {
        for (int fd : fds_)
            ::close(fd); // releases the lock
    }
    FolderLocks(const FolderLocks&) = delete;
    FolderLocks& operator=(const FolderLocks&) = delete;

  private:
    std::vector<int> fds_;
};

} // namespace

void check_output_folder(const std::string& target) {
    const std::string dir = folder_of(target);
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw Error(target + ": cannot write: " +
                    (fs::exists(dir, ec) ? "'" + dir + "' is not a folder"
                                         : "folder '" + dir + "' does not exist"));
}

// What an old output kept aside during a commit is named: its target's temporary + this.
const std::string kAside = ".previous";

std::string temporary_path(const std::string& target, long pid) {
    const fs::path p(target);
    return (fs::path(folder_of(target)) /
            (temporary_prefix(p) + std::to_string(pid) + p.extension().string()))
        .string();
}

int remove_stale_temporaries(const std::string& target) {
    const fs::path p(target);
    const std::string prefix = temporary_prefix(p), suffix = p.extension().string();
    std::error_code ec;
    fs::directory_iterator it(folder_of(target), ec), end;
    int removed = 0;
    for (; !ec && it != end; it.increment(ec)) {
        std::string name = it->path().filename().string();
        auto is_temporary = [&](const std::string& n) {
            return n.size() > prefix.size() + suffix.size() &&
                   !n.compare(0, prefix.size(), prefix) &&
                   !n.compare(n.size() - suffix.size(), suffix.size(), suffix);
        };
        // A commit killed between keeping an old output aside and dropping it leaves the aside
        // link (temporary + ".previous"): the dead process's too. (A target named *.previous
        // has temporaries of that extension: they match as they are.)
        if (!is_temporary(name) && name.size() > kAside.size() &&
            !name.compare(name.size() - kAside.size(), kAside.size(), kAside))
            name.resize(name.size() - kAside.size());
        if (!is_temporary(name))
            continue;
        const std::string digits =
            name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
        if (digits.empty() || digits.size() > 9 ||
            digits.find_first_not_of("0123456789") != std::string::npos)
            continue;
        const long pid = std::stol(digits);
        // A live process (this one, or another render writing the same output) keeps its file.
        if (pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)
            continue;
        std::error_code rm;
        if (it->is_regular_file(rm) && fs::remove(it->path(), rm))
            ++removed;
    }
    return removed;
}

OutputBatch::OutputBatch(const std::vector<std::string>& targets,
                         const std::vector<std::string>& may_replace) {
    for (const auto& t : targets) {
        std::error_code ec;
        if (t.empty())
            throw Error("an output path is empty");
        if (fs::is_directory(t, ec))
            throw Error(t + ": cannot write: it is a folder");
        check_output_folder(t);
        bool replaceable = false;
        for (const auto& m : may_replace)
            replaceable = replaceable || same_file(t, m);
        const std::string input = input_file_named(t);
        if (!input.empty() && !replaceable)
            throw Error(t + ": refusing to write an output over " + input +
                        ", an input of this run; choose another output name");
        for (const auto& e : entries_)
            if (same_file(e.target, t))
                throw Error(t + ": two outputs of this run would be the same file ('" + e.target +
                            "' and '" + t + "')");
        entries_.push_back({t, temporary_path(t, ::getpid())});
    }
    for (const auto& e : entries_)
        remove_stale_temporaries(e.target);
    for (const auto& e : entries_) // a signal ending the process removes them too
        register_temporary(e.temporary);
}

OutputBatch::~OutputBatch() {
    if (committed_)
        return;
    for (const auto& e : entries_) {
        std::error_code ec;
        fs::remove(e.temporary, ec);
        unregister_temporary(e.temporary);
    }
}

void OutputBatch::write(const std::string& target,
                        const std::function<void(const std::string&)>& writer) {
    for (auto& e : entries_)
        if (e.target == target) {
            std::error_code ec;
            fs::remove(e.temporary, ec);
            e.written = false;
            writer(e.temporary);
            if (!fs::is_regular_file(e.temporary, ec))
                throw Error(target + ": cannot write: the writer left no file");
            e.written = true;
            return;
        }
    throw Error(target + ": not an output reserved by this batch (a bug)");
}

void OutputBatch::commit() {
    for (const auto& e : entries_)
        if (!e.written)
            throw Error(e.target + ": was not written (a bug)");
    SignalHold hold;
    CommitInProgress committing; // a signal taken by another thread waits for the renames
    FolderLocks locks(entries_);
    // All or nothing: a target that became a folder is refused before anything moves, and the
    // files a failed rename would leave replaced are kept aside (hard links) and put back, so a
    // failed run leaves the previous outputs as they were.
    for (const auto& e : entries_) {
        std::error_code ec;
        if (fs::is_directory(fs::symlink_status(e.target, ec)))
            throw Error(e.target + ": cannot write: it is a folder");
    }
    std::vector<std::string> kept(entries_.size());
    std::vector<bool> existed(entries_.size(), false);
    for (size_t i = 0; i < entries_.size(); ++i) {
        std::error_code ec;
        existed[i] = fs::exists(fs::symlink_status(entries_[i].target, ec));
        if (!existed[i])
            continue;
        const std::string aside = entries_[i].temporary + kAside;
        fs::remove(aside, ec);
        fs::create_hard_link(entries_[i].target, aside, ec);
        if (!ec)
            kept[i] = aside; // else no hard links here: that one cannot be put back
    }
    auto drop_kept = [&] {
        for (const auto& k : kept)
            if (!k.empty()) {
                std::error_code ec;
                fs::remove(k, ec);
            }
    };
    for (size_t i = 0; i < entries_.size(); ++i) {
        std::error_code ec;
        fs::rename(entries_[i].temporary, entries_[i].target, ec);
        if (!ec)
            continue;
        for (size_t j = 0; j < i; ++j) { // back as they were
            std::error_code back;
            if (!kept[j].empty()) {
                fs::rename(kept[j], entries_[j].target, back);
                kept[j].clear();
            } else if (!existed[j]) {
                fs::remove(entries_[j].target, back);
            }
        }
        drop_kept();
        throw Error(entries_[i].target + ": cannot write: " + ec.message());
    }
    drop_kept();
    committed_ = true;
    for (const auto& e : entries_)
        unregister_temporary(e.temporary);
}

} // namespace et
