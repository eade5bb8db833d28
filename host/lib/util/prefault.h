// Large zeroed buffers whose memory is mapped in before it is written.
#pragma once
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <vector>

namespace et {

// A vector of n value-initialised elements. Buffers of 16 MiB and more have their pages mapped in
// by one madvise(MADV_POPULATE_WRITE) before the zeroing: a fresh gigabyte otherwise takes a page
// fault per 4 KiB, which on the VMs this runs on costs about twice as much (0.9 s against 0.5 s
// per GiB). Kernels without it (before Linux 5.14) refuse the call and the zeroing maps the pages
// as before. The call works on the vector's storage after reserve(), before its elements exist:
// only the pages are touched, never an object.
template <typename T> std::vector<T> prefaulted_vector(size_t n) {
    std::vector<T> v;
    v.reserve(n);
#ifdef MADV_POPULATE_WRITE
    if (n * sizeof(T) >= (size_t(16) << 20)) {
        const uintptr_t page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
        const uintptr_t begin = (reinterpret_cast<uintptr_t>(v.data()) + page - 1) & ~(page - 1);
        const uintptr_t end = reinterpret_cast<uintptr_t>(v.data() + n) & ~(page - 1);
        if (end > begin)
            madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE);
    }
#endif
    v.resize(n);
    return v;
}

} // namespace et
