#include "opencl/opencl_runtime.h"

#include "util/error.h"
#include "opencl/kernel_sources.h"
#include "util/file_check.h"
#include "util/timer.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace et {
namespace {

const char* kInstallHint =
    "install an OpenCL driver and the ICD loader, e.g. on Debian/Ubuntu: "
    "apt-get install pocl-opencl-icd ocl-icd-libopencl1 (tools/setup does this)";

// Two independent 64-bit FNV-1a hashes: a 128-bit cache key.
std::string cache_key(const std::string& text) {
    uint64_t a = 0xcbf29ce484222325ull, b = 0x84222325cbf29ce4ull;
    for (unsigned char c : text) {
        a = (a ^ c) * 0x100000001b3ull;
        b = (b ^ c) * 0x00000100000001b3ull + 0x9e3779b97f4a7c15ull;
    }
    char buf[40];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", (unsigned long long)a, (unsigned long long)b);
    return buf;
}

std::string build_log(const cl::Program& program, const cl::Device& device) {
    try {
        return program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device);
    } catch (const cl::Error&) {
        return "(no build log)";
    }
}

std::string lower(std::string s) {
    for (char& c : s)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

// A positive byte count from the environment variable `name` (a testing hook), else 0.
uint64_t env_bytes(const char* name) {
    const char* v = std::getenv(name);
    if (!v || !*v)
        return 0;
    char* end = nullptr;
    errno = 0;
    // Digits only: strtoull would take "-5" as 2^64 - 5, and "1e9" stops at the e.
    const bool digits = std::isdigit(static_cast<unsigned char>(v[0])) != 0;
    const unsigned long long x = std::strtoull(v, &end, 10);
    if (!digits || *end != '\0' || x == 0 || errno == ERANGE)
        throw Error(std::string(name) + ": expected a positive number of bytes, got '" + v + "'");
    return x;
}

std::string bytes_text(uint64_t bytes) {
    return std::to_string(bytes) + " bytes (" + byte_text(bytes) + ")";
}

} // namespace

