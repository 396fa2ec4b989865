/* philox.h: the Philox4x32-10 counter-based random number generator.
 *
 * Salmon, Moraes, Dror and Shaw, "Parallel random numbers: as easy as 1, 2, 3", SC 2011 (Random123).
 * A work-item draws four 32-bit words from a 128-bit counter and a 64-bit key with no state: keyed by
 * (seed) and counted by (site, sweep, phase), a stochastic kernel gives the same bits for the same seed
 * whatever the local size, the launch order or the device. Checked against Random123's known-answer
 * vectors (tests/kat_vectors, "philox4x32 10") in tests/test_mrf_philox.py.
 */
#ifndef PHILOX_H
#define PHILOX_H

#define PHILOX_M0 0xD2511F53u
#define PHILOX_M1 0xCD9E8D57u
#define PHILOX_W0 0x9E3779B9u
#define PHILOX_W1 0xBB67AE85u

inline uint4 philox_round(uint4 c, uint2 k)
{
    uint hi0 = mul_hi(PHILOX_M0, c.x), lo0 = PHILOX_M0 * c.x;
    uint hi1 = mul_hi(PHILOX_M1, c.z), lo1 = PHILOX_M1 * c.z;
    return (uint4)(hi1 ^ c.y ^ k.x, lo1, hi0 ^ c.w ^ k.y, lo0);
}

/* Ten rounds; the key is bumped by the Weyl constants between rounds. */
inline uint4 philox4x32_10(uint4 counter, uint2 key)
{
    for (int r = 0; r < 10; ++r) {
        counter = philox_round(counter, key);
        key += (uint2)(PHILOX_W0, PHILOX_W1);
    }
    return counter;
}

/* A uniform float in the open interval (0, 1) from the top 24 bits of a word: never 0, so log is safe. */
inline float philox_uniform(uint word)
{
    return ((float)(word >> 8) + 0.5f) * 0x1.0p-24f;
}

#endif
