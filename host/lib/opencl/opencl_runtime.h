// OpenCL devices, a context on one of them, and program builds from the embedded sources with a
// persistent on-disk cache of program binaries keyed by source, options and device.
#pragma once
#include <CL/opencl.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace et {

// What envtrace needs to know of a device before it allocates or launches anything.
struct DeviceLimits {
    uint64_t max_alloc = 0;     // CL_DEVICE_MAX_MEM_ALLOC_SIZE
    uint64_t global_mem = 0;    // CL_DEVICE_GLOBAL_MEM_SIZE
    size_t max_work_group = 0;  // CL_DEVICE_MAX_WORK_GROUP_SIZE
    size_t max_work_item_x = 0; // CL_DEVICE_MAX_WORK_ITEM_SIZES[0]
    bool little_endian = true;  // CL_DEVICE_ENDIAN_LITTLE
    bool host_unified = false;  // CL_DEVICE_HOST_UNIFIED_MEMORY: reads host memory in place
    bool cpu = false;           // CL_DEVICE_TYPE_CPU (LightBatch::automatic batches there)
    // CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT in CL_DEVICE_SINGLE_FP_CONFIG: programs are then built
    // with -cl-fp32-correctly-rounded-divide-sqrt, so that x / y and sqrt round as on the host
    // (OpenCL otherwise allows 2.5 and 3 ulp, and NVIDIA's driver uses that latitude).
    bool correctly_rounded_div_sqrt = false;
};

// The device's limits; ENVTRACE_CL_MAX_ALLOC and ENVTRACE_CL_GLOBAL_MEM (bytes) lower the two
// memory limits, to exercise the checks below as on a smaller device.
DeviceLimits query_device_limits(const cl::Device& device);

// Refuses a device envtrace cannot run on (big-endian: integers travel inside float buffers and
// kernel arguments in the host's byte order), with a message naming it.
void check_device_usable(const DeviceLimits& limits, const std::string& device_name);

// One device buffer about to be allocated: its name (kernels/path_state.h) and size.
struct BufferRequest {
    std::string name;
    uint64_t bytes = 0;
};
// Checks every buffer against the device's largest allocation and their sum against its global
// memory, before anything is allocated; throws et::Error naming the buffer and the sizes.
void check_buffer_sizes(const std::vector<BufferRequest>& buffers, const DeviceLimits& limits,
                        const std::string& device_name);

// The work-group size for a kernel: the largest size <= target that the kernel and device
// allow (CL_KERNEL_WORK_GROUP_SIZE, device limits), rounded down to the kernel's preferred
// multiple when that fits.
size_t choose_local_size(size_t kernel_max, size_t preferred_multiple, const DeviceLimits& limits,
                         size_t target = 64);
size_t choose_local_size(const cl::Kernel& kernel, const cl::Device& device,
                         const DeviceLimits& limits, size_t target = 64);

struct DeviceEntry {
    cl::Platform platform;
    cl::Device device;
    std::string platform_name, device_name, device_version, driver_version;
    int compute_units = 0;
};

// Every device of every platform, in a stable order (the index is what --device takes). When
// ENVTRACE_CL_PLATFORM is set, only the platforms whose name contains it (case-insensitive), e.g.
// ENVTRACE_CL_PLATFORM=oclgrind. Throws et::Error with what to install when there is no platform
// or no device, and with the platforms' names when none matches.
std::vector<DeviceEntry> list_devices();

struct ProgramBuildInfo {
    double seconds = 0.0;
    bool from_cache = false;
    std::string cache_file;
    // The compiler's log of a build from source (its warnings; kernels/FILE:LINE locations), ""
    // for a cached binary. ENVTRACE_CL_BUILD_LOG=1 prints it.
    std::string log;
};

class ClRuntime {
  public:
    explicit ClRuntime(int device_index = 0);

    const DeviceEntry& device() const { return entry_; }
    const DeviceLimits& limits() const { return limits_; }
    cl::Context& context() { return context_; }
    cl::CommandQueue& queue() { return queue_; }
    // Oclgrind's simulator: its interpreter has quirks of its own (one kernel at a time, no
    // llvm.experimental.noalias.scope.decl) that the renderer works around.
    bool is_oclgrind() const;

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
    DeviceLimits limits_;
    cl::Context context_;
    cl::CommandQueue queue_;
};

// "CL_INVALID_VALUE (-30)" for an OpenCL error code.
std::string cl_error_name(cl_int code);

} // namespace et
