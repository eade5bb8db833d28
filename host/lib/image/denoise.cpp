#include "image/denoise.h"

#include "image/oidn_library.h"
#include "util/error.h"

#include <cmath>
#include <memory>

namespace et {
namespace {

// OIDN's objects, released in reverse order of creation by their owners' destructors.
class Device {
  public:
    Device() : api_(oidn_api()), device_(api_.NewDevice(oidn::kDeviceDefault)) {
        if (!device_)
            throw Error("Open Image Denoise (" + oidn_library_file() + "): no device");
        api_.CommitDevice(device_);
        check("starting a device");
        const int version = api_.GetDeviceInt(device_, "version");
        if (version < 20000)
            throw Error(oidn_library_file() + ": Open Image Denoise " + version_text(version) +
                        ", envtrace needs 2.x");
    }
    ~Device() { api_.ReleaseDevice(device_); }
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    const oidn::Api& api() const { return api_; }
    oidn::Device get() const { return device_; }
    // Throws the device's pending error, if any, saying what was being done.
    void check(const char* doing) const {
        const char* message = nullptr;
        if (api_.GetDeviceError(device_, &message) != oidn::kErrorNone)
            throw Error(std::string("Open Image Denoise: ") + doing + ": " +
                        (message ? message : "unknown error"));
    }
    static std::string version_text(int v) {
        return std::to_string(v / 10000) + "." + std::to_string(v / 100 % 100) + "." +
               std::to_string(v % 100);
    }
    std::string version() const { return version_text(api_.GetDeviceInt(device_, "version")); }

  private:
    const oidn::Api& api_;
    oidn::Device device_;
};

// One image of RGB floats in the device's memory.
class Buffer {
  public:
    Buffer(const Device& d, const RgbImage& img)
        : api_(d.api()), w_(img.width), h_(img.height), buffer_(api_.NewBuffer(d.get(), bytes())) {
        d.check("allocating an image");
        api_.WriteBuffer(buffer_, 0, bytes(), img.rgb.data());
    }
    ~Buffer() {
        if (buffer_)
            api_.ReleaseBuffer(buffer_);
    }
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;

    size_t bytes() const { return static_cast<size_t>(w_) * h_ * 3 * sizeof(float); }
    void bind(oidn::Filter f, const char* name) const {
        api_.SetFilterImage(f, name, buffer_, oidn::kFormatFloat3, w_, h_, 0, 0, 0);
    }
    RgbImage read() const {
        RgbImage out{w_, h_, std::vector<float>(static_cast<size_t>(w_) * h_ * 3)};
        api_.ReadBuffer(buffer_, 0, bytes(), out.rgb.data());
        return out;
    }

  private:
    const oidn::Api& api_;
    int w_, h_;
    oidn::Buffer buffer_;
};

class Filter {
  public:
    explicit Filter(const Device& d) : d_(d), filter_(d.api().NewFilter(d.get(), "RT")) {
        d.check("creating the RT filter");
    }
    ~Filter() {
        if (filter_)
            d_.api().ReleaseFilter(filter_);
    }
    Filter(const Filter&) = delete;
    Filter& operator=(const Filter&) = delete;

    Filter& image(const char* name, const Buffer& b) {
        b.bind(filter_, name);
        return *this;
    }
    Filter& flag(const char* name, bool value) {
        d_.api().SetFilterBool(filter_, name, value);
        return *this;
    }
    void run(const char* doing) {
        d_.api().CommitFilter(filter_);
        d_.check(doing);
        d_.api().ExecuteFilter(filter_);
        d_.check(doing);
    }

  private:
    const Device& d_;
    oidn::Filter filter_;
};

void check_size(const RgbImage& img, const RgbImage& beauty, const char* what) {
    if (img.width != beauty.width || img.height != beauty.height ||
        img.rgb.size() != beauty.rgb.size())
        throw Error(std::string("denoise: the ") + what + " is " + std::to_string(img.width) + "x" +
                    std::to_string(img.height) + ", the beauty " + std::to_string(beauty.width) +
                    "x" + std::to_string(beauty.height) + ": the images must be of one size");
}

void check_inputs(const RgbImage& beauty, const RgbImage& albedo, const RgbImage& normal) {
    if (beauty.width <= 0 || beauty.height <= 0 ||
        beauty.rgb.size() != static_cast<size_t>(beauty.width) * beauty.height * 3)
        throw Error("denoise: the beauty must be a non-empty RGB image (" +
                    std::to_string(beauty.width) + "x" + std::to_string(beauty.height) + ", " +
                    std::to_string(beauty.rgb.size()) + " floats)");
    if (albedo.width > 0)
        check_size(albedo, beauty, "albedo");
    if (normal.width > 0) {
        if (albedo.width <= 0)
            throw Error("denoise: a normal image needs an albedo image too (Open Image Denoise "
                        "takes the normal only beside the albedo)");
        check_size(normal, beauty, "normal");
    }
}

// A guide (albedo or normal) denoised by its own filter, in place of its noisy self.
RgbImage prefilter(const Device& d, const RgbImage& guide, const char* name) {
    const Buffer in(d, guide), out(d, guide);
    Filter(d).image(name, in).image("output", out).run(name);
    return out.read();
}

} // namespace

RgbImage denoise(const RgbImage& beauty, const RgbImage& albedo, const RgbImage& normal,
                 const DenoiseOptions& o) {
    check_inputs(beauty, albedo, normal);
    RgbImage colour = beauty;
    for (float& v : colour.rgb)
        v = std::isfinite(v) ? v : 0.0f;
    const Device d;
    const bool guided = albedo.width > 0, prefiltered = guided && o.prefilter_guides;
    const bool with_normal = normal.width > 0;
    const RgbImage a = prefiltered ? prefilter(d, albedo, "albedo") : albedo;
    const RgbImage n = prefiltered && with_normal ? prefilter(d, normal, "normal") : normal;
    const Buffer in(d, colour), out(d, colour);
    Filter f(d);
    f.image("color", in).image("output", out).flag("hdr", o.hdr);
    std::unique_ptr<Buffer> albedo_buffer, normal_buffer;
    if (guided)
        f.image("albedo", *(albedo_buffer = std::make_unique<Buffer>(d, a)));
    if (with_normal)
        f.image("normal", *(normal_buffer = std::make_unique<Buffer>(d, n)));
    f.flag("cleanAux", prefiltered).run("denoising the image");
    return out.read();
}

std::string check_denoiser() {
    const Device d;
    return "Open Image Denoise " + d.version() + " (" + oidn_library_file() + ")";
}

} // namespace et
