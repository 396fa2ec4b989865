/* reduce.cl: the Connection Machine's global reductions (sum, max, min, logical AND and OR of a field,
 * returned to the host) and histograms, global or per tile: the local histograms of the paper's noise
 * estimation ("Edge detection", Noise Estimation).
 *
 * Defines: T (element type), OP (OP_PLUS|OP_MAX|OP_MIN|OP_AND|OP_OR), ACC (accumulator type),
 * T_IS_FLOAT. Results are deterministic: every reduction runs in a fixed order (a serial pass per chunk,
 * then a serial pass over the chunk results), and histograms count with integer atomics only.
 */
#include "vmcl.h"

#if OP == OP_PLUS
#define IDENTITY ((ACC)0)
#define COMBINE(a, b) ((a) + (b))
#elif OP == OP_MAX
#define IDENTITY ((ACC)T_LOWEST)
#define COMBINE(a, b) max((a), (b))
#elif OP == OP_MIN
#define IDENTITY ((ACC)T_HIGHEST)
#define COMBINE(a, b) min((a), (b))
#elif OP == OP_AND
#define IDENTITY ((ACC)1)
#define COMBINE(a, b) ((ACC)((a) && (b)))
#elif OP == OP_OR
#define IDENTITY ((ACC)0)
#define COMBINE(a, b) ((ACC)((a) || (b)))
#endif

/* Float sums use Kahan's compensated summation, so the result stays within a few ulps of the exact sum
 * however many elements there are; everything else accumulates directly. */
#define KAHAN (OP == OP_PLUS && T_IS_FLOAT)

/* Reduce elements [begin, end) of x, writing the chunk result (and its compensation) to partial[g]. */
__kernel void reduce_chunks(__global const T *x, __global ACC *partial, __global ACC *compensation,
                            long n, long chunk)
{
    long g = get_global_id(0);
    if (g * chunk >= n) return;
    long begin = g * chunk, end = min(begin + chunk, n);
    ACC acc = IDENTITY;
#if KAHAN
    ACC c = 0;
    for (long i = begin; i < end; i++) {
        ACC y = (ACC)x[i] - c;
        ACC t = acc + y;
        c = (t - acc) - y;
        acc = t;
    }
    compensation[g] = c;
#else
    for (long i = begin; i < end; i++) acc = COMBINE(acc, (ACC)x[i]);
#endif
    partial[g] = acc;
}

/* One work-item folds the chunk results in order. */
__kernel void reduce_partials(__global const ACC *partial, __global const ACC *compensation,
                              __global ACC *out, long count)
{
    if (get_global_id(0) != 0) return;
    ACC acc = IDENTITY;
#if KAHAN
    ACC c = 0;
    for (long g = 0; g < count; g++) {
        ACC y = (partial[g] - compensation[g]) - c;
        ACC t = acc + y;
        c = (t - acc) - y;
        acc = t;
    }
#else
    for (long g = 0; g < count; g++) acc = COMBINE(acc, partial[g]);
#endif
    out[0] = acc;
}

/* Histogram of tile g of a (H, W) field cut into tiles of th x tw (edge tiles may be smaller): bin
 * floor((v - lo) * scale) for lo <= v <= hi (v == hi and rounding up to `bins` both go to the last
 * bin); values outside [lo, hi] and NaN are not counted. The work-group counts into local memory, then
 * writes its tile's row of `out` (per-tile mode) or adds it into the one histogram (accumulate). */
__kernel void histogram_tiles(__global const T *x, __global int *out, __local int *counts,
                              long W, long H, long th, long tw, long tiles_x,
                              float lo, float hi, float scale, int bins, int accumulate)
{
    long g = get_group_id(0);
    int lid = get_local_id(0), size = get_local_size(0);
    for (int b = lid; b < bins; b += size) counts[b] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    long y0 = (g / tiles_x) * th, x0 = (g % tiles_x) * tw;
    long rows = min(th, H - y0), cols = min(tw, W - x0);
    for (long k = lid; k < rows * cols; k += size) {
        float v = (float)x[(y0 + k / cols) * W + x0 + k % cols];
        if (v >= lo && v <= hi) {
            int b = (int)floor((v - lo) * scale);
            atomic_inc(&counts[min(b, bins - 1)]);
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int b = lid; b < bins; b += size) {
        if (accumulate) {
            if (counts[b]) atomic_add(&out[b], counts[b]);
        } else {
            out[g * bins + b] = counts[b];
        }
    }
}
