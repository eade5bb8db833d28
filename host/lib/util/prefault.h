// Large zeroed buffers whose memory is mapped in before it is written.
#pragma once
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <vector>

namespace et {

namespace detail {
// Maps in the pages wholly inside [begin, end) for writing (MADV_POPULATE_WRITE, Linux 5.14+);
// a no-op where the kernel refuses it.
inline void populate_pages(const void* begin, const void* end) {
#ifdef MADV_POPULATE_WRITE
    const uintptr_t page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
    const uintptr_t b = (reinterpret_cast<uintptr_t>(begin) + page - 1) & ~(page - 1);
    const uintptr_t e = reinterpret_cast<uintptr_t>(end) & ~(page - 1);
    if (e > b)
        madvise(reinterpret_cast<void*>(b), e - b, MADV_POPULATE_WRITE);
#else
    (void)begin;
    (void)end;
#endif
}
} // namespace detail

// A vector of n value-initialised elements. Buffers of 16 MiB and more have their pages mapped in
// by one madvise(MADV_POPULATE_WRITE) before the zeroing: a fresh gigabyte otherwise takes a page
// fault per 4 KiB, which on the VMs this runs on costs about twice as much (0.9 s against 0.5 s
// per GiB). Kernels without it (before Linux 5.14) refuse the call and the zeroing maps the pages
// as before. The call works on the vector's storage after reserve(), before its elements exist:
// only the pages are touched, never an object.
template <typename T> std::vector<T> prefaulted_vector(size_t n) {
    std::vector<T> v;
    v.reserve(n);
    if (n * sizeof(T) >= (size_t(16) << 20))
        detail::populate_pages(v.data(), v.data() + n);
    v.resize(n);
    return v;
}

// Grows v to n elements (value-initialised) within the capacity reserved beforehand, so that
// v.data() stays where it is; the new elements' pages are mapped in first, as above. A buffer
// reserved for a whole image and grown a band at a time as the file decodes touches memory only
// for what the file really holds: a truncated file that declares a huge size fails before its
// size has been paid for (fuzz finding F7). Returns false, leaving v alone, when n is beyond the
// capacity (growing would move the data).
template <typename T> bool grow_in_place(std::vector<T>& v, size_t n) {
    if (n > v.capacity())
        return false;
    if (n > v.size() && (n - v.size()) * sizeof(T) >= (size_t(1) << 20))
        detail::populate_pages(v.data() + v.size(), v.data() + n);
    v.resize(n);
    return true;
}

} // namespace et
