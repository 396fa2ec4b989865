/* box.cl: the window sum of "Powerful primitive operations" (Scanning): for every pixel, the sum over the
 * (2r+1) x (2r+1) square around it, zero outside the field, in time independent of r.
 *
 * The paper's recipe: plus-scan the rows, and let each pixel take the scan values r in front of it and
 * r + 1 behind it; their difference P[x+r] - P[x-r-1] is the sum along the row. Then the same on the
 * columns. Each pass below keeps that difference as its scan advances (adding the element that enters
 * the window, subtracting the one that leaves), which fuses the scan and the two gets into one pass
 * over memory; for int32 the result is exact, for float32 it differs from the prefix form only by
 * rounding.
 *
 * Defines: T (float|int), VEC (1 or 16, box_cols only).
 */
#include "vmcl.h"

/* One row of the row pass: chain K slides over the row starting at bK. */
#define ROW_STEP(K)                                                                        \
    {                                                                                      \
        if (i < n) w##K += x[b##K + i];                                                    \
        if (i > 2 * r) w##K -= x[b##K + i - 2 * r - 1];                                    \
        if (i >= r) out[b##K + i - r] = w##K;                                              \
    }

/* Work-item g slides along rows 4g .. 4g+3 (interleaved: four independent chains hide the latency of
 * the dependent adds). Rows past the last are clamped to it and write the same values again. */
__kernel void box_rows(__global const T *x, __global T *out, long n, long lines, long r)
{
    long first = get_global_id(0) * 4;
    if (first >= lines) return;
    long b0 = first * n, b1 = min(first + 1, lines - 1) * n;
    long b2 = min(first + 2, lines - 1) * n, b3 = min(first + 3, lines - 1) * n;
    T w0 = 0, w1 = 0, w2 = 0, w3 = 0;
    for (long i = 0; i < n + r; i++) {
        ROW_STEP(0) ROW_STEP(1) ROW_STEP(2) ROW_STEP(3)
    }
}

/* Work-item (k, p) slides down columns [col0 + k*VEC, col0 + (k+1)*VEC) of plane p, VEC at a time so
 * every row step is one contiguous vector access. */
__kernel void box_cols(__global const T *x, __global T *out, long W, long H, long col0, long n_vec, long r)
{
    long k = get_global_id(0), p = get_global_id(1);
    if (k >= n_vec) return;
    size_t base = (size_t)p * H * W + col0 + k * VEC;
    VT w = (VT)0;
    for (long i = 0; i < H + r; i++) {
        if (i < H) w += VLOAD(x + base + (size_t)i * W);
        if (i > 2 * r) w -= VLOAD(x + base + (size_t)(i - 2 * r - 1) * W);
        if (i >= r) VSTORE(w, out + base + (size_t)(i - r) * W);
    }
}