DeviceLimits query_device_limits(const cl::Device& device) {
    DeviceLimits l;
    l.max_alloc = device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
    l.global_mem = device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
    l.max_work_group = device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
    const std::vector<size_t> items = device.getInfo<CL_DEVICE_MAX_WORK_ITEM_SIZES>();
    l.max_work_item_x = items.empty() ? l.max_work_group : items[0];
    l.little_endian = device.getInfo<CL_DEVICE_ENDIAN_LITTLE>() != CL_FALSE;
    l.host_unified = device.getInfo<CL_DEVICE_HOST_UNIFIED_MEMORY>() != CL_FALSE;
    l.cpu = (device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU) != 0;
    l.correctly_rounded_div_sqrt =
        (device.getInfo<CL_DEVICE_SINGLE_FP_CONFIG>() & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
    if (uint64_t v = env_bytes("ENVTRACE_CL_MAX_ALLOC"))
        l.max_alloc = std::min(l.max_alloc, v);
    if (uint64_t v = env_bytes("ENVTRACE_CL_GLOBAL_MEM"))
        l.global_mem = std::min(l.global_mem, v);
    return l;
}

void check_device_usable(const DeviceLimits& limits, const std::string& device_name) {
    if (!limits.little_endian)
        throw Error("OpenCL device '" + device_name +
                    "' is big-endian (CL_DEVICE_ENDIAN_LITTLE is false); envtrace needs a "
                    "little-endian device: integers travel inside float buffers and kernel "
                    "arguments in the host's byte order");
}

void check_buffer_sizes(const std::vector<BufferRequest>& buffers, const DeviceLimits& limits,
                        const std::string& device_name) {
    uint64_t total = 0;
    const BufferRequest* largest = nullptr;
    for (const BufferRequest& b : buffers) {
        if (b.bytes > limits.max_alloc)
            throw Error("OpenCL device '" + device_name + "': buffer " + b.name + " needs " +
                        bytes_text(b.bytes) + ", more than the device allows in one buffer " +
                        "(CL_DEVICE_MAX_MEM_ALLOC_SIZE = " + bytes_text(limits.max_alloc) + ")");
        total += b.bytes;
        if (!largest || b.bytes > largest->bytes)
            largest = &b;
    }
    if (total > limits.global_mem)
        throw Error("OpenCL device '" + device_name + "': its " + std::to_string(buffers.size()) +
                    " buffers need " + bytes_text(total) + " in all (the largest, " +
                    largest->name + ", " + bytes_text(largest->bytes) +
                    "), more than the device's memory (CL_DEVICE_GLOBAL_MEM_SIZE = " +
                    bytes_text(limits.global_mem) + ")");
}

size_t choose_local_size(size_t kernel_max, size_t preferred_multiple, const DeviceLimits& limits,
                         size_t target) {
    size_t local = std::max<size_t>(1, target);
    for (size_t cap : {kernel_max, limits.max_work_group, limits.max_work_item_x})
        if (cap > 0)
            local = std::min(local, cap);
    if (preferred_multiple > 1 && local >= preferred_multiple)
        local -= local % preferred_multiple;
    return local;
}

size_t choose_local_size(const cl::Kernel& kernel, const cl::Device& device,
                         const DeviceLimits& limits, size_t target) {
    return choose_local_size(
        kernel.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(device),
        kernel.getWorkGroupInfo<CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE>(device), limits,
        target);
}

std::string cl_error_name(cl_int code) {
    switch (code) {
#define ET_CASE(x)                                                                                 \
    case x:                                                                                        \
        return #x " (" + std::to_string(code) + ")";
        ET_CASE(CL_DEVICE_NOT_FOUND)
        ET_CASE(CL_OUT_OF_RESOURCES)
        ET_CASE(CL_OUT_OF_HOST_MEMORY)
        ET_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
        ET_CASE(CL_BUILD_PROGRAM_FAILURE)
        ET_CASE(CL_INVALID_VALUE)
        ET_CASE(CL_INVALID_BUFFER_SIZE)
        ET_CASE(CL_INVALID_KERNEL_ARGS)
        ET_CASE(CL_INVALID_ARG_SIZE)
        ET_CASE(CL_INVALID_WORK_GROUP_SIZE)
        ET_CASE(CL_INVALID_BINARY)
        ET_CASE(CL_PLATFORM_NOT_FOUND_KHR)
#undef ET_CASE
    default:
        return "OpenCL error " + std::to_string(code);
    }
}

std::vector<DeviceEntry> list_devices() {
    std::vector<cl::Platform> platforms;
    try {
        cl::Platform::get(&platforms);
    } catch (const cl::Error& e) {
        if (e.err() != CL_PLATFORM_NOT_FOUND_KHR)
            throw Error(std::string("cannot list OpenCL platforms: ") + cl_error_name(e.err()));
    }
    if (platforms.empty())
        throw Error(std::string("no OpenCL platform found: ") + kInstallHint);
    const char* filter_env = std::getenv("ENVTRACE_CL_PLATFORM");
    const std::string filter = filter_env ? lower(filter_env) : "";
    std::string names;
    std::vector<DeviceEntry> out;
    for (auto& p : platforms) {
        const std::string pname = p.getInfo<CL_PLATFORM_NAME>();
        names += (names.empty() ? "'" : ", '") + pname + "'";
        if (!filter.empty() && lower(pname).find(filter) == std::string::npos)
            continue;
        std::vector<cl::Device> devices;
        try {
            p.getDevices(CL_DEVICE_TYPE_ALL, &devices);
        } catch (const cl::Error&) {
            continue; // a platform without devices
        }
        for (auto& d : devices) {
            DeviceEntry e;
            e.platform = p;
            e.device = d;
            e.platform_name = pname + " " + p.getInfo<CL_PLATFORM_VERSION>();
            e.device_name = d.getInfo<CL_DEVICE_NAME>();
            e.device_version = d.getInfo<CL_DEVICE_VERSION>();
            e.driver_version = d.getInfo<CL_DRIVER_VERSION>();
            e.compute_units = static_cast<int>(d.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>());
            out.push_back(std::move(e));
        }
    }
    if (out.empty() && !filter.empty())
        throw Error("ENVTRACE_CL_PLATFORM='" + std::string(filter_env) +
                    "' matches no OpenCL platform with a device; the platforms are " + names);
    if (out.empty())
        throw Error(std::string("OpenCL platforms exist but none has a device: ") + kInstallHint);
    return out;
}

ClRuntime::ClRuntime(int device_index) {
    auto devices = list_devices();
    if (device_index < 0 || device_index >= static_cast<int>(devices.size()))
        throw Error("--device " + std::to_string(device_index) + " does not exist: there " +
                    (devices.size() == 1 ? "is 1 device"
                                         : "are " + std::to_string(devices.size()) + " devices") +
                    " (see 'envtrace devices')");
    entry_ = devices[device_index];
    try {
        limits_ = query_device_limits(entry_.device);
    } catch (const cl::Error& e) {
        throw Error("cannot query OpenCL device '" + entry_.device_name +
                    "': " + cl_error_name(e.err()));
    }
    check_device_usable(limits_, entry_.device_name);
    try {
        context_ = cl::Context(entry_.device);
        queue_ = cl::CommandQueue(context_, entry_.device);
    } catch (const cl::Error& e) {
        throw Error("cannot open OpenCL device '" + entry_.device_name +
                    "': " + cl_error_name(e.err()));
    }
}

std::string ClRuntime::cache_dir() {
    if (const char* d = std::getenv("ENVTRACE_CACHE_DIR"); d && *d)
        return d;
    if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d)
        return std::string(d) + "/envtrace";
    if (const char* d = std::getenv("HOME"); d && *d)
        return std::string(d) + "/.cache/envtrace";
    return (fs::temp_directory_path() / "envtrace-cache").string();
}

