// The common subset of OpenCL C and C++ that every shared header under kernels/ is written in.
// In OpenCL C this is nearly empty; in C++ it supplies float2/float3, their operators and the
// few built-ins the shared math uses, inside namespace etk so that the host sees the very same
// functions the kernels run.
#ifndef ETK_COMPAT_H
#define ETK_COMPAT_H

// OpenCL C or C++: decided by the language macro __OPENCL_C_VERSION__, which every OpenCL C
// compiler predefines (the driver's compilers and clang offline alike). __OPENCL_VERSION__ is the
// device's version and comes from the driver's headers only: an offline clang -target spir64
// build does not define it.
#ifdef __OPENCL_C_VERSION__
#define ETK_OPENCL_C 1
#endif

#ifdef ETK_OPENCL_C

// No fused multiply-adds: the host compiles with -ffp-contract=off, so both round alike.
#pragma OPENCL FP_CONTRACT OFF
#define ETK_BEGIN
#define ETK_END
#define ETK_FN static inline
// For small helpers on hot paths that take pointers to the caller's locals (the BVH lane) or a
// large struct by value (EtkParams): a call that is not inlined spills them or copies the struct,
// and PoCL's inliner leaves such calls (0.73x -> 0.87x of native from the BVH's lane
// helper alone). Everything else stays plain inline: inlining it all multiplies PoCL's build time
// by 8.
#if defined(__clang__) || defined(__GNUC__)
#define ETK_FORCE_INLINE_FN static inline __attribute__((always_inline))
#else
#define ETK_FORCE_INLINE_FN static inline
#endif
// Forced inline: functions that take a struct by value (EtkScene, EtkPaths, EtkParams,
// EtkSurface, EtkVertex, EtkMaterial, EtkEnvMap) and that the compilers leave as calls, copying the
// structs (about a kilobyte) through memory on every call: PoCL's shade stage 0.98-1.09x native's
// -> 0.74-0.84x at depth 5 as calls; natively 5-11% faster renders forced, every strategy, the same
// bits (docs/history/bench-journal.md, "Stage steps inlined natively"). Plain where the host
// defines ETK_PLAIN_INLINE: for Oclgrind, whose interpreter has no
// llvm.experimental.noalias.scope.decl, which clang emits when it inlines a function that returns a
// struct (opencl_runtime.cpp).
#ifdef ETK_PLAIN_INLINE
#define ETK_STRUCT_INLINE_FN ETK_FN
#else
#define ETK_STRUCT_INLINE_FN ETK_FORCE_INLINE_FN
#endif
// A call in OpenCL C on CPU devices (the host defines ETK_CPU_DEVICE there): for functions with
// a large private array (the BVH's traversal stack). PoCL gives every private array of a kernel
// one copy per work-item of the group (a context array: the traversal stack, 768 bytes, became
// 49 KB a group, more than L1 holds), so a stack inlined into the kernel lands at a new address
// for every ray; in a function of its own it lives in that function's frame, one copy reused by
// every work-item. Natively GCC keeps such a function a call anyway. Inline on other devices:
// GPUs were measured with the traversal inlined, never as a call.
#if defined(ETK_CPU_DEVICE) && (defined(__clang__) || defined(__GNUC__))
#define ETK_CL_NOINLINE_FN static __attribute__((noinline))
#else
#define ETK_CL_NOINLINE_FN ETK_FN
#endif
#define ETK_GLOBAL __global
// A table of numbers at program scope (kernels/base_albedo_table.h).
#define ETK_TABLE __constant
#define make_float2(a, b) ((float2)((a), (b)))
#define make_float3(a, b, c) ((float3)((a), (b), (c)))
#define ETK_UINT_MAX 0xffffffffu
#define make_float4(a, b, c, d) ((float4)((a), (b), (c), (d)))
// Four lanes compared at once (bvh.h): comparisons give a mask per lane (-1 or 0); its lanes as
// bits 0-3 (s0 is bit 0).
typedef float4 etk_lanes;
#define etk_lanes_of(a) (a)
#define etk_lanes_splat(s) ((float4)(s))
#if defined(__clang__) && defined(__x86_64__)
#define etk_lane_bits4(m) ((uint)__builtin_ia32_movmskps(as_float4(m)))
#else
#define etk_lane_bits4(m) ((uint)(((m).s0 & 1) | ((m).s1 & 2) | ((m).s2 & 4) | ((m).s3 & 8)))
#endif
// The lowest set bit's index (bvh.h: a node's entered children as a bit mask).
#define etk_lowest_bit(b) (31 - (int)clz((b) & (0u - (b))))
// Eight lanes (bvh.h's 8-wide nodes): row r of eight floats at p, read with only a float's
// alignment (a buffer over a host vector of float4, CL_MEM_USE_HOST_PTR, is 16-byte aligned,
// and an aligned float8 load from there faults on PoCL); a mask's lanes as bits 0-7 (s0
// is bit 0), a float8's sign bits, and lane i. Clang for x86-64 with AVX (PoCL's CPU device):
// vmovmskps, or kmov straight from the mask's compare; lane by lane, clang makes it a masked
// move and an OR over the lanes, instructions between a node's box test and the branch on its
// children.
#if defined(__clang__) && defined(__x86_64__)
// As one unaligned 32-byte load: PoCL's vload8 is two vload4, each at an offset of its own, and
// the traversal's twelve offsets (six rows chosen per ray) were reloaded from the stack at every
// node, with a lane insert per row.
typedef float etk_float8_unaligned __attribute__((ext_vector_type(8), aligned(4)));
#define etk_row8(p, r) (*(__global const etk_float8_unaligned*)((p) + 8 * (r)))
#else
#define etk_row8(p, r) vload8((r), (p))
#endif
#define etk_splat8(s) ((float8)(s))
#if defined(__clang__) && defined(__x86_64__) && defined(__AVX__)
#define etk_sign_bits8(v) ((uint)__builtin_ia32_movmskps256(as_float8(v)))
#define etk_lane_bits8(m) etk_sign_bits8(m)
#else
#define etk_lane_bits8(m)                                                                          \
    ((uint)(((m).s0 & 1) | ((m).s1 & 2) | ((m).s2 & 4) | ((m).s3 & 8) | ((m).s4 & 16) |            \
            ((m).s5 & 32) | ((m).s6 & 64) | ((m).s7 & 128)))
