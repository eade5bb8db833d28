#include "util/file_check.h"
#include "util/input_files.h"

#include "util/error.h"

#include <cctype>
#include <cerrno>
#include <filesystem>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace et {
namespace {

std::string kind_of(mode_t mode) {
    if (S_ISDIR(mode))
        return "a folder";
    if (S_ISFIFO(mode))
        return "a FIFO (named pipe)";
    if (S_ISCHR(mode))
        return "a character device";
    if (S_ISBLK(mode))
        return "a block device";
    if (S_ISSOCK(mode))
        return "a socket";
    return "not a regular file";
}

uint64_t check_stat(const std::string& path, const struct stat& st, uint64_t max_bytes,
                    const char* what) {
    if (!S_ISREG(st.st_mode))
        throw Error(path + ": " + what + " is " + kind_of(st.st_mode) +
                    ", not a regular file (only regular files are read)");
    const uint64_t size = static_cast<uint64_t>(st.st_size);
    if (size > max_bytes)
        throw Error(path + ": " + what + " is " + byte_text(size) + ", more than the " +
                    byte_text(max_bytes) + " read at most");
    note_input_file(path, what, static_cast<unsigned long long>(st.st_dev),
                    static_cast<unsigned long long>(st.st_ino));
    return size;
}

std::string errno_text(int err) {
    return err ? std::strerror(err) : "unknown error";
}

} // namespace

std::string byte_text(uint64_t bytes) {
    char buf[64];
    if (bytes < kMiB)
        std::snprintf(buf, sizeof buf, "%llu bytes", static_cast<unsigned long long>(bytes));
    else if (bytes < kGiB)
        std::snprintf(buf, sizeof buf, "%.1f MiB", static_cast<double>(bytes) / kMiB);
    else
        std::snprintf(buf, sizeof buf, "%.1f GiB", static_cast<double>(bytes) / kGiB);
    return buf;
}

uint64_t check_regular_file(const std::string& path, uint64_t max_bytes, const char* what) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        if (err == ENOENT || err == ENOTDIR)
            throw Error(path + ": no such file");
        throw Error(path + ": cannot open: " + errno_text(err));
    }
    return check_stat(path, st, max_bytes, what);
}

std::string read_regular_file(const std::string& path, uint64_t max_bytes, const char* what) {
    check_regular_file(path, max_bytes, what);
    // O_NONBLOCK: opening a FIFO swapped in after the check returns at once instead of waiting
    // for a writer; fstat on the descriptor then refuses it.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        throw Error(path + ": cannot open: " + errno_text(err));
    }
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat st;
    if (::fstat(fd, &st) != 0) {
        const int err = errno;
        throw Error(path + ": cannot read: " + errno_text(err));
    }
    const uint64_t size = check_stat(path, st, max_bytes, what);
    std::string text;
    text.resize(static_cast<size_t>(size));
    size_t got = 0;
    for (;;) {
        if (got == text.size()) {
            if (text.size() >= max_bytes) {
                // At the cap: one more byte means the file grew past it.
                char extra;
                const ssize_t n = ::read(fd, &extra, 1);
                if (n > 0)
                    throw Error(path + ": " + what + " is more than the " + byte_text(max_bytes) +
                                " read at most");
                break;
            }
            text.resize(std::min<uint64_t>(max_bytes, text.size() + 65536));
        }
        const ssize_t n = ::read(fd, &text[got], text.size() - got);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            const int err = errno;
            throw Error(path + ": cannot read: " + errno_text(err));
        }
        if (n == 0)
            break;
        got += static_cast<size_t>(n);
    }
    text.resize(got);
    return text;
}

std::string read_text_file(const std::string& path, uint64_t max_bytes, const char* what) {
    std::string text = read_regular_file(path, max_bytes, what);
    auto starts = [&](const char* bom, size_t n) { return text.compare(0, n, bom, n) == 0; };
    // The encoding as iconv names it (a BOM-less UTF-16 guessed from ASCII's NUL bytes).
    const char* wide = starts("\x00\x00\xFE\xFF", 4)   ? "UTF-32BE"
                       : starts("\xFF\xFE\x00\x00", 4) ? "UTF-32LE"
                       : starts("\xFE\xFF", 2)         ? "UTF-16BE"
                       : starts("\xFF\xFE", 2)         ? "UTF-16LE"
                                                       : nullptr;
    if (!wide && text.size() >= 4) {
        const bool z[4] = {text[0] == '\0', text[1] == '\0', text[2] == '\0', text[3] == '\0'};
        if (z[0] && !z[1] && z[2] && !z[3])
            wide = "UTF-16BE";
        else if (!z[0] && z[1] && !z[2] && z[3])
            wide = "UTF-16LE";
    }
    if (wide)
        throw Error(path + ": the " + what + " is " + wide +
                    " text; save it as UTF-8 (or ASCII), e.g. iconv -f " + wide +
                    " -t UTF-8 IN > OUT");
    if (starts("\xEF\xBB\xBF", 3))
        text.erase(0, 3);
    return text;
}

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) // ASCII only: std::tolower of a negative char is undefined
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

} // namespace et
