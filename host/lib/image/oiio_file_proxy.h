// A read-only OpenImageIO IOProxy over a file with a buffer of its own, and the positioned reads
// under it (the Radiance reader's input, oiio_reader.cpp).
#pragma once
#include <OpenImageIO/filesystem.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fcntl.h>
#include <string>
#include <unistd.h>
#include <vector>

namespace et::image_detail {

// Up to `size` bytes at `offset`, retrying short reads and EINTR; fewer only at the end of the
// file or on an error.
inline size_t pread_full(int fd, void* buf, size_t size, int64_t offset) {
    size_t done = 0;
    while (fd >= 0 && offset >= 0 && done < size) {
        const ssize_t n = ::pread(fd, static_cast<char*>(buf) + done, size - done,
                                  static_cast<off_t>(offset + static_cast<int64_t>(done)));
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        done += static_cast<size_t>(n);
    }
    return done;
}

// A read-only IOProxy over a file, with a buffer of its own. OpenImageIO's Radiance HDR reader
// asks for 2 bytes per RLE run; through its default proxy each request is an fread, and those
// cost more than the decoding (a 16384x8192 map has tens of millions of runs).
class BufferedFileProxy final : public OIIO::Filesystem::IOProxy {
  public:
    BufferedFileProxy(const std::string& path, uint64_t size)
        : IOProxy(path, Read), size_(size), buf_(1 << 20) {
        fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd_ < 0)
            m_mode = Closed;
    }
    ~BufferedFileProxy() override { close(); }
    const char* proxytype() const override { return "envtrace-buffered-file"; }
    void close() override {
        if (fd_ >= 0)
            ::close(fd_);
        fd_ = -1;
        m_mode = Closed;
    }
    size_t size() const override { return size_; }
    size_t read(void* buf, size_t size) override {
        char* dst = static_cast<char*>(buf);
        size_t done = 0;
        while (done < size) {
            if (m_pos >= buf_at_ && m_pos < buf_at_ + static_cast<int64_t>(buf_len_)) {
                const size_t at = static_cast<size_t>(m_pos - buf_at_);
                const size_t n = std::min(size - done, buf_len_ - at);
                std::memcpy(dst + done, buf_.data() + at, n);
                m_pos += static_cast<int64_t>(n);
                done += n;
            } else if (size - done >= buf_.size()) {
                const size_t n = pread(dst + done, size - done, m_pos);
                m_pos += static_cast<int64_t>(n);
                done += n;
                break;
            } else {
                buf_at_ = m_pos;
                buf_len_ = pread(buf_.data(), buf_.size(), m_pos);
                if (buf_len_ == 0)
                    break;
            }
        }
        return done;
    }
    // Unbuffered, so that concurrent calls stay safe as IOProxy promises.
    size_t pread(void* buf, size_t size, int64_t offset) override {
        return pread_full(fd_, buf, size, offset);
    }
    size_t write(const void*, size_t) override { return 0; }
    size_t pwrite(const void*, size_t, int64_t) override { return 0; }

  private:
    int fd_ = -1;
    uint64_t size_;
    std::vector<char> buf_;
    int64_t buf_at_ = 0; // file offset of buf_[0]
    size_t buf_len_ = 0;
};

} // namespace et::image_detail
