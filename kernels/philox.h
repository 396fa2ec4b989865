/* philox.h: the Philox4x32-10 counter-based random number generator.
 *
 * Salmon, Moraes, Dror and Shaw, "Parallel random numbers: as easy as 1, 2, 3", SC 2011 (Random123).
 * A work-item draws four 32-bit words from a 128-bit counter and a 64-bit key with no state: keyed by
 * the seed and counted by (sites, sweep, colour, block), a stochastic kernel gives the same bits for the
 * same seed whatever the local size or the launch order (mrf.cl computes four blocks at once on uint4
 * lanes for 16 sites). Checked against Random123's known-answer vectors (tests/kat_vectors, "philox4x32 10") in tests/test_mrf_philox.py.
 */
#ifndef PHILOX_H
#define PHILOX_H

#define PHILOX_M0 0xD2511F53u
#define PHILOX_M1 0xCD9E8D57u
#define PHILOX_W0 0x9E3779B9u
#define PHILOX_W1 0xBB67AE85u

/* Scalar words and a 64-bit product rather than uint4 and mul_hi: PoCL vectorises this form across
 * work-items (measured 5x faster on the CPU than the vector-typed round). */
inline uint4 philox4x32_10(uint4 counter, uint2 key)
{
    uint c0 = counter.x, c1 = counter.y, c2 = counter.z, c3 = counter.w, k0 = key.x, k1 = key.y;
#pragma unroll
    for (int r = 0; r < 10; ++r) {
        ulong p0 = (ulong)PHILOX_M0 * c0, p1 = (ulong)PHILOX_M1 * c2;
        uint hi0 = (uint)(p0 >> 32), lo0 = (uint)p0, hi1 = (uint)(p1 >> 32), lo1 = (uint)p1;
        c0 = hi1 ^ c1 ^ k0;
        c1 = lo1;
        c2 = hi0 ^ c3 ^ k1;
        c3 = lo0;
        k0 += PHILOX_W0;
        k1 += PHILOX_W1;
    }
    return (uint4)(c0, c1, c2, c3);
}

/* A uniform float in the open interval (0, 1) from the top 24 bits of a word: never 0, so log is safe. */
inline float philox_uniform(uint word)
{
    return ((float)(word >> 8) + 0.5f) * 0x1.0p-24f;
}

/* The four uniforms of one Philox block, into u[0..3]. */
inline void philox_uniforms(uint4 counter, uint2 key, float *u)
{
    uint4 r = philox4x32_10(counter, key);
    u[0] = philox_uniform(r.x);
    u[1] = philox_uniform(r.y);
    u[2] = philox_uniform(r.z);
    u[3] = philox_uniform(r.w);
}

/* Four blocks at once, lane j of each word vector belonging to block j (counters c0..c3 word by word):
 * the same rounds on uint4 lanes, so a work-item gets 16 words in straight-line vector code. Gives the
 * bits of philox4x32_10 for each lane's counter (tests/test_mrf_philox.py checks it). */
inline void philox4x32_10_x4(uint4 *w0, uint4 *w1, uint4 *w2, uint4 *w3, uint2 key)
{
    uint4 c0 = *w0, c1 = *w1, c2 = *w2, c3 = *w3;
    uint k0 = key.x, k1 = key.y;
#pragma unroll
    for (int r = 0; r < 10; ++r) {
        ulong4 p0 = convert_ulong4(c0) * (ulong)PHILOX_M0, p1 = convert_ulong4(c2) * (ulong)PHILOX_M1;
        uint4 hi0 = convert_uint4(p0 >> 32), lo0 = convert_uint4(p0 & 0xFFFFFFFFUL);
        uint4 hi1 = convert_uint4(p1 >> 32), lo1 = convert_uint4(p1 & 0xFFFFFFFFUL);
        c0 = hi1 ^ c1 ^ k0;
        c1 = lo1;
        c2 = hi0 ^ c3 ^ k1;
        c3 = lo0;
        k0 += PHILOX_W0;
        k1 += PHILOX_W1;
    }
    *w0 = c0; *w1 = c1; *w2 = c2; *w3 = c3;
}

inline float4 philox_uniform4(uint4 word)
{
    return (convert_float4(word >> 8) + 0.5f) * 0x1.0p-24f;
}

/* The 16 uniforms of blocks (c0, c1, c2, first + j), j = 0..3: lane 4 m + j is word m of block j. */
inline float16 philox_uniforms16(uint c0, uint c1, uint c2, uint first, uint2 key)
{
    uint4 w0 = (uint4)(c0), w1 = (uint4)(c1), w2 = (uint4)(c2), w3 = (uint4)(first) + (uint4)(0, 1, 2, 3);
    philox4x32_10_x4(&w0, &w1, &w2, &w3, key);
    return (float16)(philox_uniform4(w0), philox_uniform4(w1), philox_uniform4(w2), philox_uniform4(w3));
}

#endif
