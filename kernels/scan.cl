/* scan.cl: the Connection Machine's scans (Blelloch 1987) along rows and columns: "grid-scans".
 *
 * Defines: T (float|int), OP (OP_PLUS|OP_MAX|OP_MIN|OP_COPY), SEGMENTED (0|1), EXCLUSIVE (0|1),
 * VEC (1 or 16, column kernels only). T_IS_PAIR (1: T is int2, pairs summed componentwise) builds the
 * row kernels alone: the column kernels' vectors of T would be vectors of vectors.
 *
 * State of a running scan: (have, s). have = 0 before the first element of a line, so the next element
 * starts a segment whatever its flag says; that is how copy-scan, which has no identity, gets its first
 * value. A segment flag (uchar, non-zero) restarts the scan at its element.
 *
 * Two variants:
 *  - work-efficient (O(n) work): lines cut into chunks; each chunk is scanned serially by one work-item
 *    (contiguous memory, the fast case on a CPU), after "chunk_totals" and "chunk_carries" have given it
 *    the carry from the chunks before it. With one chunk per line the two extra passes are skipped.
 *  - Hillis-Steele (O(n log n) work, the per-processor algorithm): log2(n) steps, each a launch over all
 *    elements that combines with the element 2^k before it.
 */
#include "vmcl.h"

#if T_IS_FLOAT
#define MAX_OF fmax
#define MIN_OF fmin
#else
#define MAX_OF max
#define MIN_OF min
#endif

/* IDENTITY starts every running state; EXCLUSIVE_START is what an exclusive scan writes where nothing
 * precedes (the documented identity). */
#if OP == OP_PLUS
#define COMBINE(a, b) ((a) + (b))
#define IDENTITY ((T)0)
#define EXCLUSIVE_START ((T)0)
/* Floats take fmax and fmin, which pass over NaN (as reduce.cl's max and min do): max and min return
 * their first operand when the comparison fails, so a NaN's effect depended on the scan's order. Their
 * running state starts at NaN, which fmax and fmin pass over too: a state started at -inf made a line's
 * leading NaN -inf, a value not in the input, where the Hillis-Steele scan (no starting state) gave NaN;
 * now both give NumPy's fmax.accumulate. */
#elif OP == OP_MAX
#define COMBINE(a, b) MAX_OF((a), (b))
#if T_IS_FLOAT
#define IDENTITY ((T)NAN)
#else
#define IDENTITY (T_LOWEST)
#endif
#define EXCLUSIVE_START (T_LOWEST)
#elif OP == OP_MIN
#define COMBINE(a, b) MIN_OF((a), (b))
#if T_IS_FLOAT
#define IDENTITY ((T)NAN)
#else
#define IDENTITY (T_HIGHEST)
#endif
#define EXCLUSIVE_START (T_HIGHEST)
#elif OP == OP_COPY
#define COMBINE(a, b) (a)
/* Exclusive copy-scan gives 0 at each segment start, where nothing precedes. */
#define IDENTITY ((T)0)
#define EXCLUSIVE_START ((T)0)
#endif

#if SEGMENTED
#define FLAG(f, i) ((f)[i] != 0)
#else
#define FLAG(f, i) 0
#endif

/* The row kernels give each work-item four chunks, scanned interleaved: a serial scan is bound by the
 * latency of its one chain of dependent operations, and four independent chains hide it. (Written out
 * per chain: private arrays indexed in a loop measured 2x slower on PoCL.) */
#define ILP 4

/* One element of chain K: chunk K of this work-item, at offset j, from state (hK, sK). Only copy-scan
 * needs hK: for the other operators the state starts at the identity, so a line start needs no test. */
