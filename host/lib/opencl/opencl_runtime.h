// OpenCL devices, a context on one of them, and program builds from the embedded sources with a
// persistent on-disk cache of program binaries keyed by source, options and device.
#pragma once
#include <CL/opencl.hpp>

#include <string>
#include <vector>

namespace et {

struct DeviceEntry {
    cl::Platform platform;
    cl::Device device;
    std::string platform_name, device_name, device_version, driver_version;
    int compute_units = 0;
};

// Every device of every platform, in a stable order (the index is what --device takes). Throws
// et::Error with what to install when there is no platform or no device.
std::vector<DeviceEntry> list_devices();

struct ProgramBuildInfo {
    double seconds = 0.0;
    bool from_cache = false;
    std::string cache_file;
};

class ClRuntime {
  public:
    explicit ClRuntime(int device_index = 0);

    const DeviceEntry& device() const { return entry_; }
    cl::Context& context() { return context_; }
    cl::CommandQueue& queue() { return queue_; }

    // Builds kernels/<file> (includes expanded) with `options`, from the cache when it can.
    // Build errors throw et::Error carrying the compiler log (which names kernels/FILE:LINE).
    cl::Program build(const std::string& file, const std::string& options = "",
                      ProgramBuildInfo* info = nullptr);
    // The same for a source already expanded (`file` names it in messages and the cache).
    cl::Program build_source(const std::string& file, const std::string& source,
                             const std::string& options = "", ProgramBuildInfo* info = nullptr);

    // Where program binaries are cached: $ENVTRACE_CACHE_DIR, else $XDG_CACHE_HOME/envtrace,
    // else ~/.cache/envtrace.
    static std::string cache_dir();

  private:
    DeviceEntry entry_;
    cl::Context context_;
    cl::CommandQueue queue_;
};

// "CL_INVALID_VALUE (-30)" for an OpenCL error code.
std::string cl_error_name(cl_int code);

} // namespace et
