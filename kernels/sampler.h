// Deterministic sample values regenerated from (seed, stream, index, dimension pair): nothing is
// stored, and host and device compute identical bits.
//
// ETK_SAMPLER_SOBOL: the first two Sobol' dimensions, a (0,2)-sequence, randomised per stream and
// pair by random digit (XOR) scrambling as in Kollig & Keller 2002. Each pair also shuffles the
// sample index by a nested uniform scramble of its bits (Burley 2020), which maps every aligned
// block of 2^m indices onto another aligned block, so the first 2^m samples of a stream are still
// a (0,m,2)-net while different pairs of dimensions are decorrelated (padding).
// ETK_SAMPLER_RANDOM: independent uniform values from a hash.
#ifndef ETK_SAMPLER_H
#define ETK_SAMPLER_H
#include "compat.h"

#define ETK_SAMPLER_RANDOM 0
#define ETK_SAMPLER_SOBOL 1

ETK_BEGIN

// Wellons' lowbias32 integer hash.
ETK_FN uint etk_hash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

ETK_FN uint etk_hash_combine(uint a, uint b) {
    return etk_hash(a ^ (etk_hash(b) + 0x9e3779b9u));
}

// One byte reversed with three multiplications (Sean Anderson's "bit twiddling hacks", 32-bit
// variant; the wrap-around of the last product leaves bits 16..23 exact).
ETK_FN uint etk_reverse_byte(uint b) {
    return (((b * 0x0802u & 0x22110u) | (b * 0x8020u & 0x88440u)) * 0x10101u >> 16) & 0xffu;
}

// The 32 bits of x in reverse order. Written with multiplications rather than the usual
// shift-and-mask network on purpose: LLVM recognises that network (and a bit-by-bit loop) and
// replaces it with the llvm.bitreverse intrinsic, which some OpenCL implementations (Oclgrind)
// and SPIR-V translators cannot compile. tests/portability checks that no program contains it.
ETK_FN uint etk_reverse_bits(uint x) {
    return (etk_reverse_byte(x & 0xffu) << 24) | (etk_reverse_byte((x >> 8) & 0xffu) << 16) |
           (etk_reverse_byte((x >> 16) & 0xffu) << 8) | etk_reverse_byte(x >> 24);
}

// The second Sobol' dimension of the index whose bits, reversed, are y: etk_sobol_dim1 without
// the reversal. That dimension's generator matrix is Pascal's triangle mod 2: output bit 31 - j
// is the parity of the index bits k with (k & j) == j (Lucas' theorem), i.e. a superset-sum
// (zeta) transform over the 5-bit bit positions, done here as five shift-mask-xor steps on the
// whole word instead of 32 conditional xors of direction numbers. Exactly the same bits
// (Sampler.SobolDimensionOneEqualsTheDirectionNumbers checks it).
ETK_FN uint etk_sobol_dim1_reversed(uint y) {
    y ^= (y << 1) & 0xaaaaaaaau;
    y ^= (y << 2) & 0xccccccccu;
    y ^= (y << 4) & 0xf0f0f0f0u;
    y ^= (y << 8) & 0xff00ff00u;
    y ^= (y << 16) & 0xffff0000u;
    return y;
}

// Second Sobol' dimension (the first is the bit-reversed index).
ETK_FN uint etk_sobol_dim1(uint i) {
    return etk_sobol_dim1_reversed(etk_reverse_bits(i));
}

// Laine-Karras style hash on reversed bits: a nested uniform scramble of the index, returned
// with its bits reversed (what the (0,2)-sequence needs: see etk_sample_pair).
ETK_FN uint etk_shuffle_index_reversed(uint i, uint seed) {
    uint x = etk_reverse_bits(i);
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}
ETK_FN uint etk_shuffle_index(uint i, uint seed) {
    return etk_reverse_bits(etk_shuffle_index_reversed(i, seed));
}

// 24 bits to [0,1): exactly representable, never 1.
ETK_FN float etk_unit_float(uint bits) {
    return (float)(bits >> 8) * 5.9604644775390625e-8f;
}

// The scrambled (0,2)-sequence point of a stream before shuffling, as raw 32-bit values.
ETK_FN uint etk_sobol02_x(uint index, uint scramble) {
    return etk_reverse_bits(index) ^ scramble;
}
ETK_FN uint etk_sobol02_y(uint index, uint scramble) {
    return etk_sobol_dim1(index) ^ scramble;
}

// Two sample values for dimensions (2 pair, 2 pair + 1) of sample `index` of `stream`. Forced
// inline: a vertex draws several pairs of one stream, whose hash of (seed, stream) the compiler
// then computes once (GCC kept a call: 3% of a native pass at depth 5; the same bits).
ETK_FORCE_INLINE_FN float2 etk_sample_pair(int sampler, uint seed, uint stream, uint index,
                                           uint pair) {
    uint key = etk_hash_combine(etk_hash_combine(seed, stream), pair);
    uint bx, by; // the two values' bits; one float2 made at the end (a loop over a batch of
                 // these then has no vector-typed values, which LLVM cannot vectorise)
    if (sampler == ETK_SAMPLER_SOBOL) {
        // r: the shuffled index i with its bits reversed, so etk_sobol02_x(i, sx) = r ^ sx and
        // etk_sobol02_y(i, sy) = etk_sobol_dim1_reversed(r) ^ sy, without reversing i back and
        // forth (the same bits; Sampler.PairEqualsTheSequenceFunctions checks it).
        uint r = etk_shuffle_index_reversed(index, etk_hash(key ^ 0x5bd1e995u));
        bx = r ^ etk_hash(key ^ 0x68e31da4u);
        by = etk_sobol_dim1_reversed(r) ^ etk_hash(key ^ 0xb5297a4du);
    } else {
        uint h = etk_hash_combine(key, index);
        bx = etk_hash(h ^ 0x1b873593u);
        by = etk_hash(h ^ 0xcc9e2d51u);
    }
    return make_float2(etk_unit_float(bx), etk_unit_float(by));
}

// Point j of n (a power of two) of a sample point u shifted by a rank-1 lattice: u + (j / n,
// (j g mod n) / n), wrapped to [0, 1)^2, g odd and near n / golden ratio (a Fibonacci-like
// generator: the n points are well spread in both coordinates). Each point is uniform on the
// square when u is, and together the n stratify it, so n samples of a vertex drawn from them
// split one sample (integrator.h) while u keeps the sequence's stratification across passes.
// Exact in float on every device (j / n: etk_inv_pow2).
ETK_FN float2 etk_lattice_point(float2 u, uint j, uint n) {
    uint g = ((n * 40503u) >> 16) | 1u; // 40503 / 65536 = 0.61803
    float inv = etk_inv_pow2(n);
    float x = u.x + (float)j * inv, y = u.y + (float)((j * g) & (n - 1u)) * inv;
    return make_float2(x >= 1.0f ? x - 1.0f : x, y >= 1.0f ? y - 1.0f : y);
}

ETK_END

#endif