#if OP == OP_COPY
#define IS_START(K, i) (!h##K || FLAG(flags, i))
#else
#define IS_START(K, i) FLAG(flags, i)
#endif
#define STEP(K, WRITE)                                                                     \
    {                                                                                      \
        long i = b##K + j;                                                                 \
        T v = x[i];                                                                        \
        int start = IS_START(K, i);                                                        \
        T next = start ? v : COMBINE(s##K, v);                                             \
        if (WRITE) out[i] = EXCLUSIVE ? (start || !h##K ? EXCLUSIVE_START : s##K) : next;  \
        f##K |= FLAG(flags, i);                                                            \
        s##K = next;                                                                       \
        h##K = 1;                                                                          \
    }
#define GUARDED_STEP(K, WRITE) if (j < len##K) STEP(K, WRITE)

/* Where chunk g begins and how long it is (0 past the last chunk); chunk c of line l covers
 * [l*n + c*chunk, min(l*n + (c+1)*chunk, (l+1)*n)). */
#define CHUNK(K)                                                                           \
    long g##K = first + K;                                                                 \
    long b##K = (g##K / chunks_per_line) * n + (g##K % chunks_per_line) * chunk;           \
    long len##K = g##K < n_chunks ? min(chunk, (g##K / chunks_per_line + 1) * n - b##K) : 0; \
    int f##K = 0;

/* All four chains in step while they last (the common case), then each finishes alone. */
#define SCAN_CHUNKS(WRITE)                                                                 \
    long shortest = min(min(len0, len1), min(len2, len3));                                 \
    long longest = max(max(len0, len1), max(len2, len3));                                  \
    long j = 0;                                                                            \
    for (; j < shortest; j++) {                                                            \
        STEP(0, WRITE) STEP(1, WRITE) STEP(2, WRITE) STEP(3, WRITE)                        \
    }                                                                                      \
    for (; j < longest; j++) {                                                             \
        GUARDED_STEP(0, WRITE) GUARDED_STEP(1, WRITE) GUARDED_STEP(2, WRITE) GUARDED_STEP(3, WRITE) \
    }

#define START_STATE(K)                                                                     \
    CHUNK(K)                                                                               \
    int h##K = use_carry && len##K ? carry_have[g##K] : 0;                                 \
    T s##K = use_carry && len##K ? carry[g##K] : IDENTITY;

/* Work-item w scans chunks 4w .. 4w+3, each from the carry chunk_carries gave it, if any. */
__kernel void scan_rows(__global const T *x, __global const uchar *flags, __global T *out,
                        __global const T *carry, __global const uchar *carry_have,
                        long n, long chunk, int chunks_per_line, int use_carry, long n_chunks)
{
    long first = get_global_id(0) * ILP;
    if (first >= n_chunks) return;
    START_STATE(0) START_STATE(1) START_STATE(2) START_STATE(3)
    SCAN_CHUNKS(1)
}

#define STORE_TOTAL(K)                                                                     \
    if (len##K) { total[g##K] = s##K; restarts[g##K] = f##K; }

/* Reduction of each chunk as if nothing came before it, and whether it holds a segment start. */
__kernel void chunk_totals_rows(__global const T *x, __global const uchar *flags,
                                __global T *total, __global uchar *restarts,
                                long n, long chunk, int chunks_per_line, long n_chunks)
{
    long first = get_global_id(0) * ILP;
    if (first >= n_chunks) return;
    const int use_carry = 0;
    __global const T *carry = 0;
    __global const uchar *carry_have = 0;
    __global T *out = 0;
    START_STATE(0) START_STATE(1) START_STATE(2) START_STATE(3)
    SCAN_CHUNKS(0)
    STORE_TOTAL(0) STORE_TOTAL(1) STORE_TOTAL(2) STORE_TOTAL(3)
}

/* Serial scan of the chunk totals of one line (there are few): the state entering each chunk. Used by
 * the row and the column variants alike; totals are laid out [line][chunk]. */
__kernel void chunk_carries(__global const T *total, __global const uchar *restarts,
                            __global T *carry, __global uchar *carry_have,
                            int chunks_per_line, long n_lines)
{
    long line = get_global_id(0);
    if (line >= n_lines) return;
    int have = 0;
    T s = IDENTITY;
    for (long g = line * chunks_per_line; g < (line + 1) * chunks_per_line; g++) {
        carry[g] = s;
        carry_have[g] = have;
        s = (restarts[g] || !have) ? total[g] : COMBINE(s, total[g]);
        have = 1;
    }
}

#if !T_IS_PAIR
/* Column scans of a stack of planes (P, H, W): work-item (k, c, p) scans columns
 * [col0 + k*VEC, col0 + (k+1)*VEC) of plane p over rows [c*chunk, min((c+1)*chunk, H)), VEC columns at
 * a time so every row step is one contiguous vector load. Carries and totals are laid out per column:
 * [p][column][chunk]. */
#define COL_SETUP                                                                           \
    long k = get_global_id(0), c = get_global_id(1), p = get_global_id(2);                  \
    if (k >= n_vec) return;                                                                 \
    long col = col0 + k * VEC;                                                              \
    long r0 = c * chunk, r1 = min(r0 + chunk, H);                                           \
    __global const T *xp = x + ((size_t)p * H) * W + col;

__kernel void scan_cols(__global const T *x, __global const uchar *flags, __global T *out,
                        __global const T *carry, __global const uchar *carry_have,
                        long W, long H, long col0, long n_vec, long chunk, int chunks_per_line,
                        int use_carry)
{
    COL_SETUP
    VT s = (VT)IDENTITY;
    VIT have = (VIT)0;
    if (use_carry) {
        T cs[VEC];
        int ch[VEC];
        for (int j = 0; j < VEC; j++) {
            long g = (p * W + col + j) * chunks_per_line + c;
            cs[j] = carry[g];
            ch[j] = carry_have[g] ? -1 : 0;
        }
        s = VLOAD(cs);
        have = VLOAD(ch);
    }
    for (long r = r0; r < r1; r++) {
        size_t off = (size_t)r * W;
        VT v = VLOAD(xp + off);
#if SEGMENTED
        VIT start = (have == (VIT)0) | (VFLAGS(flags + ((size_t)p * H) * W + col + off) != (VIT)0);
#else
        VIT start = (have == (VIT)0);
#endif
        VT next = select(COMBINE(s, v), v, start);
#if EXCLUSIVE
        VSTORE(select(s, (VT)EXCLUSIVE_START, start), out + ((size_t)p * H) * W + col + off);
#else
        VSTORE(next, out + ((size_t)p * H) * W + col + off);
#endif
        s = next;
        have = (VIT)(-1);
    }
}

__kernel void chunk_totals_cols(__global const T *x, __global const uchar *flags,
                                __global T *total, __global uchar *restarts,
                                long W, long H, long col0, long n_vec, long chunk, int chunks_per_line)
{
    COL_SETUP
    VT s = (VT)IDENTITY;
    VIT have = (VIT)0, any_flag = (VIT)0;
    for (long r = r0; r < r1; r++) {
        size_t off = (size_t)r * W;
        VT v = VLOAD(xp + off);
#if SEGMENTED
        VIT flag = VFLAGS(flags + ((size_t)p * H) * W + col + off) != (VIT)0;
        VIT start = (have == (VIT)0) | flag;
        any_flag |= flag;
#else
        VIT start = (have == (VIT)0);
#endif
        s = select(COMBINE(s, v), v, start);
        have = (VIT)(-1);
    }
    T ts[VEC];
    int tf[VEC];
    VSTORE(s, ts);
    VSTORE(any_flag, tf);
    for (int j = 0; j < VEC; j++) {
        long g = (p * W + col + j) * chunks_per_line + c;
        total[g] = ts[j];
        restarts[g] = tf[j] != 0;
    }
}

/* One Hillis-Steele step: every element combines with the one `dist` positions before it on its line
 * (element stride `stride`, line length n), unless a segment start lies between them. */
__kernel void hillis_steele_step(__global const T *x, __global const uchar *flags_in,
                                 __global T *out, __global uchar *flags_out,
                                 long stride, long n, long dist, long size)
{
    long i = get_global_id(0);
    if (i >= size) return;
    long pos = (i / stride) % n;
    T v = x[i];
    if (pos >= dist) {
        long j = i - dist * stride;
#if SEGMENTED
        /* flags_in[i] says a segment starts within the 2^k elements ending at i: nothing to combine. */
        uchar f = flags_in[i];
        if (!f) v = COMBINE(x[j], v);
        flags_out[i] = f | flags_in[j];
#else
        v = COMBINE(x[j], v);
#endif
    }
#if SEGMENTED
    else flags_out[i] = flags_in[i];
#endif
    out[i] = v;
}

/* Turns an inclusive Hillis-Steele result into an exclusive one: the element before, or the identity
 * at a line or segment start. */
__kernel void shift_exclusive(__global const T *inclusive, __global const uchar *flags, __global T *out,
                              long stride, long n, long size)
{
    long i = get_global_id(0);
    if (i >= size) return;
    long pos = (i / stride) % n;
    out[i] = (pos == 0 || FLAG(flags, i)) ? EXCLUSIVE_START : inclusive[i - stride];
}
#endif
