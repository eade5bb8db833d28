// The part of Intel Open Image Denoise 2's C API (OpenImageDenoise/oidn.h) that envtrace calls,
// declared here because the library is loaded at run time (oidn_library.h), never linked: the
// PyPI wheel it comes from (pyoidn) ships the shared libraries without the header. The values
// and signatures are OIDN 2.x's; oidn_library.cpp checks the loaded library's version.
#pragma once
#include <cstddef>

namespace et::oidn {

enum DeviceType { kDeviceDefault = 0, kDeviceCpu = 1 };
enum ErrorCode { kErrorNone = 0 };
enum Format { kFormatFloat3 = 3 };

typedef struct DeviceImpl* Device;
typedef struct FilterImpl* Filter;
typedef struct BufferImpl* Buffer;

// The functions, by their C names (oidnNewDevice ...), as pointers resolved from the library.
struct Api {
    Device (*NewDevice)(int type);
    void (*CommitDevice)(Device device);
    void (*ReleaseDevice)(Device device);
    int (*GetDeviceInt)(Device device, const char* name);
    int (*GetDeviceError)(Device device, const char** message);

    Buffer (*NewBuffer)(Device device, size_t bytes);
    void (*WriteBuffer)(Buffer buffer, size_t offset, size_t bytes, const void* src);
    void (*ReadBuffer)(Buffer buffer, size_t offset, size_t bytes, void* dst);
    void (*ReleaseBuffer)(Buffer buffer);

    Filter (*NewFilter)(Device device, const char* type);
    void (*SetFilterImage)(Filter filter, const char* name, Buffer buffer, int format, size_t width,
                           size_t height, size_t byte_offset, size_t pixel_byte_stride,
                           size_t row_byte_stride);
    void (*SetFilterBool)(Filter filter, const char* name, bool value);
    void (*CommitFilter)(Filter filter);
    void (*ExecuteFilter)(Filter filter);
    void (*ReleaseFilter)(Filter filter);
};

} // namespace et::oidn