bool ClRuntime::is_oclgrind() const {
    return lower(entry_.platform_name).find("oclgrind") != std::string::npos;
}

cl::Program ClRuntime::build(const std::string& file, const std::string& options,
                             ProgramBuildInfo* info) {
    return build_source(file, expand_kernel_source(file), options, info);
}

cl::Program ClRuntime::build_source(const std::string& file, const std::string& source,
                                    const std::string& options, ProgramBuildInfo* info) {
    Timer timer;
    // Oclgrind's interpreter lacks an intrinsic that forced inlining makes (kernels/compat.h,
    // ETK_STRUCT_INLINE_FN): it checks the kernels as plain inline functions, the same operations.
    const bool plain_inline = is_oclgrind();
    const std::string full_options =
        std::string("-cl-std=CL1.2 ") +
        (limits_.correctly_rounded_div_sqrt ? "-cl-fp32-correctly-rounded-divide-sqrt " : "") +
        (plain_inline ? "-DETK_PLAIN_INLINE " : "") + (limits_.cpu ? "-DETK_CPU_DEVICE " : "") +
        options; // kernels/compat.h
    const std::string key =
        cache_key(source + '\0' + full_options + '\0' + entry_.platform_name + '\0' +
                  entry_.device_name + '\0' + entry_.driver_version + '\0' + entry_.device_version);
    const fs::path cached =
        fs::path(cache_dir()) / (fs::path(file).stem().string() + "-" + key + ".bin");
    ProgramBuildInfo local;
    ProgramBuildInfo& bi = info ? *info : local;
    bi.cache_file = cached.string();

    // Warm path: a cached binary for exactly this source, options and device.
    std::error_code ec;
    if (fs::exists(cached, ec)) {
        std::ifstream in(cached, std::ios::binary);
        std::vector<unsigned char> bin((std::istreambuf_iterator<char>(in)),
                                       std::istreambuf_iterator<char>());
        try {
            cl::Program program(context_, {entry_.device}, cl::Program::Binaries{bin});
            program.build({entry_.device}, full_options.c_str());
            bi.from_cache = true;
            bi.seconds = timer.seconds();
            return program;
        } catch (const cl::Error&) {
            fs::remove(cached, ec); // stale or corrupt: rebuild from source
        }
    }

    cl::Program program(context_, source);
    try {
        program.build({entry_.device}, full_options.c_str());
    } catch (const cl::Error& e) {
        throw Error("OpenCL program kernels/" + file + " failed to build on '" +
                    entry_.device_name + "' (" + cl_error_name(e.err()) + "):\n" +
                    logical_locations(build_log(program, entry_.device), source));
    }
    // ENVTRACE_CL_BUILD_LOG=1: the compiler's log of a build that succeeded (its warnings), for
    // bringing the kernels to a new device; a cached binary has none.
    bi.log = logical_locations(build_log(program, entry_.device), source);
    if (const char* v = std::getenv("ENVTRACE_CL_BUILD_LOG"); v && *v && std::string(v) != "0")
        std::fprintf(stderr, "OpenCL build log of kernels/%s on '%s':\n%s\n", file.c_str(),
                     entry_.device_name.c_str(), bi.log.c_str());
    // Store the binary atomically; a cache that cannot be written only costs time.
    try {
        auto binaries = program.getInfo<CL_PROGRAM_BINARIES>();
        if (!binaries.empty() && !binaries[0].empty()) {
            fs::create_directories(cached.parent_path(), ec);
            fs::path tmp = cached;
            tmp += ".tmp" + std::to_string(getpid());
            {
                std::ofstream out(tmp, std::ios::binary);
                out.write(reinterpret_cast<const char*>(binaries[0].data()),
                          static_cast<std::streamsize>(binaries[0].size()));
            }
            fs::rename(tmp, cached, ec);
            if (ec)
                fs::remove(tmp, ec);
        }
    } catch (const cl::Error&) {
    }
    bi.from_cache = false;
    bi.seconds = timer.seconds();
    return program;
}

} // namespace et
