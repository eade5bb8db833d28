// Images written through OpenImageIO (image_library.h): 8-bit previews encoded in memory and
// written with every write checked, float formats by their writers.
#include "image/image_library.h"
#include "util/error.h"
#include "util/file_check.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

OIIO_NAMESPACE_USING

namespace et::image_detail {

// The bytes into `file`, every write() and the close() checked (a full disk is an error).
static void write_bytes_checked(const std::string& path, const std::string& file,
                                const std::vector<unsigned char>& bytes) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    auto fail = [&](int err) { throw Error(path + ": cannot write: " + std::strerror(err)); };
    if (fd < 0)
        fail(errno);
    size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            const int err = n < 0 ? errno : ENOSPC;
            ::close(fd);
            fail(err);
        }
        done += static_cast<size_t>(n);
    }
    if (::close(fd) != 0)
        fail(errno);
}

void check_library_writer(const std::string& path, const std::string& ext) {
    auto out = ImageOutput::create(ext.substr(1));
    if (!out)
        throw Error(path + ": cannot write: this OpenImageIO build has no writer for '" + ext +
                    "'");
}

void write_with_library(const std::string& path, const std::string& file, int width, int height,
                        int channels, const float* pixels, bool floating,
                        const std::vector<std::pair<std::string, std::string>>& attributes,
                        const std::vector<std::string>* names) {
    auto out = ImageOutput::create(file);
    if (!out)
        throw Error(path + ": cannot write: " + one_line(OIIO::geterror()));
    ImageSpec spec(width, height, channels, floating ? TypeDesc::FLOAT : TypeDesc::UINT8);
    if (lower_extension(path) == ".exr")
        spec.attribute("compression", "zip");
    if (names) {
        spec.channelnames = *names;
        spec.alpha_channel = -1; // no channel is alpha: the layers are alpha-free
        spec.z_channel = -1;
        for (int c = 0; c < channels; ++c)
            if ((*names)[static_cast<size_t>(c)] == "Z")
                spec.z_channel = c;
    }
    for (const auto& [k, v] : attributes)
        spec.attribute(k, v);
    // 8-bit previews are encoded in memory and written here: OpenImageIO's PNG writer reports
    // no error when the disk fills (libpng's fwrite results go unchecked), and committed a
    // truncated preview with exit status 0. The float formats' writers report it.
    std::vector<unsigned char> encoded;
    Filesystem::IOVecOutput memory(encoded);
    const bool in_memory = !floating && out->supports("ioproxy") && out->set_ioproxy(&memory);
    const bool ok = out->open(in_memory ? path : file, spec) &&
                    out->write_image(TypeDesc::FLOAT, pixels) && out->close();
    if (!ok)
        throw Error(path + ": cannot write: " + one_line(out->geterror()));
    if (in_memory)
        write_bytes_checked(path, file, encoded);
}

} // namespace et::image_detail