#define etk_sign_bits8(v) etk_lane_bits8(as_int8(v) < 0)
#endif
#define etk_le_bits8(a, b) etk_lane_bits8((a) <= (b))
static inline float etk_lane8(float8 v, int i) {
    union {
        float8 v;
        float a[8];
    } u;
    u.v = v;
    return u.a[i];
}
// Reserves a slot in a work queue.
#define ETK_ATOMIC_INC(p) atomic_inc(p)
#define ETK_ATOMIC_ADD(p, v) atomic_add((p), (v))
#define ETK_ATOMIC_PTR volatile __global uint*
// A queue counter: shared by every work-item of the launch.
#define ETK_COUNTER_INC(p) atomic_inc(p)
#define ETK_COUNTER_ADD(p, v) atomic_add((p), (v))
#define ETK_COUNTER_PTR volatile __global uint*
// A hint to start loading the cache line at p (OpenCL 1.2's prefetch; an implementation may
// ignore it): retires at once, where a load would hold its place until the line arrives. PoCL
// ignores it (no instruction in the kernel's code), so a clang compiling for x86-64 (PoCL's CPU
// device) gets the compiler's own prefetch: the sample_lights stage 12% faster there.
#if defined(__clang__) && defined(__x86_64__)
#define ETK_PREFETCH(p) __builtin_prefetch((p))
#else
#define ETK_PREFETCH(p) prefetch((p), 1)
#endif
// Vector geometry spelled out as the host spells it: the built-ins may sum in another order or
// normalise through rsqrt, and the back ends are meant to round identically.
static inline float etk_dot3(float3 a, float3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline float3 etk_cross3(float3 a, float3 b) {
    return (float3)(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float etk_length3(float3 a) {
    return sqrt(etk_dot3(a, a));
}
static inline float3 etk_normalize3(float3 a) {
    return a / etk_length3(a);
}
// Some implementations' headers make the built-ins macros themselves (PoCL 5: every build warned
// "macro redefined"): theirs are dropped first.
#undef dot
#undef cross
#undef length
#undef normalize
#define dot(a, b) etk_dot3((a), (b))
#define cross(a, b) etk_cross3((a), (b))
#define length(a) etk_length3(a)
#define normalize(a) etk_normalize3(a)

#else // C++ host

#include <cmath>
#include <cstdint>
#include <cstring>
#if defined(__AVX512VL__)
#include <immintrin.h>
#endif

#define ETK_BEGIN namespace etk {
#define ETK_END }
#define ETK_FN inline
#if defined(__clang__) || defined(__GNUC__)
#define ETK_FORCE_INLINE_FN inline __attribute__((always_inline))
#else
#define ETK_FORCE_INLINE_FN inline
#endif
#define ETK_STRUCT_INLINE_FN ETK_FORCE_INLINE_FN // forced natively too (above)
#define ETK_CL_NOINLINE_FN inline                // a call in OpenCL C only (above)
#define ETK_GLOBAL
#define ETK_TABLE static const
#define ETK_UINT_MAX 0xffffffffu
#define ETK_ATOMIC_INC(p) __atomic_fetch_add((p), 1u, __ATOMIC_RELAXED)
#define ETK_ATOMIC_ADD(p, v) __atomic_fetch_add((p), (v), __ATOMIC_RELAXED)
#define ETK_ATOMIC_PTR uint*
// A queue counter: each native lane (one thread) has its own queues and counters, so a plain add
// reserves the same slots, in the same order, as an atomic one would -- without its locked
// instruction (1-2% of a pass).
#define ETK_COUNTER_INC(p) etk::etk_counter_add((p), 1u)
#define ETK_COUNTER_ADD(p, v) etk::etk_counter_add((p), (v))
#define ETK_COUNTER_PTR uint*
#define ETK_PREFETCH(p) __builtin_prefetch(p)

namespace etk {
using std::acos;
using std::atan2;
using std::cos;
using std::exp;
using std::fabs;
using std::floor;
using std::pow;
using std::sin;
using std::sqrt;
typedef std::uint32_t uint;
typedef std::uint64_t ulong;
typedef std::uint8_t uchar;

// ETK_COUNTER_ADD: the counter's old value, as atomic_add returns it.
inline uint etk_counter_add(uint* p, uint v) {
    const uint old = *p;
    *p = old + v;
    return old;
}

struct float2 {
    float x, y;
};
struct float3 {
    float x, y, z;
};
// 16-byte aligned like OpenCL's float4, so arrays of it match device buffers.
struct alignas(16) float4 {
    float x, y, z, w;
};
inline float4 make_float4(float a, float b, float c, float d) {
    return float4{a, b, c, d};
}
inline float2 make_float2(float a, float b) {
    return float2{a, b};
}
inline float3 make_float3(float a, float b, float c) {
    return float3{a, b, c};
}

inline float3 operator+(float3 a, float3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline float3 operator-(float3 a, float3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline float3 operator-(float3 a) {
    return {-a.x, -a.y, -a.z};
}
inline float3 operator*(float3 a, float3 b) {
    return {a.x * b.x, a.y * b.y, a.z * b.z};
}
inline float3 operator*(float3 a, float s) {
    return {a.x * s, a.y * s, a.z * s};
}
inline float3 operator*(float s, float3 a) {
    return {a.x * s, a.y * s, a.z * s};
}
inline float3 operator/(float3 a, float3 b) {
    return {a.x / b.x, a.y / b.y, a.z / b.z};
}
inline float3 operator/(float3 a, float s) {
    return {a.x / s, a.y / s, a.z / s};
}
inline float3& operator+=(float3& a, float3 b) {
    return a = a + b;
}
inline float3& operator*=(float3& a, float3 b) {
    return a = a * b;
}
inline float3& operator*=(float3& a, float s) {
    return a = a * s;
}

// Lane-wise float4 arithmetic, as OpenCL has it: the BVH's triangle packets (bvh.h). Done on
// GCC/Clang vector types, one SSE instruction per operation (the same arithmetic lane by lane is
// left scalar by the SLP vectoriser).
typedef float etk_v4 __attribute__((vector_size(16)));
inline etk_v4 etk_to_v4(float4 a) {
    etk_v4 v;
    std::memcpy(&v, &a, 16);
    return v;
}
inline float4 etk_from_v4(etk_v4 v) {
    float4 a;
    std::memcpy(&a, &v, 16);
    return a;
}
inline float4 operator-(float4 a, float4 b) {
    return etk_from_v4(etk_to_v4(a) - etk_to_v4(b));
}
inline float4 operator*(float4 a, float4 b) {
    return etk_from_v4(etk_to_v4(a) * etk_to_v4(b));
}
inline float4 operator*(float4 a, float s) {
    return etk_from_v4(etk_to_v4(a) * s);
}
// Four lanes compared at once (bvh.h): comparisons give a mask per lane (-1 or 0), as in OpenCL.
typedef etk_v4 etk_lanes;
inline etk_lanes etk_lanes_of(float4 a) {
    return etk_to_v4(a);
}
inline etk_lanes etk_lanes_splat(float s) {
    return etk_v4{s, s, s, s};
}
// A four-lane mask's lanes as bits 0-3 (one instruction with SSE).
template <typename Mask> inline uint etk_lane_bits4(Mask m) {
#if defined(__SSE__)
    return static_cast<uint>(__builtin_ia32_movmskps(reinterpret_cast<etk_v4>(m)));
#else
    return (m[0] & 1u) | (m[1] & 2u) | (m[2] & 4u) | (m[3] & 8u);
#endif
}
// As in OpenCL C (above): the lowest set bit's index.
inline int etk_lowest_bit(uint b) {
    return __builtin_ctz(b);
}
inline float4 operator+(float4 a, float4 b) {
    return etk_from_v4(etk_to_v4(a) + etk_to_v4(b));
}
// Eight lanes, as in OpenCL C (above): GCC/Clang vectors of 32 bytes (one AVX instruction per
// operation, two SSE ones without AVX). Rows are read from buffers of float4, 16-byte aligned:
// an unaligned load.
typedef float float8 __attribute__((vector_size(32)));
inline float8 etk_row8(const float* p, int r) {
    float8 v;
    std::memcpy(&v, p + 8 * r, sizeof v);
    return v;
}
inline float8 etk_splat8(float s) {
    return float8{s, s, s, s, s, s, s, s};
}
template <typename Mask> inline uint etk_lane_bits8(Mask m) {
#if defined(__AVX__)
    return static_cast<uint>(__builtin_ia32_movmskps256(reinterpret_cast<float8>(m)));
#else
    uint b = 0;
    for (int i = 0; i < 8; ++i)
        b |= (m[i] & 1u) << i;
    return b;
#endif
}
inline uint etk_sign_bits8(float8 v) {
#if defined(__AVX__)
    return static_cast<uint>(__builtin_ia32_movmskps256(v)); // the sign bits as they are
#else
    typedef int int8v __attribute__((vector_size(32)));
    return etk_lane_bits8(reinterpret_cast<int8v>(v) < 0);
#endif
}
// The lanes where a <= b, as bits. With AVX-512 the comparison writes a mask register, which
// moves straight to the bits; through a vector mask it took two more instructions, on the path
// from a node's box test to the branch on its children.
inline uint etk_le_bits8(float8 a, float8 b) {
#if defined(__AVX512VL__)
    return _mm256_cmp_ps_mask(a, b, _CMP_LE_OQ);
#else
    return etk_lane_bits8(a <= b);
#endif
}
inline float etk_lane8(float8 v, int i) {
    return v[i];
}
inline float8 fmin(float8 a, float8 b) { // lane-wise, as fmin below
    return a < b ? a : b;
}
inline float8 fmax(float8 a, float8 b) {
    return a > b ? a : b;
}
inline float4 operator/(float4 a, float4 b) {
    return etk_from_v4(etk_to_v4(a) / etk_to_v4(b));
}

// fmin/fmax as single min/max instructions: std::fminf is a libm call GCC does not inline
// (twelve per BVH box test), and a NaN test makes it branch. These match OpenCL's fmin/fmax
// except when the second argument is NaN, so shared code puts a value that may be NaN first.
inline float fmin(float a, float b) {
    return a < b ? a : b;
}
inline float fmax(float a, float b) {
    return a > b ? a : b;
}
inline float4 fmin(float4 a, float4 b) { // lane-wise, as fmin above
    etk_v4 x = etk_to_v4(a), y = etk_to_v4(b);
    return etk_from_v4(x < y ? x : y);
}
inline float4 fmax(float4 a, float4 b) {
    etk_v4 x = etk_to_v4(a), y = etk_to_v4(b);
    return etk_from_v4(x > y ? x : y);
}
inline float4 fabs(float4 a) { // lane-wise: the sign bits cleared (one AND; -0 gives +0)
    typedef int etk_i4 __attribute__((vector_size(16)));
    etk_i4 x = reinterpret_cast<etk_i4>(etk_to_v4(a)) & 0x7fffffff;
    return etk_from_v4(reinterpret_cast<etk_v4>(x));
}
inline float dot(float3 a, float3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline float3 cross(float3 a, float3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(float3 a) {
    return std::sqrt(dot(a, a));
}
inline float3 normalize(float3 a) {
    return a / length(a);
}
inline float clamp(float x, float lo, float hi) {
    return fmin(fmax(x, lo), hi);
}
inline int clamp(int x, int lo, int hi) {
    return x < lo ? lo : (x > hi ? hi : x);
}
inline int min(int a, int b) {
    return a < b ? a : b;
}
inline int max(int a, int b) {
    return a > b ? a : b;
}
inline uint min(uint a, uint b) {
    return a < b ? a : b;
}
inline uint as_uint(float f) {
    uint u;
    std::memcpy(&u, &f, 4);
    return u;
}
// Leading zero bits of x (32 for 0), as OpenCL's clz.
inline uint clz(uint x) {
    return x ? static_cast<uint>(__builtin_clz(x)) : 32u;
}
inline float as_float(uint u) {
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}
inline float3 fmin(float3 a, float3 b) {
    return {fmin(a.x, b.x), fmin(a.y, b.y), fmin(a.z, b.z)};
}
inline float3 fmax(float3 a, float3 b) {
    return {fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)};
}
inline int isfinite(float x) {
    return std::isfinite(x) ? 1 : 0;
}
} // namespace etk

#endif

// Plain min/max (one instruction; a NaN operand yields the second): for hot paths whose
// operands cannot be NaN, where OpenCL's fmin/fmax pay for NaN handling.
#ifdef ETK_OPENCL_C
#define ETK_MINF(a, b) ((a) < (b) ? (a) : (b))
#define ETK_MAXF(a, b) ((a) > (b) ? (a) : (b))
#else
#define ETK_MINF(a, b) etk::fmin((a), (b))
#define ETK_MAXF(a, b) etk::fmax((a), (b))
#endif

#define ETK_PI 3.14159265358979323846f
#define ETK_INV_PI 0.31830988618379067154f
#define ETK_INV_2PI2 0.05066059182116888572f // 1 / (2 pi^2)
// Largest float below one: keeps a sample inside the cell its binary search chose.
#define ETK_ONE_MINUS_EPS 0.99999994f

ETK_BEGIN
// 1 / n for n a power of two, built from its exponent bits: exact on every device (OpenCL's
// float division may be off by ulps, so 1.0f / n is not).
ETK_FN float etk_inv_pow2(uint n) {
    return as_float((uint)(127 - (31 - (int)clz(n))) << 23); // 2^-log2(n)
}
ETK_END

#endif
